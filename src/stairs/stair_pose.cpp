// Stair modelling, phase "pose": the stair frame's origin at the centre of the first edge
// (ascending: nosing of tread 1; descending: the floor's edge), then every level expressed in it.
#include <algorithm>
#include <cmath>

#include "stair_modelling_internal.hpp"
#include "stairguide/stairs/stair_modelling.hpp"

namespace stairguide {

using namespace modelling;

StairModelling::StairOrigin StairModelling::place_origin(const StairHypothesis& hyp, int n, int dir,
                                                         const StairFrame& frame, const StairSpan& span,
                                                         const FloorSeen& floor, float near_boundary,
                                                         const StairProfile& profile,
                                                         StairResult& out) const {
  const Eigen::Vector3f &xs = frame.xs, &zs = frame.zs, &up = frame.up;
  const float a_mid = span.a_mid, width = span.width, riser = profile.riser;
  const LineFit& efit = profile.tread;
  const bool floor_edge = floor.edge;
  const StairLevel& fl = out.level_data[0];
  // ---- pose: origin at the centre of the first edge ----
  StairOrigin o;
  float& edge_b = o.edge_b;
  float& plane = o.plane;
  if (dir > 0) {
    const float first = static_cast<float>(hyp.levels[1].index);
    edge_b = efit.ok ? efit.intercept + efit.slope * first : out.level_data[1].edge;
    plane = levels_[1].plane;
  } else {
    if (efit.ok) {
      edge_b = efit.intercept;
    } else if (floor_edge) {
      edge_b = fl.edge;
    } else {
      edge_b = std::isfinite(near_boundary) ? near_boundary : out.level_data[1].depth_min;
      // No floor boundary seen at the drop (its edge out of view, or too thin a strip): the
      // level below is seen from where the edge's shadow ends. From a camera H above the floor,
      // an edge D ahead hides a drop of R up to D * R / H beyond it, so the strip seen from b on
      // says the edge lies at b / (1 + R / H) (b counted from the camera's foot, as edge_b is).
      const float H = -levels_[0].plane;
      if (n == 1 && H > 0.3f && edge_b > 0.f) edge_b /= 1.f + riser / H;
    }
    plane = levels_[0].plane;
  }
  o.origin = xs * a_mid + up * plane + zs * edge_b;
  const Eigen::Vector3f& origin = o.origin;
  out.T_camera_stair.setIdentity();
  out.T_camera_stair.linear().col(0) = xs;
  out.T_camera_stair.linear().col(1) = up;
  out.T_camera_stair.linear().col(2) = zs;
  out.T_camera_stair.translation() = origin;
  out.edge_left = origin + xs * (0.5f * width);
  out.edge_right = origin - xs * (0.5f * width);
  out.width_m = width;
  out.riser_m = riser;
  out.tread_m = (n >= 2 && efit.ok) ? efit.slope : 0.f;
  return o;
}

void StairModelling::express_in_stair_frame(const SceneResult& scene, const StairHypothesis& hyp, int n,
                                            int dir, const StairOrigin& origin, const StairSpan& span,
                                            const FloorSeen& floor, StairResult& out) const {
  const float edge_b = origin.edge_b, a_mid = span.a_mid;
  const bool floor_edge = floor.edge, floor_extent = floor.extent;
  StairLevel& fl = out.level_data[0];
  // ---- per-level output in the stair frame ----
  for (int k = 0; k <= n; ++k) {
    StairLevel& o = out.level_data[static_cast<std::size_t>(k)];
    const LevelSeed& s = hyp.levels[static_cast<std::size_t>(k)];
    o.index = dir * hyp.levels[static_cast<std::size_t>(k)].index;
    o.height = levels_[static_cast<std::size_t>(k)].plane - levels_[0].plane;
    o.regions = s.regions;
    if (k == 0) continue;  // the floor's points stay with perception
    o.edge -= edge_b;
    o.depth_min -= edge_b;
    o.depth_max -= edge_b;
    o.lateral_min -= a_mid;
    o.lateral_max -= a_mid;
    std::size_t total = 0;
    for (int r : s.regions) total += scene.regions[static_cast<std::size_t>(r)].points.size();
    const std::size_t stride = std::max<std::size_t>(1, (total + kOutputPoints - 1) / kOutputPoints);
    for (int r : s.regions) {
      const auto& pts = scene.regions[static_cast<std::size_t>(r)].points;
      for (std::size_t i = 0; i < pts.size(); i += stride) o.points.push_back(pts[i]);
    }
  }
  if (floor_extent) {
    fl.depth_min -= edge_b;
    fl.depth_max -= edge_b;
    fl.lateral_min -= a_mid;
    fl.lateral_max -= a_mid;
  }
  if (floor_edge) {
    fl.edge -= edge_b;
    fl.depth_min -= edge_b;
    fl.depth_max -= edge_b;
    fl.lateral_min -= a_mid;
    fl.lateral_max -= a_mid;
  }
}

}  // namespace stairguide
