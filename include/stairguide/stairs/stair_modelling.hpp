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
#include "stairguide/stairs/stair_detection.hpp"
#include "stairguide/stairs/stair_result.hpp"

namespace stairguide {

/// Section 4.2. Pure: no I/O, no exceptions; buffers are kept between frames.
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
  struct Level2d {
    std::vector<Eigen::Vector2f> pts;  ///< ray-projected points in the horizontal basis (e1, e2)
    float plane = 0.f;                 ///< mean of up . p (camera frame), m
    Eigen::Vector2f centroid = Eigen::Vector2f::Zero();
    std::vector<Eigen::Vector2f> hull; ///< convex hull of a subsample
    float extent = 0.f;                ///< hull area / PCA rectangle area
    float pca_angle = 0.f;             ///< rad, major axis in (e1, e2)
  };

  Eigen::Vector3f fit_up(const SceneResult& scene, const StairHypothesis& hyp, const Eigen::Vector3f& up0);
  void project_level(const SceneResult& scene, const LevelSeed& seed, const Eigen::Vector3f& up,
                     const Eigen::Vector3f& e1, const Eigen::Vector3f& e2, std::size_t max_points, Level2d& out);
  float area_cost(float angle, int first, int last) const;
  /// The stair axes and a level's plane, to put a 2D point back in the camera frame.
  struct BoundaryFrame {
    Eigen::Vector3f x, z, up;
    float plane;
  };
  /// Nearest (low) or farthest point of each lateral bin into bin_a_/bin_e_ (those on the image
  /// border dropped when the intrinsics are known); returns their median.
  float boundary_median_ab(const std::vector<float>& a, const std::vector<float>& b, bool low, const BoundaryFrame& f);
  float boundary_median(const std::vector<Eigen::Vector2f>& pts, const Eigen::Vector2f& x2, const Eigen::Vector2f& z2,
                        const BoundaryFrame& f);
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
  bool level_stands_on_lower(int n, const Eigen::Vector2f& x2, const Eigen::Vector2f& z2, const StairResult& out) const;
  /// Turns z2 so that the near boundary of a single level runs along x.
  void refine_single_axis(const Level2d& level, Eigen::Vector2f& z2, const Eigen::Vector3f& e1,
                          const Eigen::Vector3f& e2, const Eigen::Vector3f& up);
  float robust_low(std::vector<float>& v) const;
  float robust_high(std::vector<float>& v) const;

  ClassificationConfig cls_;
  StairDetectionConfig det_;
  StairModellingConfig cfg_;
  std::vector<Level2d> levels_;       ///< [0] floor, then steps
  std::vector<float> a_, b_;          ///< scratch coordinates
  std::vector<Eigen::Vector2f> sub_;  ///< scratch subsample for hulls
  std::vector<float> fit_k_, fit_e_;  ///< scratch for the edge fit
  std::vector<int> fit_level_;        ///< level (position in the hypothesis) of each fit entry
  std::vector<float> ba_, bb_, a_band_, bin_a_, bin_e_, bin_ext_, bin_at_, sorted_, tmp_;  ///< scratch for boundaries
  std::vector<int> bin_count_;
  std::vector<char> landing_;         ///< per level: deeper than a tread (landing or floor)
  std::vector<char> axis_skip_;       ///< per level: left out of the axes' area cost (a landing)
  std::vector<char> outlier_;         ///< per level: edge off the staircase's line
  std::vector<float> riser_at_;       ///< per level: position along z_S of the riser below it (NaN: none)
  std::vector<int> riser_n_;          ///< per level: points of that riser's region
  const CameraIntrinsics* K_ = nullptr;  ///< intrinsics of the frame being modelled, when given
};

}  // namespace stairguide
