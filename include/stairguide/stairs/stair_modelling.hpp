#pragma once
/// \file stair_modelling.hpp
/// Stair modelling (paper 4.2): axes, dimensions, pose and building-code validation of the levels
/// found by detection.
///
/// - Vertical axis y_S: the common normal of all the horizontal levels (floor and steps), fitted to
///   their points together; the floor transform's up when it disagrees.
/// - Horizontal axes: the rotation about y_S that minimises the summed bounding-rectangle areas of
///   the steps, searched from the principal axis of the step with the greatest extent (hull area over
///   rectangle area), levels over four times the median level's area (a landing, the lower floor,
///   whose rectangle turns with the image border cutting them) left out. When the scene has enough
///   Manhattan evidence and the Manhattan axes agree with the steps' own within
///   `manhattan_max_disagreement`, the Manhattan axes are used (method kManhattan); otherwise the
///   steps' (kPca). z_S points from the user into the staircase.
/// - Each step's points are moved along their camera ray onto the level's plane (depth noise lies
///   along the ray, so this removes most of it), then each level's step edge is found in z_S:
///   ascending, the near edge of each tread (its nosing); descending, the far edge of each level
///   (the floor's far edge is the first; the lowest level's far side on the image border is the
///   view's end, no edge, and that level is taken as the lower floor). Edges are extrapolated from
///   two low quantiles, which is unbiased for evenly spread points and insensitive to a few
///   strays. Ascending, the risers
///   facing the user place the edges in grazing views, and replace an edge whose tread's near rows
///   are hidden (one lying more than a nosing beyond its riser) or whose tread took in the riser's
///   top rows (one lying before its riser by more than edge_max_residual, the riser where the tread
///   below is seen to end and the step below placed by its riser too). A riser spans at least 15%
///   of the staircase's width (a post or a stringer is none).
/// - Tread: slope of the edge positions against the step index (edge to edge); riser: slope of the
///   level heights (centroid to centroid, the floor included); width: lateral extent of all steps.
///   The step index is LevelSeed::index, so steps hidden under the view (detection's hidden first
///   steps) count, and the first edge is extrapolated to index 0 (descending: the floor's edge).
/// - Origin: centre of the first edge (ascending: nosing of tread 1; descending: floor's edge).
/// - Validation: riser, tread, 2R+T and width against the building code (a width cut by the image
///   border only against half the minimum), evenly spaced edges; a
///   single level by size (obstacle / single step / curb, paper 4.1 last paragraph); a level one
///   riser below the floor starting at the shadow of the floor's edge is a drop however shallow.
///   An untracked floor seen less deep than a landing is refused (kFloorDoubtful): ascending, with a
///   level one riser below it in view or not reaching the image bottom; descending, with a larger
///   level one riser above it reaching the image bottom (the first tread taken for the floor).

#include <Eigen/Core>
#include <vector>

#include "stairguide/core/config.hpp"
#include "stairguide/perception/scene.hpp"
#include "stairguide/stairs/stair_axes.hpp"
#include "stairguide/stairs/stair_detection.hpp"
#include "stairguide/stairs/stair_levels.hpp"
#include "stairguide/stairs/stair_profile.hpp"
#include "stairguide/stairs/stair_result.hpp"

namespace stairguide {

/// Section 4.2. Pure: no I/O, no exceptions; buffers are kept between frames.
///
/// run() is a short driver over named phases, each in its own file under src/stairs/:
/// axes (stair_axes.cpp), levels (stair_levels.cpp), extents and the floor before the steps
/// (stair_extents.cpp), profile: riser, risers and tread (stair_profile.cpp), pose
/// (stair_pose.cpp), the floor doubt and the decisions for one level and a flight
/// (stair_decision.cpp), whose physical checks live in stair_checks.cpp.
class StairModelling {
 public:
  StairModelling(const ClassificationConfig& classification, const StairDetectionConfig& detection,
                 const StairModellingConfig& config);

  /// Models the levels of `hyp` (which must have at least one step level) and validates them.
  /// Fills every field of `out` except the timings. With the intrinsics `K` of the frame, a width
  /// cut by the image border is known to be a lower bound (StairResult::width_complete) and is held
  /// only to half the narrowest width; without them every width is taken as complete.
  void run(const SceneResult& scene, const StairHypothesis& hyp, StairResult& out,
           const CameraIntrinsics* K = nullptr);

