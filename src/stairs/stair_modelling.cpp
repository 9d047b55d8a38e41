// Stair modelling (stair_modelling.hpp): the driver over its phases. Each phase lives in its own
// file: stair_axes.cpp, stair_levels.cpp, stair_extents.cpp, stair_profile.cpp, stair_pose.cpp,
// stair_decision.cpp (with stair_checks.cpp), and the shared 2D geometry in stair_geometry.cpp.
#include "stairguide/stairs/stair_modelling.hpp"

#include <algorithm>
#include <cmath>

namespace stairguide {

StairModelling::StairModelling(const ClassificationConfig& classification,
                               const StairDetectionConfig& detection, const StairModellingConfig& config)
    : cls_(classification), det_(detection), cfg_(config) {}

void StairModelling::reset_result(const StairHypothesis& hyp, int n, StairResult& out) const {
  out.detected = false;
  out.verdict = StairVerdict::kNoFirstStep;
  out.kind = StairKind::kNone;
  out.levels = n;
  out.riser_m = out.tread_m = out.width_m = 0.f;
  out.T_camera_stair = Pose::Identity();
  out.edge_left.setZero();
  out.edge_right.setZero();
  out.method = StairAxesMethod::kNone;
  out.width_complete = false;
  out.candidates = hyp.candidates;
  out.rejected_candidates = hyp.rejected;
  out.level_data.resize(static_cast<std::size_t>(std::max(n, 0) + 1));
  for (auto& l : out.level_data) {
    l.regions.clear();
    l.points.clear();
    l.index = 0;
    l.height = l.edge = l.lateral_min = l.lateral_max = l.depth_min = l.depth_max = 0.f;
  }
}

void StairModelling::run(const SceneResult& scene, const StairHypothesis& hyp, StairResult& out,
                         const CameraIntrinsics* K) {
  K_ = (K && K->valid()) ? K : nullptr;
  const int n = hyp.step_levels();
  const int dir = hyp.direction;
  reset_result(hyp, n, out);
  if (n < 1 || dir == 0) return;

  // Axes: the vertical and the horizontal basis; levels in the horizontal plane.
  const Eigen::Matrix3f R = scene.T_floor_camera.linear();
  const Eigen::Vector3f up0 = R.row(1).transpose();
  StairFrame frame = horizontal_basis(fit_stair_vertical(scene, hyp, up0));
  const LevelsSeen seen = project_levels(scene, hyp, n, frame);
  if (levels_[static_cast<std::size_t>(seen.seed)].pts.size() < 3) {
    out.verdict = StairVerdict::kObstacle;
    return;
  }
  // Horizontal axes: minimum summed bounding-rectangle area, seeded by the best step.
  out.method = fit_axes(scene, n, seen.seed, frame);

  // Extents: each level's extents and edge in the stair frame; the staircase's span.
  const LevelExtents extents = level_extents(frame, n, dir, out);
  if (dir > 0 && level_stands_on_lower(n, frame.x2, frame.z2, out)) {
    out.verdict = StairVerdict::kStackedLevels;
    return;
  }
  StairSpan span = lateral_span(frame, n, extents.steps_not_landing, out);
  out.width_complete = span.seen[0] && span.seen[1];
  if (narrow_level_on_surface(frame, n, dir, span.width, out)) {
    out.verdict = StairVerdict::kStackedLevels;
    return;
  }
  const FloorSeen floor = floor_before_steps(scene, hyp, frame, n, dir, span, out);

  // Profile: riser, the risers placing the edges, the tread.
  StairProfile profile;
  profile.riser = fit_riser(hyp, n);
  if (dir > 0 && n >= 2) place_edges_at_risers(scene, frame, n, span, out);
  if (n >= 2) fit_tread(hyp, n, dir, floor, extents.steps_not_landing, span, profile, out);

  // Pose: origin at the centre of the first edge; every level in the stair frame.
  const StairOrigin origin =
      place_origin(hyp, n, dir, frame, span, floor, extents.near_boundary, profile, out);
  express_in_stair_frame(scene, hyp, n, dir, origin, span, floor, out);

  // Decision.
  if (floor_doubtful(scene, hyp, n, dir, frame, span, floor, profile.riser, origin.edge_b, out)) return;
  // Too few points somewhere leave a measure undefined: nothing is reported from it.
  if (!std::isfinite(profile.riser) || !std::isfinite(span.width) || !std::isfinite(out.tread_m) ||
      !origin.origin.allFinite()) {
    out.kind = StairKind::kNone;
    out.verdict = StairVerdict::kObstacle;
    return;
  }
  if (n == 1)
    decide_single_level(scene, hyp, dir, frame, span, floor, profile.riser, origin, out);
  else
    decide_flight(dir, span, profile, origin, out);
}

}  // namespace stairguide
