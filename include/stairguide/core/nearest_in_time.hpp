#pragma once
// The entry of a time-sorted list nearest a moment: labels and ground-truth poses are matched to
// frames by their timestamps (datasets, replay, eval-odometry).
#include <algorithm>
#include <cmath>
#include <vector>

namespace stairguide {

/// The element of `sorted` (ascending by its `timestamp`, seconds) nearest `t`, or null when the
/// list is empty or the nearest is more than `max_gap` seconds away.
template <class Timed>
const Timed* nearest_in_time(const std::vector<Timed>& sorted, double t, double max_gap) {
  auto it = std::lower_bound(sorted.begin(), sorted.end(), t,
                             [](const Timed& a, double v) { return a.timestamp < v; });
  const Timed* best = it != sorted.end() ? &*it : nullptr;
  if (it != sorted.begin() && (!best || std::abs((it - 1)->timestamp - t) < std::abs(best->timestamp - t)))
    best = &*(it - 1);
  return best && std::abs(best->timestamp - t) <= max_gap ? best : nullptr;
}

}  // namespace stairguide