 private:
  /// Output of the levels phase (levels in levels_).
  struct LevelsSeen {
    bool have_floor = false;  ///< the hypothesis has floor regions (else the floor plane is the transform's)
    int seed = 1;             ///< the step with the greatest extent: it seeds the horizontal axes
  };
  /// Output of the extents phase (per-level extents and edges in out.level_data, landings in landing_).
  struct LevelExtents {
    float near_boundary = 0.f;  ///< one level: its near boundary along z_S (NaN when not found)
    int steps_not_landing = 0;  ///< levels that are no landing
  };
  /// The staircase's lateral span along x_S.
  struct StairSpan {
    float a_min = 0.f, a_max = 0.f;  ///< m, lateral ends over the steps (landings left out)
    float width = 0.f, a_mid = 0.f;  ///< m, width and centre (the tread fit may narrow them to its inliers)
    bool seen[2] = {true, true};     ///< each lateral end (min, max) seen inside the image
  };
  /// What the floor phase found of the floor before the first step (in out.level_data[0]).
  struct FloorSeen {
    bool edge = false;    ///< descending: the floor's far edge at the drop was found
    bool extent = false;  ///< ascending: the floor's extent before the first step was measured
  };
  /// Output of the profile phase.
  struct StairProfile {
    float riser = 0.f;            ///< m
    LineFit tread;                ///< step edges against the step index (slope: the tread)
    bool edge_consistent = true;  ///< most edges lie on the tread line
    float edge_residual = 0.f;    ///< m, largest residual of the edges on it
  };
  /// Output of the pose phase: where the stair frame's origin lies.
  struct StairOrigin {
    float edge_b = 0.f;  ///< m, first edge along z_S (camera frame)
    float plane = 0.f;   ///< m, up . p of the origin's level
    Eigen::Vector3f origin = Eigen::Vector3f::Zero();
  };

  // ---- phases (run's order) ----
  /// Clears `out` for hypothesis `hyp` with n step levels (verdict kNoFirstStep).
  void reset_result(const StairHypothesis& hyp, int n, StairResult& out) const;
  /// Levels (stair_levels.cpp): every level projected into levels_, step outlines, the seed step.
  LevelsSeen project_levels(const SceneResult& scene, const StairHypothesis& hyp, int n,
                            const StairFrame& frame);
  /// Axes (stair_axes.cpp): the horizontal axes (x_S, z_S) into `frame`; returns the method.
  StairAxesMethod fit_axes(const SceneResult& scene, int n, int seed, StairFrame& frame);
  /// Minimum summed bounding-rectangle area of steps 1..n, searched from `seed_angle`.
  float min_area_angle(int n, float seed_angle);
  /// Which of the two axes at `theta` runs into the staircase, and which way.
  Eigen::Vector2f orient_into_staircase(int n, float theta) const;
  /// Extents (stair_extents.cpp): per-level extents and edges, landings.
  LevelExtents level_extents(const StairFrame& frame, int n, int dir, StairResult& out);
  /// The lateral span of the steps and whether each end is seen.
  StairSpan lateral_span(const StairFrame& frame, int n, int steps_not_landing, const StairResult& out) const;
  /// Going up: a step seen whole across yet far narrower than the staircase (an object on a surface).
  bool narrow_level_on_surface(const StairFrame& frame, int n, int dir, float width,
                               const StairResult& out) const;
  /// The floor before the first step: its extent (ascending) or its far edge (descending).
  FloorSeen floor_before_steps(const SceneResult& scene, const StairHypothesis& hyp, const StairFrame& frame,
                               int n, int dir, const StairSpan& span, StairResult& out);
  /// Profile (stair_profile.cpp): riser from the level heights.
  float fit_riser(const StairHypothesis& hyp, int n);
  /// Going up: each level's riser below it (riser_at_, NaN: none), a vertical region facing the
  /// user across the staircase between the level's and the one below's heights, where a step
  /// can start.
  void find_risers(const SceneResult& scene, const StairFrame& frame, int n, const StairSpan& span,
                   const StairResult& out);
  /// Going up: risers facing the user place the steps' starts where the treads' edges mislead.
  void place_edges_at_risers(const SceneResult& scene, const StairFrame& frame, int n, const StairSpan& span,
                             StairResult& out);
  /// Tread line by consensus over the edges; narrows `span` to the levels on it.
  void fit_tread(const StairHypothesis& hyp, int n, int dir, const FloorSeen& floor, int steps_not_landing,
                 StairSpan& span, StairProfile& profile, const StairResult& out);
  /// Pose (stair_pose.cpp): the origin at the centre of the first edge; sets the pose and measures.
  StairOrigin place_origin(const StairHypothesis& hyp, int n, int dir, const StairFrame& frame,
                           const StairSpan& span, const FloorSeen& floor, float near_boundary,
                           const StairProfile& profile, StairResult& out) const;
  /// Every level's output (heights, indices, extents from the origin, points).
  void express_in_stair_frame(const SceneResult& scene, const StairHypothesis& hyp, int n, int dir,
                              const StairOrigin& o, const StairSpan& span, const FloorSeen& floor,
                              StairResult& out) const;
  /// Decision (stair_decision.cpp): is the "floor" the one the user stands on? Sets the verdict
  /// kFloorDoubtful and returns true when it is not sure.
  bool floor_doubtful(const SceneResult& scene, const StairHypothesis& hyp, int n, int dir,
                      const StairFrame& frame, const StairSpan& span, const FloorSeen& floor, float riser,
                      float edge_b, StairResult& out) const;
  /// A single level: obstacle, single step or curb.
  void decide_single_level(const SceneResult& scene, const StairHypothesis& hyp, int dir,
                           const StairFrame& frame, const StairSpan& span, const FloorSeen& floor,
                           float riser, const StairOrigin& o, StairResult& out) const;
  /// Single level: does it run out of the image at its far side (its depth then only a lower bound)?
  bool far_side_out_of_view(const StairFrame& frame, float a_mid, float edge_b, const StairLevel& o) const;
  /// Single level below the floor: does its seen strip start at the shadow of the floor's edge (a
  /// drop, however shallow)?
  bool strip_at_floor_edge_shadow(float riser, const StairLevel& o, const StairResult& out) const;
  /// Single level: a horizontal surface above it, within its footprint (furniture, no step).
  bool surface_above(const SceneResult& scene, const StairHypothesis& hyp, const StairFrame& frame,
                     float a_mid, float edge_b, const StairLevel& o) const;
  /// A flight: physical checks (stair_checks.hpp) and the edges' consistency.
  void decide_flight(int dir, const StairSpan& span, const StairProfile& profile, const StairOrigin& o,
                     StairResult& out) const;

