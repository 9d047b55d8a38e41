// `stairguide bench WHAT ...`: dispatches to the benchmarks registered with SG_BENCH.
#include <cstdio>
#include <string>

#include "cli/command.hpp"

namespace stairguide::cli {

std::vector<Command>& bench_registry() {
  static std::vector<Command> r;
  return r;
}

namespace {

int bench(Context& ctx) {
  if (ctx.args.empty() || ctx.args[0].rfind("--", 0) == 0) {
    std::string names;
    for (const auto& b : bench_registry())
      names += std::string("\n  stairguide bench ") + b.usage + "  " + b.summary;
    throw UsageError("which benchmark?" + names);
  }
  const std::string what = ctx.args[0];
  for (const auto& b : bench_registry()) {
    if (what == b.name) {
      ctx.args.erase(ctx.args.begin());
      return b.fn(ctx);
    }
  }
  throw UsageError("unknown benchmark '" + what + "'");
}

}  // namespace

SG_COMMAND("bench", "bench WHAT [--json] ...",
           "benchmarks: medians and ratios against a reference in the same run", bench);

}  // namespace stairguide::cli
