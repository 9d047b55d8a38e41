// Stair modelling, the decisions: is the "floor" the user's, and is what was modelled a single step,
// a curb, an obstacle or a flight? The physical checks and the building code's description live
// in stair_checks.cpp.
#include <algorithm>
#include <cmath>

#include "stair_modelling_internal.hpp"
#include "stairguide/stairs/stair_checks.hpp"
#include "stairguide/stairs/stair_modelling.hpp"

namespace stairguide {

using namespace modelling;

bool StairModelling::floor_doubtful(const SceneResult& scene, const StairHypothesis& hyp, int n, int dir,
                                    const StairFrame& frame, const StairSpan& span, const FloorSeen& floor,
                                    float riser, float edge_b, StairResult& out) const {
  const Eigen::Vector3f &xs = frame.xs, &zs = frame.zs, &up = frame.up;
  const float a_mid = span.a_mid;
  const bool floor_edge = floor.edge, floor_extent = floor.extent;
  const StairLevel& fl = out.level_data[0];
  // ---- is the floor the one the user stands on? ----
  // Perception takes the nearest large plane for the floor; right in front of a staircase that can
  // be the first tread, and every height is then one riser off. A "floor" reaching less than a
  // landing in front of the steps is suspect when a level one riser below it is in view, or when
  // it does not run to the bottom of the image (something lies between it and the user's feet).
  if (dir > 0 && floor_extent && -fl.depth_min < kShallowFloor) {
    bool doubtful = false;
    const float cos_par = std::cos(cls_.parallel_threshold);
    for (const PlaneRegion& r : scene.regions) {
      if (r.cls != RegionClass::kStepCandidate && r.cls != RegionClass::kObstacle) continue;
      if (std::fabs(r.normal.dot(up)) < cos_par || r.pixel_count < kDoubtfulPixels) continue;
      if (std::fabs(up.dot(r.centroid) - levels_[0].plane + riser) < det_.same_level_tolerance)
        doubtful = true;
    }
    if (K_ && !doubtful) {
      const Eigen::Vector3f p = xs * a_mid + up * levels_[0].plane + zs * (edge_b + fl.depth_min);
      const float margin = 0.04f * static_cast<float>(K_->height);
      if (p.z() > 0.05f && K_->fy * p.y() / p.z() + K_->cy < static_cast<float>(K_->height) - margin)
        doubtful = true;
    }
    if (doubtful) {
      out.kind = n >= 2 ? StairKind::kAscending : StairKind::kSingleStep;
      out.verdict = StairVerdict::kFloorDoubtful;
      return true;
    }
  }
  // Descending, the mirror case: perception refused the user's own floor (the first tread below
  // it lies nearer the user) and took that tread for the floor. The flight then comes out one step
  // short, its first edge a tread too far: a step the user does not expect. The "floor" is a strip
  // seen less deep than a landing before the drop, and the real floor lies one riser above it,
  // larger than it and reaching the bottom of the view beside it. A tracked floor was verified on
  // the frames before and is not doubted.
  if (dir < 0 && floor_edge && K_ && !scene.floor_tracked && fl.edge - fl.depth_min < kShallowFloor) {
    int floor_px = 0;
    for (int r : hyp.levels[0].regions) floor_px += scene.regions[static_cast<std::size_t>(r)].pixel_count;
    const float cos_par = std::cos(cls_.parallel_threshold);
    const int bottom = K_->height - static_cast<int>(0.02f * static_cast<float>(K_->height));
    for (const PlaneRegion& r : scene.regions) {
      if (r.cls != RegionClass::kStepCandidate && r.cls != RegionClass::kObstacle) continue;
      if (std::fabs(r.normal.dot(up)) < cos_par || r.pixel_count < std::max(kDoubtfulPixels, floor_px))
        continue;
      if (std::fabs(up.dot(r.centroid) - levels_[0].plane - riser) >= det_.same_level_tolerance) continue;
      int lowest = -1;
      for (int px : r.pixels) lowest = std::max(lowest, px / K_->width);
      if (lowest >= bottom) {
        out.kind = StairKind::kDescending;
        out.verdict = StairVerdict::kFloorDoubtful;
        return true;
      }
    }
  }
  return false;
}

bool StairModelling::far_side_out_of_view(const StairFrame& frame, float a_mid, float edge_b,
                                          const StairLevel& o) const {
  if (!K_) return false;
  const Eigen::Vector3f &xs = frame.xs, &zs = frame.zs, &up = frame.up;
  const Eigen::Vector3f p = xs * (a_mid + 0.5f * (o.lateral_min + o.lateral_max)) + up * levels_[1].plane +
                            zs * (edge_b + o.depth_max);
  const float margin = 0.02f * static_cast<float>(std::max(K_->width, K_->height));
  const float u = K_->fx * p.x() / p.z() + K_->cx, v = K_->fy * p.y() / p.z() + K_->cy;
  return p.z() < 0.05f || u < margin || v < margin || u > static_cast<float>(K_->width) - margin ||
         v > static_cast<float>(K_->height) - margin;
}

bool StairModelling::strip_at_floor_edge_shadow(float riser, const StairLevel& o,
                                                const StairResult& out) const {
  const Eigen::Vector3f cam = out.T_camera_stair.inverse().translation();  // camera in S
  const float H = cam.y(), D = -cam.z();
  if (H > 0.3f && D > 0.f) {
    const float shadow = D * riser / H;
    // Slack: the edge and the strip's near boundary are each measured to a few cm, worse far.
    const float slack = 0.04f + 0.01f * D * D;
    return std::fabs(o.depth_min - shadow) < slack;
  }
  return false;
}

bool StairModelling::surface_above(const SceneResult& scene, const StairHypothesis& hyp,
                                   const StairFrame& frame, float a_mid, float edge_b,
                                   const StairLevel& o) const {
  const Eigen::Vector3f &xs = frame.xs, &zs = frame.zs, &up = frame.up;
  const float cos_par = std::cos(cls_.parallel_threshold);
  const auto& level_regions = hyp.levels[1].regions;
  for (std::size_t i = 0; i < scene.regions.size(); ++i) {
    const PlaneRegion& r = scene.regions[i];
    if (r.cls != RegionClass::kStepCandidate && r.cls != RegionClass::kObstacle) continue;
    if (std::fabs(r.normal.dot(up)) < cos_par) continue;
    if (std::find(level_regions.begin(), level_regions.end(), static_cast<int>(i)) != level_regions.end())
      continue;
    const float above = up.dot(r.centroid) - levels_[1].plane;
    if (above < 0.05f || above > 2.0f) continue;
    const float a = xs.dot(r.centroid) - a_mid, b = zs.dot(r.centroid) - edge_b;
    if (a > o.lateral_min + 0.1f && a < o.lateral_max - 0.1f && b > o.depth_min + 0.1f &&
        b < o.depth_max - 0.1f) {
      return true;
    }
  }
  return false;
}

void StairModelling::decide_single_level(const SceneResult& scene, const StairHypothesis& hyp, int dir,
                                         const StairFrame& frame, const StairSpan& span,
                                         const FloorSeen& floor, float riser, const StairOrigin& pose,
                                         StairResult& out) const {
  const Eigen::Vector3f &xs = frame.xs, &zs = frame.zs, &up = frame.up;
  const float a_mid = span.a_mid, width = span.width;
  const bool* seen = span.seen;
  const bool floor_edge = floor.edge;
  const float edge_b = pose.edge_b;
  const Eigen::Vector3f& origin = pose.origin;
  const float tol = cfg_.dimension_tolerance;
  // One level (paper 4.1, last paragraph): a step or curb by the building code's riser, and by
  // size: too small is an obstacle (a box, a low platform), very deep is another floor level.
  const StairLevel& o = out.level_data[1];
  const float depth = o.depth_max - o.depth_min;
  const int cut = (seen[0] ? 0 : 1) + (seen[1] ? 0 : 1);
  // Does the level run out of the image at its far side (its depth then only a lower bound)?
  const bool far_cut = far_side_out_of_view(frame, a_mid, edge_b, o);
  // Another floor level (a curb) is deeper than a step platform, or runs out of view on both
  // sides and at the far side (seen shallower than a step platform, only when wider than any
  // furniture board); a platform whose far edge is seen, or a narrower one running out of view,
  // is a single step.
  const bool shallow = depth < det_.single_min_depth - tol;
  const bool other_floor = cut == 2 && far_cut && (!shallow || width >= kOtherFloorWidth);
  out.kind =
      (dir < 0 || depth >= det_.curb_min_depth || other_floor) ? StairKind::kCurb : StairKind::kSingleStep;
  const float min_width = det_.single_min_width;
  // A level below the floor is hidden behind the floor's edge up to the edge's shadow: from the
  // camera (height H above the floor, D in front of the edge) a drop of R is seen from D * R / H
  // beyond the edge on. A far descending flight shows only that strip of its first tread, so
  // its seen depth says nothing; a strip that starts right at the shadow of the floor's edge is
  // a drop, however shallow.
  const bool shadowed_drop = dir < 0 && floor_edge && strip_at_floor_edge_shadow(riser, o, out);
  // Seen shallower than a step platform: an obstacle, unless it runs out of view at the far side
  // (its depth seen is then only where the view ends: a platform as wide as a step that goes on
  // beyond the view is one to step onto, whatever lies past it), or is the strip of a drop seen
  // past the floor's edge.
  const bool too_small = width < min_width - tol || (shallow && !far_cut && !shadowed_drop);
  if (too_small || (shallow && !shadowed_drop && dir > 0 &&
                    boxed_in(scene, xs, up, zs, a_mid, edge_b, o, levels_[1].plane))) {
    out.verdict = StairVerdict::kObstacle;
    return;
  }
  // A horizontal surface above the level, within its footprint, makes it furniture (a shelf
  // board, a seat under a table top), not a step one walks onto.
  if (surface_above(scene, hyp, frame, a_mid, edge_b, o)) {
    out.verdict = StairVerdict::kObstacle;
    return;
  }
  // A single level's rise: the curb's lowest (a threshold is no curb), up to what a leg climbs.
  if (riser < det_.curb_height_min - tol || riser > WalkableLimits{}.riser_max + tol) {
    out.verdict = StairVerdict::kRiserOutOfRange;
    return;
  }
  StairDimensions dims;
  dims.riser = riser;
  dims.width = width;
  dims.width_complete = out.width_complete;
  dims.range = origin.norm();
  out.code_notes = describe_against_code(dims, false, cfg_);
  out.verdict = StairVerdict::kDetected;
  out.detected = true;
}

void StairModelling::decide_flight(int dir, const StairSpan& span, const StairProfile& profile,
                                   const StairOrigin& o, StairResult& out) const {
  const float riser = profile.riser, width = span.width;
  const bool edge_consistent = profile.edge_consistent;
  const Eigen::Vector3f& origin = o.origin;
  const float tol = cfg_.dimension_tolerance;
  out.kind = dir > 0 ? StairKind::kAscending : StairKind::kDescending;
  // Physical evidence only silences a flight (stair_checks.hpp); the building code describes it.
  StairDimensions dims;
  dims.riser = riser;
  dims.tread = out.tread_m;
  dims.tread_known = true;
  dims.width = width;
  dims.width_complete = out.width_complete;
  dims.range = origin.norm();
  out.verdict = check_walkable(dims, tol, cfg_.tread_tolerance_per_m2);
  if (out.verdict == StairVerdict::kDetected && !edge_consistent)
    out.verdict = StairVerdict::kInconsistentEdges;
  out.code_notes = describe_against_code(dims, true, cfg_);
  out.detected = out.verdict == StairVerdict::kDetected;
}

bool StairModelling::boxed_in(const SceneResult& scene, const Eigen::Vector3f& xs, const Eigen::Vector3f& up,
                              const Eigen::Vector3f& zs, float a_mid, float edge_b, const StairLevel& o,
                              float plane) const {
  // A board with a side panel rising above it (a shelf's or a cabinet's bottom board): a vertical
  // plane facing along the edge at a lateral end of the level, over its depth, reaching above its
  // surface. One panel is enough: the other is often hidden behind the board or out of view. (A
  // step between walls looks the same; this is only asked of a level seen too shallow for a step
  // platform, which was an obstacle anyway before its far side was taken as running out of view.)
  // Seen far away as a strip under the image top, the panel's upper part is out of view: a panel
  // at a lateral end that faces the level's middle (its inner face: a platform's own side faces
  // outwards) bounds the level whatever its height seen, and so does the front edge of a panel, a
  // narrow upright facing the user across the level's end and rising above it. Such a strip may
  // still be a step between walls: it is only "not yet sure", the user comes nearer. Both stand
  // flush with the level's front (a wall beside a flight runs on before it, a post stands behind
  // the nosing): a flight's first tread seen alone between walls stays a step.
  constexpr float kEndSlack = 0.10f;   // m, a panel this near the level's lateral end bounds it
  constexpr float kPanelRise = 0.05f;  // m, a panel reaching this far above the level is furniture
  constexpr float kPostWidth = 0.15f;  // m, an upright facing the user this narrow is a panel's edge
  constexpr float kPostSlack = 0.03f;  // m, slack on a panel being flush with the level's front or end
  const float sin_vert = std::sin(cls_.parallel_threshold), cos_side = std::cos(cls_.parallel_threshold);
  const float cos_diag = std::sqrt(0.5f);  // faces more along the edge than towards the user
  for (const PlaneRegion& r : scene.regions) {
    if (r.points.size() < 20 || std::fabs(r.normal.dot(up)) > sin_vert) continue;
    const float nx = r.normal.dot(xs), nz = r.normal.dot(zs);
    const bool side = std::fabs(nx) >= cos_diag, front = std::fabs(nz) >= cos_side;
    if (!side && !front) continue;
    float top = -1e9f, b_lo = 1e9f, b_hi = -1e9f, a_lo = 1e9f, a_hi = -1e9f;
    const std::size_t stride = std::max<std::size_t>(1, r.points.size() / 200);
    for (std::size_t i = 0; i < r.points.size(); i += stride) {
      top = std::max(top, up.dot(r.points[i]) - plane);
      const float b = zs.dot(r.points[i]) - edge_b, a = xs.dot(r.points[i]) - a_mid;
      b_lo = std::min(b_lo, b);
      b_hi = std::max(b_hi, b);
      a_lo = std::min(a_lo, a);
      a_hi = std::max(a_hi, a);
    }
    if (side) {
      const float a = xs.dot(r.centroid) - a_mid;
      const bool at_min = std::fabs(a - o.lateral_min) < kEndSlack,
                 at_max = std::fabs(a - o.lateral_max) < kEndSlack;
      if (!at_min && !at_max) continue;
      if (b_hi < o.depth_min || b_lo > o.depth_max) continue;
      // Facing the level's middle: at the x_S-high end the normal points to -x_S, and vice versa;
      // and flush with the level's front, as a shelf's side panel is with its bottom board (a wall
      // beside a flight whose first tread alone is in view runs on before the step).
      const bool inward = ((at_max && nx < 0.f) || (at_min && nx > 0.f)) && b_lo >= o.depth_min - kPostSlack;
      if ((std::fabs(nx) >= cos_side && top >= kPanelRise) || inward) return true;
    } else {
      if (a_hi - a_lo > kPostWidth || top < kPanelRise) continue;
      // At the level's front, as a panel's edge is flush with its board (a handrail post stands
      // on the tread, behind its nosing).
      if (std::fabs(b_lo - o.depth_min) > kPostSlack) continue;
      // Across the level's end, reaching over it (the board's end lies behind the panel's edge):
      // a wall's end or a post beside the level, wholly outside it, does not bound it.
      const bool at_max = a_lo < o.lateral_max && a_hi >= o.lateral_max - kPostSlack;
      const bool at_min = a_hi > o.lateral_min && a_lo <= o.lateral_min + kPostSlack;
      if (at_min || at_max) return true;
    }
  }
  return false;
}

}  // namespace stairguide
