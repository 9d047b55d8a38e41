#pragma once
// Timing helpers shared by the benchmark and evaluation commands.

#include <time.h>

#include <algorithm>
#include <chrono>
#include <vector>

namespace stairguide::cli {

/// The q-quantile (0..1) of v, nearest rank; 0 for an empty vector. (Takes a reference and copies
/// by iterators: GCC 12's -Wfree-nonheap-object misfires at -O3 on the by-value copy.)
inline double percentile(const std::vector<double>& values, double q) {
  if (values.empty()) return 0.0;
  std::vector<double> v(values.begin(), values.end());
  std::sort(v.begin(), v.end());
  const std::size_t i = static_cast<std::size_t>(q * static_cast<double>(v.size() - 1) + 0.5);
  return v[std::min(i, v.size() - 1)];
}

/// CPU time of the calling thread, ms: what a stage cost, whatever else the machine was doing.
inline double thread_cpu_ms() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) * 1e3 + static_cast<double>(t.tv_nsec) * 1e-6;
}

/// Wall and thread-CPU milliseconds since construction.
struct Timer {
  std::chrono::steady_clock::time_point w = std::chrono::steady_clock::now();
  double c = thread_cpu_ms();
  double wall() const {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - w).count();
  }
  double cpu() const { return thread_cpu_ms() - c; }
};

}  // namespace stairguide::cli
