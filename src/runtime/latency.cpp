#include "stairguide/runtime/latency.hpp"

#include <algorithm>
#include <cmath>

namespace stairguide::runtime {

void LatencyHistogram::add(double ms) {
  if (!(ms >= 0.0)) ms = 0.0;  // also NaN
  const double b = std::floor(ms / kBinMs);
  const int bin = b >= kBins ? kBins : static_cast<int>(b);
  ++bins_[static_cast<std::size_t>(bin)];
  ++count_;
  sum_ += ms;
  max_ = std::max(max_, ms);
}

void LatencyHistogram::clear() {
  std::fill(bins_.begin(), bins_.end(), 0u);
  count_ = 0;
  sum_ = 0.0;
  max_ = 0.0;
}

double LatencyHistogram::percentile(double p) const {
  if (count_ == 0) return 0.0;
  p = std::clamp(p, 0.0, 100.0);
  // Nearest-rank: the smallest value with at least p% of the samples at or below it.
  const auto rank = std::max<std::uint64_t>(
      1, static_cast<std::uint64_t>(std::ceil(p / 100.0 * static_cast<double>(count_))));
  std::uint64_t seen = 0;
  for (int i = 0; i <= kBins; ++i) {
    seen += bins_[static_cast<std::size_t>(i)];
    if (seen >= rank) return i == kBins ? max_ : std::min(max_, (i + 1) * kBinMs);
  }
  return max_;
}

}  // namespace stairguide::runtime
