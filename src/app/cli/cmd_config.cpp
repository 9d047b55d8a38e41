// check-config / dump-config commands.
#include <cstdio>

#include "cli/command.hpp"
#include "stairguide/config/config_loader.hpp"

namespace stairguide::cli {
namespace {

int check_config(Context& ctx) {
  const auto pos = ctx.positionals(0, 1);
  const std::string path = pos.empty() ? ctx.config_path : pos[0];
  if (path.empty()) throw UsageError("no config file given and no default found");
  ConfigLoadReport report;
  try {
    load_config(path, &report);
  } catch (const ConfigError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
  }
  std::printf("%s: ok", path.c_str());
  if (!report.missing_keys.empty())
    std::printf(" (%zu keys not given, defaults used)", report.missing_keys.size());
  std::printf("\n");
  return 0;
}

int dump_config(Context& ctx) {
  const bool defaults = ctx.flag("--defaults");
  ctx.positionals(0, 0);
  std::fputs(dump_config_yaml(defaults ? PipelineConfig{} : ctx.config).c_str(), stdout);
  return 0;
}

}  // namespace

SG_COMMAND("check-config", "check-config [FILE]", "validate a config file; exit 0 or name the problem",
           check_config);
SG_COMMAND("dump-config", "dump-config [--defaults]", "print the effective config as commented YAML",
           dump_config);

}  // namespace stairguide::cli
