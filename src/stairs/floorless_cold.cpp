// The floorless route, phase "cold start" (floorless.hpp, "Cold start"): nothing remembered, so
// either the user's floor is seen outside the stack and anchors it, or the first seen level is
// decided to be the floor, a step, or unknown.
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "floorless_internal.hpp"
#include "stairguide/stairs/floorless.hpp"

namespace stairguide {

using namespace floorless;

void FloorlessStairs::run_cold(const SceneResult& scene, const CameraIntrinsics* K, int dir, int n,
                               const StackFit& fit, StairResult& out) {
  const float level0 = fit.level0, riser = fit.riser;
  // Cold start, but the floor the user stands on may be in view outside the stack: perception
  // refused it (the top of a descent: the treads below look nearer the user's feet; a floor strip
  // that might be a tread), and the stack does not reach it because the first steps are hidden
  // (self-occluded below a descending edge, under the view at the foot of a climb). A level a
  // rig's height (0.4-1.9 m) below the camera and a whole number of risers from the first seen level
  // places the steps from the feet as a remembered height would. Without it, the checks below
  // settle whether the first seen level is the floor; otherwise its step number is unknown and the
  // stack is reported without_floor or refused.
  // Split at the landing the user stands on, the flight's first level is that landing: the other
  // flight's levels, a riser or more from it, are no floor of the user's.
  if (trace_.landing_split) {
    model(scene, K, dir, 0, level0, out);
    if (!model_on_floor_level(scene, K, dir, out)) model(scene, K, dir, 0, level0, out);
    return;
  }
  const float seen = seen_floor_height(dir, riser);
  if (seen > 0.f) {
    trace_.floor_seen = true;
    run_anchored(scene, K, dir, riser, level0, seen, out);
    return;
  }
  // Two levels seen cold with nothing placing the user's feet: a curb or a single step whose floor
  // perception refused because it could not tell which of the two the user stands on. The one
  // pair's direction compares where the levels come nearest the user, and on an edge seen
  // obliquely that is where the view's border cuts them: a curb going up, seen at 21 deg with the
  // sidewalk filling the view and the street only in a corner, came out as stairs going down
  // (held-out seed 1 curb #4). Going down, the face between the two levels turns away from the
  // user; an upright face seen between their heights says the step rises away from the user, and
  // a direction the scene contradicts is not reported.
  if (n == 2 && dir < 0 &&
      riser_between(scene, nodes_[static_cast<std::size_t>(chain_.back())].height,
                    nodes_[static_cast<std::size_t>(chain_.front())].height)) {
    trace_.riser_against = true;
    out.detected = false;
    out.verdict = StairVerdict::kNoFloor;  // without it, which way the step goes is not settled
    return;
  }
  model(scene, K, dir, 0, level0, out);
  decide_first_level(scene, K, dir, out);
}

void FloorlessStairs::decide_first_level(const SceneResult& scene, const CameraIntrinsics* K, int dir,
                                         StairResult& out) {
  // Cold start: is the first level seen the first step, or the floor the user stands on (seen, but
  // refused by the floor detector: a level camera, a floor strip at the foot of the steps)? The
  // floor runs to the user's feet, so its near boundary is the image border; a first step whose
  // nosing is in view is no floor. Cut by the border, a tread shows at most its own depth: a level
  // deeper than the tread measured on the others is the floor. Shallower, nothing in one frame
  // tells a floor strip from a tread seen from above unless the camera's height rules one out.
  // Either way a staircase lies ahead in that direction: it is reported `without_floor` (which
  // step is the first, and how far, unknown) rather than withheld (issue 39: a wearer standing at
  // the foot of a flight that fills the view was told nothing).
  if (out.level_data.size() < 2) return;
  {
    const StairLevel& l1 = out.level_data[1];
    const float y = dir > 0 ? 0.f : l1.height;  // the level's height in the stair frame
    trace_.first_near_cut = K && line_cut(*K, out, 1, y, l1.depth_min);
  }
  if (!trace_.first_near_cut) return;
  const float depth = out.level_data[1].depth_max - out.level_data[1].depth_min;
  trace_.first_depth = depth;
  // Seen at a chest camera's pitch (the floor detector's range), the floor the user stands on lies
  // a rig's height below it (the floor detector's rig range, 0.4-1.9 m): a level nearer the camera, or
  // farther, is a step whatever its depth. A camera held level (a hand-held or tripod view) says
  // nothing of its height: there the rule does not apply.
  const float cam_above = -nodes_[static_cast<std::size_t>(chain_[0])].height;
  const bool chest_view = trace_.tilt >= floor_.usual_tilt_min && trace_.tilt <= floor_.usual_tilt_max;
  // Every tread of a flight has the same depth (building codes allow about 1 cm between the
  // deepest and the shallowest), so a level seen deeper than the fitted tread plus the measuring
  // slack is no tread of this flight: it is the floor. From a chest camera the level cut by the
  // bottom border lies within a metre or so of the camera and its depth is measured to a few cm;
  // only from a camera held level, whose lowest rows look far and grazing, is anything shallower
  // than a landing left undecided.
  const float floor_depth = chest_view && out.tread_m > 0.f
                                ? out.tread_m + kFloorDepthSlack
                                : std::max(kLandingDepth, out.tread_m + kFloorDepthSlack);
  const bool deep = depth > floor_depth;
  const bool floor_height = cam_above >= floor_.height_min - det_.same_level_tolerance &&
                            cam_above <= floor_.height_max + det_.same_level_tolerance;
  if (chest_view && !floor_height) return;
  // The other way round: were the level a first tread, the user's floor would lie one riser
  // below it (ascending) or above it (descending); outside the rig range that
  // cannot be the user's floor, so the level is.
  const float tread_cam = cam_above + static_cast<float>(dir) * out.riser_m;
  const bool tread_height = tread_cam >= floor_.height_min - det_.same_level_tolerance &&
                            tread_cam <= floor_.height_max + det_.same_level_tolerance;
  if (!deep && (!chest_view || tread_height)) {
    // Seen from a wearer's rig (its tilt range) the staircase is told, its first step unknown. A
    // camera held level (a hand-held or tripod view, no wearer) keeps the old refusal: its model
    // of a floor strip and open treads came out inconsistent (treads of -39 to 70 cm).
    const bool rig_view = trace_.tilt >= floor_.tilt_min && trace_.tilt <= floor_.tilt_max;
    // Two levels only: taken as the floor and one step, the single-level case would need the real
    // floor (paper 4.1) and say nothing; a person sees a flight's nosings. The stack stays as
    // modelled (the first level a tread), without_floor.
    const int levels = static_cast<int>(chain_.size());
    if (rig_view && levels - 1 < std::max(2, det_.floorless_min_levels)) return;
    // Modelled on the first level as the floor, the origin lies on a true edge whichever it is:
    // the level's far side is riser 1 if it is the floor, riser 2 if it is the first tread. The
    // count is what stays unknown.
    if (rig_view && model_on_floor_level(scene, K, dir, out)) {
      out.without_floor = true;
      return;
    }
    out.detected = false;
    out.verdict = StairVerdict::kNoFirstStep;
    return;
  }
  model_on_floor_level(scene, K, dir, out);
}

bool FloorlessStairs::riser_between(const SceneResult& scene, float h_lo, float h_hi) {
  const Eigen::Vector3f& up = trace_.up;
  const float sin_vert = std::sin(cls_.parallel_threshold);
  for (const PlaneRegion& r : scene.regions) {
    if (r.points.size() < 40 || std::fabs(r.normal.dot(up)) > sin_vert) continue;
    const std::size_t stride = std::max<std::size_t>(1, r.points.size() / 300);
    tmp_.clear();
    for (std::size_t i = 0; i < r.points.size(); i += stride) tmp_.push_back(up.dot(r.points[i]));
    std::sort(tmp_.begin(), tmp_.end());
    // Its height band (10th to 90th percentile) within the pair's, over a third of the riser.
    const float lo = tmp_[tmp_.size() / 10], hi = tmp_[tmp_.size() * 9 / 10];
    if (lo >= h_lo - kRiserBandSlack && hi <= h_hi + kRiserBandSlack && hi - lo >= (h_hi - h_lo) / 3.f)
      return true;
  }
  return false;
}

bool FloorlessStairs::model_on_floor_level(const SceneResult& scene, const CameraIntrinsics* K, int dir,
                                           StairResult& out) {
  trace_.floor_level = true;
  const int n = static_cast<int>(chain_.size());
  if (n - 1 < std::max(2, det_.floorless_min_levels)) {
    // A floor and one level on it: the single-level case needs the real floor (paper 4.1).
    out.detected = false;
    out.verdict = StairVerdict::kNoFloor;
    out.levels = n - 1;
    return false;
  }
  model(scene, K, dir, 1, nodes_[static_cast<std::size_t>(chain_[0])].height, out);
  return true;
}

}  // namespace stairguide
