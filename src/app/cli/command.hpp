#pragma once
// The `stairguide` command-line tool: each command lives in its own cli/cmd_*.cpp and registers
// itself with SG_COMMAND, so adding a command touches no other file.

#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "stairguide/core/config.hpp"

namespace stairguide::cli {

struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// What a command gets: its arguments (after the command name, --config removed) and the config.
struct Context {
  std::vector<std::string> args;
  PipelineConfig config;
  std::string config_path;  ///< empty when the built-in defaults are used

  /// Removes `--name` from args; true when it was there.
  bool flag(const std::string& name);
  /// Removes `--name VALUE` (or `--name=VALUE`) from args and returns VALUE. Throws UsageError
  /// when the value is missing.
  std::optional<std::string> option(const std::string& name);
  /// Integer option with range check; throws UsageError naming the option on bad input.
  std::optional<long> int_option(const std::string& name, long lo, long hi);
  /// After flags and options are taken: the remaining arguments; throws UsageError on any
  /// leftover "--something" or on a count outside [min_count, max_count].
  std::vector<std::string> positionals(std::size_t min_count, std::size_t max_count);
};

using CommandFn = int (*)(Context&);

struct Command {
  const char* name;
  const char* usage;    ///< "detect INPUT [--json] [--png OUT.png]"
  const char* summary;  ///< one line
  CommandFn fn;
};

std::vector<Command>& registry();

struct Registrar {
  explicit Registrar(const Command& c) { registry().push_back(c); }
};

#define SG_COMMAND_CAT2(a, b) a##b
#define SG_COMMAND_CAT(a, b) SG_COMMAND_CAT2(a, b)
#define SG_COMMAND(name, usage, summary, fn) \
  static const ::stairguide::cli::Registrar SG_COMMAND_CAT(sg_cmd_, __LINE__)({name, usage, summary, fn})

}  // namespace stairguide::cli

namespace stairguide::cli {

/// `stairguide bench WHAT`: each benchmark registers itself like a command.
std::vector<Command>& bench_registry();

struct BenchRegistrar {
  explicit BenchRegistrar(const Command& c) { bench_registry().push_back(c); }
};

#define SG_BENCH(name, usage, summary, fn)                                 \
  static const ::stairguide::cli::BenchRegistrar SG_COMMAND_CAT(sg_bench_, \
                                                                __LINE__)({name, usage, summary, fn})

}  // namespace stairguide::cli
