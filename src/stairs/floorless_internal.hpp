#pragma once
// Internal to the floorless route's phases (floorless*.cpp): the constants they share. Not a
// public interface.

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstddef>

namespace stairguide {
namespace floorless {

constexpr int kMinRegionPixels = 100;      // px, smaller regions have too noisy a normal to vote for up
constexpr std::size_t kFitPoints = 500;    // points per region in the fit of the common normal
constexpr float kLandingDepth = 0.6f;      // m, a level deeper than this is a landing or a floor
constexpr float kRiserBandSlack = 0.03f;   // m, a riser's height band may pass its levels' heights by this
constexpr float kMinRise = 0.05f;          // m, a higher level's near boundary this much farther (nearer)
                                           // than the lower one's says ascending (descending)
constexpr float kFloorDepthSlack = 0.08f;  // m, a level cut by the image border and seen deeper than
                                           // the tread by this is no tread (nosing, edge noise)
// With the chest moved towards the next level beyond the anchor tolerance (run_anchored), the user
// stands at the first edge: it lies at most kLeanReach ahead of the camera's vertical (the lean
// starts within the last stride before the edge: half a tread in the walks, plus the edge's noise)
// and at most kLeanBehind behind it (a chest camera hangs 10-15 cm ahead of the feet, more when
// leaning; the feet are still before the edge).
constexpr float kLeanReach = 0.35f;   // m
constexpr float kLeanBehind = 0.20f;  // m

inline float clampf(float x, float lo, float hi) { return std::min(hi, std::max(lo, x)); }

/// Pitch below horizontal and roll of a camera whose "up" is `u` (camera frame: x right, y down,
/// z forward).
inline void tilt_roll(const Eigen::Vector3f& u, float& tilt, float& roll) {
  tilt = std::asin(clampf(-u.z(), -1.f, 1.f));
  roll = std::atan2(u.x(), -u.y());
}

}  // namespace floorless
}  // namespace stairguide
