// The floorless route, phase "anchoring" (floorless.hpp, "Remembered floor" and "At the first
// edge"): the stack placed from the user's feet, a known camera height below the camera.
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "floorless_internal.hpp"
#include "stairguide/stairs/floorless.hpp"

namespace stairguide {

using namespace floorless;

float FloorlessStairs::seen_floor_height(int dir, float riser) const {
  if (chain_.empty() || riser <= 0.f) return 0.f;
  const float h0 = nodes_[static_cast<std::size_t>(chain_[0])].height;
  const float tol = det_.same_level_tolerance;
  const int kmax = 1 + std::max(0, det_.floorless_max_hidden_steps);
  float best = 0.f;
  int best_pixels = 0;
  for (int i : order_) {
    if (std::find(chain_.begin(), chain_.end(), i) != chain_.end()) continue;
    const Node& f = nodes_[static_cast<std::size_t>(i)];
    const float cam_above = -f.height;
    if (cam_above < floor_.height_min - tol || cam_above > floor_.height_max + tol) continue;
    // On the user's side of the flight: below its first level ascending, above it descending.
    const float a0 = static_cast<float>(dir) * (h0 - f.height);
    const int k = static_cast<int>(std::lround(a0 / riser));
    if (k < 1 || k > kmax || std::fabs(a0 - static_cast<float>(k) * riser) > det_.floorless_anchor_tolerance)
      continue;
    if (f.pixels > best_pixels) {
      best_pixels = f.pixels;
      best = cam_above;
    }
  }
  return best;
}

void FloorlessStairs::run_anchored(const SceneResult& scene, const CameraIntrinsics* K, int dir, float riser,
                                   float level0, float camera_height, StairResult& out) {
  // The feet lie `camera_height` below the camera along up (the camera sits at up . p = 0).
  // chain_ is in stair order: chain_[0] is the first level seen from the user.
  trace_.anchored = true;
  const int n = static_cast<int>(chain_.size());
  const float h0 = nodes_[static_cast<std::size_t>(chain_[0])].height;
  const float a0 = static_cast<float>(dir) * (h0 + camera_height);
  trace_.first_offset = a0;
  const int kmax = 1 + std::max(0, det_.floorless_max_hidden_steps);
  const float tol = det_.floorless_anchor_tolerance;
  int k = riser > 0.f ? static_cast<int>(std::lround(a0 / riser)) : -1;
  out.levels = n;
  bool lean = false;
  if (riser > 0.f && std::fabs(a0 - static_cast<float>(k) * riser) > tol) {
    // The remembered height is the camera's over the feet of a user standing upright. Stepping
    // onto the next level, the chest starts moving towards it (up a climb, down a descent) before
    // the foot leaves the floor: by the time the foot reaches the edge it has gone up to half a
    // riser. The first level seen then lies k risers from the feet less that lean: k is the
    // next whole number of risers beyond the tolerance, the lean at most half a riser (plus
    // half the tolerance). A user whose chest has moved that far must stand at the first edge,
    // which the model checks below.
    k = static_cast<int>(std::floor((a0 + tol) / riser)) + 1;
    const float d = static_cast<float>(k) * riser - a0;
    lean = d > tol && d <= 0.5f * (riser + tol);
    if (lean)
      trace_.lean = d;
    else
      k = -1;
  }
  // A chest camera hangs ahead of the feet: with the user at the first edge it is over the first
  // tread, and one more step lies under the view; going down, the levels lie deeper and the view's
  // lowest rays reach them farther ahead, one more again (a high camera sees the first level 3
  // risers up at the foot of a climb, 4 down at the top of a descent). Those are allowed only
  // where the model puts the first edge at the camera's vertical, as for a lean.
  const bool extra_hidden = k > kmax;
  if (k < 0 || k > kmax + 1 + (dir < 0 ? 1 : 0)) {
    // Not a whole number of risers from the feet (or too many steps hidden): a stack of shelves,
    // furniture, or a staircase the remembered height no longer fits. Nothing is reported.
    out.detected = false;
    out.verdict = StairVerdict::kNoFirstStep;
    return;
  }
  trace_.first_index = k;
  if (k == 0) {
    // The floor itself is in the stack (seen, but refused by the floor detector): level 0.
    if (!model_on_floor_level(scene, K, dir, out)) return;
  } else {
    // Level 0 of the fit lies one riser before the first seen level: the floor when k = 1 (the
    // fit's, within the tolerance of the remembered one), the last hidden step otherwise.
    model(scene, K, dir, 0, level0, out);
    if (k >= 2 && out.detected) {
      if (out.tread_m > 0.f) {
        add_hidden_steps(out, dir, k - 1);
      } else {
        // Where the hidden steps' edges lie needs the tread.
        out.detected = false;
        out.verdict = StairVerdict::kNoFirstStep;
      }
    }
  }
  out.without_floor = false;
  if ((lean || extra_hidden) && out.detected) {
    // The chest leans towards the next level only in the last stride before its edge: the first
    // edge must lie that near ahead of the camera's vertical (not behind it: the feet would be on
    // the step). Farther, the stack is not k risers from these feet (shelves, furniture, or a
    // remembered height that no longer fits) and nothing is reported rather than a step off.
    const Eigen::Vector3f zs = out.T_camera_stair.linear().col(2);
    const float ahead = zs.dot(out.T_camera_stair.translation());
    trace_.lean_edge_ahead = ahead;
    if (ahead < -kLeanBehind || ahead > kLeanReach) {
      out.detected = false;
      out.verdict = StairVerdict::kNoFirstStep;
      trace_.first_index = -1;
    }
  }
}

void FloorlessStairs::add_hidden_steps(StairResult& out, int dir, int hidden) {
  // The model's level 0 was step `hidden` and its origin step hidden + 1's edge (ascending) or
  // step hidden's far edge (descending): both move `hidden` treads towards the user and `hidden`
  // risers towards the floor.
  const Eigen::Vector3f ys = out.T_camera_stair.linear().col(1), zs = out.T_camera_stair.linear().col(2);
  const float dz = static_cast<float>(hidden) * out.tread_m, dy = static_cast<float>(hidden) * out.riser_m;
  const Eigen::Vector3f move = -static_cast<float>(dir) * dy * ys - dz * zs;
  out.T_camera_stair.translation() += move;
  out.edge_left += move;
  out.edge_right += move;
  for (std::size_t k = 1; k < out.level_data.size(); ++k) {
    StairLevel& l = out.level_data[k];
    l.edge += dz;
    l.depth_min += dz;
    l.depth_max += dz;
    l.height += static_cast<float>(dir) * dy;
    l.index += dir * hidden;
  }
}

}  // namespace stairguide