  // ---- helpers ----
  /// The stair axes and a level's plane, to put a 2D point back in the camera frame.
  struct BoundaryFrame {
    Eigen::Vector3f x, z, up;
    float plane;
  };
  float area_cost(float angle, int first, int last) const;
  /// Nearest (low) or farthest point of each lateral bin into bin_a_/bin_e_ (those on the image
  /// border dropped when the intrinsics are known); returns their median.
  float boundary_median_ab(const std::vector<float>& a, const std::vector<float>& b, bool low,
                           const BoundaryFrame& f);
  float boundary_median(const std::vector<Eigen::Vector2f>& pts, const Eigen::Vector2f& x2,
                        const Eigen::Vector2f& z2, const BoundaryFrame& f);
  /// The near boundary from the bins of the last boundary_median: the median of the largest group
  /// of bins at one depth (the edge), or `median` when fewer than 5 agree.
  float boundary_mode(float median);
  /// True when the far side of a level (points in the basis x2, z2) lies mostly on the image
  /// border: its far boundary is where the view ends. False without the intrinsics.
  bool far_side_cut(const std::vector<Eigen::Vector2f>& pts, const Eigen::Vector2f& x2,
                    const Eigen::Vector2f& z2, const BoundaryFrame& f);
  /// True when a vertical panel reaching above the single level `o` stands at one of its lateral
  /// ends over its depth (a shelf's or cabinet's bottom board). Axes and positions as in validation.
  bool boxed_in(const SceneResult& scene, const Eigen::Vector3f& xs, const Eigen::Vector3f& up,
                const Eigen::Vector3f& zs, float a_mid, float edge_b, const StairLevel& o, float plane) const;
  /// Going up (levels 1..n in the basis x2, z2, their extents in out.level_data): true when a level
  /// shows well beyond the far side of the next one up, within its width: it carries that level
  /// (a box on a shelf board), no flight does.
  bool level_stands_on_lower(int n, const Eigen::Vector2f& x2, const Eigen::Vector2f& z2,
                             const StairResult& out) const;
  /// Turns z2 so that the near boundary of a single level runs along x.
  void refine_single_axis(const StairLevel2d& level, Eigen::Vector2f& z2, const Eigen::Vector3f& e1,
                          const Eigen::Vector3f& e2, const Eigen::Vector3f& up);

  ClassificationConfig cls_;
  StairDetectionConfig det_;
  StairModellingConfig cfg_;
  std::vector<StairLevel2d> levels_;  ///< [0] floor, then steps
  std::vector<float> a_, b_;          ///< scratch coordinates
  std::vector<Eigen::Vector2f> sub_;  ///< scratch subsample for hulls
  std::vector<float> fit_k_, fit_e_;  ///< scratch for the edge fit
  std::vector<int> fit_level_;        ///< level (position in the hypothesis) of each fit entry
  std::vector<char> fit_in_;          ///< scratch: each fit entry on the tread line
  std::vector<float> ba_, bb_, a_band_, bin_a_, bin_e_, bin_ext_, bin_at_, sorted_,
      tmp_;  ///< scratch for boundaries
  std::vector<int> bin_count_;
  std::vector<char> landing_;            ///< per level: deeper than a tread (landing or floor)
  std::vector<char> axis_skip_;          ///< per level: left out of the axes' area cost (a landing)
  std::vector<char> outlier_;            ///< per level: edge off the staircase's line
  std::vector<float> riser_at_;          ///< per level: position along z_S of the riser below it (NaN: none)
  std::vector<int> riser_n_;             ///< per level: points of that riser's region
  const CameraIntrinsics* K_ = nullptr;  ///< intrinsics of the frame being modelled, when given
};

}  // namespace stairguide
