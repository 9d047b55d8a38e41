// stairguide: the command-line tool. A thin main: global options, then one registered command.
#include <algorithm>
#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

#include "cli/command.hpp"
#include "stairguide/config/config_loader.hpp"

namespace stairguide::cli {

std::vector<Command>& registry() {
  static std::vector<Command> r;
  return r;
}

bool Context::flag(const std::string& name) {
  auto it = std::find(args.begin(), args.end(), name);
  if (it == args.end()) return false;
  args.erase(it);
  return true;
}

std::optional<std::string> Context::option(const std::string& name) {
  for (std::size_t i = 0; i < args.size(); ++i) {
    if (args[i] == name) {
      if (i + 1 >= args.size()) throw UsageError(name + " needs a value");
      std::string v = args[i + 1];
      args.erase(args.begin() + static_cast<long>(i), args.begin() + static_cast<long>(i) + 2);
      return v;
    }
    if (args[i].rfind(name + "=", 0) == 0) {
      std::string v = args[i].substr(name.size() + 1);
      args.erase(args.begin() + static_cast<long>(i));
      return v;
    }
  }
  return std::nullopt;
}

std::optional<long> Context::int_option(const std::string& name, long lo, long hi) {
  auto v = option(name);
  if (!v) return std::nullopt;
  try {
    std::size_t used = 0;
    long n = std::stol(*v, &used);
    if (used != v->size()) throw std::invalid_argument(*v);
    if (n < lo || n > hi)
      throw UsageError(name + " " + *v + " is out of range [" + std::to_string(lo) + ", " +
                       std::to_string(hi) + "]");
    return n;
  } catch (const std::logic_error&) {
    throw UsageError(name + " expects a whole number, got '" + *v + "'");
  }
}

std::vector<std::string> Context::positionals(std::size_t min_count, std::size_t max_count) {
  for (const auto& a : args)
    if (a.size() > 2 && a.rfind("--", 0) == 0) throw UsageError("unknown option " + a);
  if (args.size() < min_count) throw UsageError("missing argument");
  if (args.size() > max_count) throw UsageError("unexpected argument '" + args[max_count] + "'");
  return args;
}

}  // namespace stairguide::cli

namespace {

void print_help(std::FILE* out) {
  std::fprintf(out,
               "usage: stairguide [--config FILE] COMMAND [ARGS]\n\n"
               "Stair detection and traversal aid: tools around the stairguided daemon.\n\ncommands:\n");
  auto cmds = stairguide::cli::registry();
  std::sort(cmds.begin(), cmds.end(),
            [](const auto& a, const auto& b) { return std::string(a.name) < b.name; });
  for (const auto& c : cmds) std::fprintf(out, "  %-58s %s\n", c.usage, c.summary);
  std::fprintf(out,
               "\nEvery command takes --config FILE (default: $STAIRGUIDE_CONFIG, then\n"
               "/etc/stairguide/stairguide.yaml, then the source tree's config/stairguide.yaml).\n");
}

/// False for a command that is given its file (check-config FILE) or needs no config (synth
/// --list, dump-config --defaults): the default config ($STAIRGUIDE_CONFIG, ...) is not loaded
/// for it, so a broken one cannot stop it. A file named with --config is always loaded.
bool needs_default_config(const std::string& name, const std::vector<std::string>& args) {
  auto has = [&](const char* a) { return std::find(args.begin(), args.end(), a) != args.end(); };
  if (name == "check-config")
    return std::none_of(args.begin(), args.end(), [](const std::string& a) { return a.rfind("--", 0) != 0; });
  if (name == "synth") return !has("--list");
  if (name == "dump-config") return !has("--defaults");
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace stairguide;
  cli::Context ctx;
  for (int i = 1; i < argc; ++i) ctx.args.emplace_back(argv[i]);
  try {
    auto cfg = ctx.option("--config");
    if (ctx.args.empty() || ctx.args[0] == "help" || ctx.args[0] == "--help" || ctx.args[0] == "-h") {
      print_help(stdout);
      return ctx.args.empty() ? 2 : 0;
    }
    const std::string name = ctx.args[0];
    ctx.args.erase(ctx.args.begin());
    const cli::Command* cmd = nullptr;
    for (const auto& c : cli::registry())
      if (name == c.name) cmd = &c;
    if (!cmd) {
      std::fprintf(stderr, "stairguide: unknown command '%s' (see 'stairguide help')\n", name.c_str());
      return 2;
    }
    if (ctx.flag("--help") || ctx.flag("-h")) {
      std::printf("usage: stairguide %s\n%s\n", cmd->usage, cmd->summary);
      return 0;
    }
    if (cfg && cfg->empty()) throw cli::UsageError("--config needs a file name, got an empty one");
    ctx.config_path = cfg ? *cfg : needs_default_config(name, ctx.args) ? default_config_path() : "";
    // doctor loads the config itself: a broken one is the first thing it reports, not a reason to stop.
    if (!ctx.config_path.empty() && name != "doctor") ctx.config = load_config(ctx.config_path);
    try {
      return cmd->fn(ctx);
    } catch (const cli::UsageError& e) {
      std::fprintf(stderr, "stairguide %s: %s\nusage: stairguide %s\n", cmd->name, e.what(), cmd->usage);
      return 2;
    }
  } catch (const cli::UsageError& e) {
    std::fprintf(stderr, "stairguide: %s\n", e.what());
    return 2;
  } catch (const ConfigError& e) {
    std::fprintf(stderr, "stairguide: config error: %s\n", e.what());
    return 3;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "stairguide: error: %s\n", e.what());
    return 1;
  }
}
