#pragma once
/// \file stair_detection.hpp
/// Stair detection (paper 4.1, Algorithm 1): groups perception's step candidates into levels by
/// connectivity and height, for ascending (above the floor) and descending (below) staircases.
///
/// A candidate joins the staircase when at least `connection_min_points` of its points lie within
/// `connection_radius` of an established level (the floor is level 0) and its height either
/// matches a level (within `same_level_tolerance`: the regions fuse) or lies one riser
/// (H_min..H_max, with `height_tolerance` of slack) above the highest level. The first step must be
/// one riser from the floor and connected to it when the floor is visible as a region. Candidates
/// that never connect (a table, a shelf board) are left out as obstacles. When a level below the
/// floor lies nearer the user than the floor itself, the floor cannot be the one the user stands on
/// and the frame is refused (kFloorDoubtful), unless perception tracked that floor from the frames
/// before (SceneResult::floor_tracked: at the top of a descent the treads below are nearer the
/// user than the floor beside the stairwell).
///
/// Hidden first steps (descending, tracked floor only): at the top of a descent the first tread or
/// two lie under the bottom of the view. The first level seen is then two or more risers down and
/// cannot be the first step; it is taken as step m (LevelSeed::index) when the levels seen form an
/// evenly spaced stack whose spacing is a riser (H_min..H_max), the first of them lies m risers
/// below the floor (2 <= m <= 4), it reaches the bottom of the view (the steps above it are out of
/// view, not missing) and it lies, seen from above, within the connection radius of the floor (the
/// stairwell is cut into the floor the user stands on). A table top is never below the floor, which
/// is what the paper's connection rule guards against; here the tracked floor's height and the
/// stack's own spacing say which step the first seen level is.
///
/// Whether the levels form a valid staircase, single step or curb is decided by modelling
/// (stair_modelling.hpp).

#include <Eigen/Core>
#include <vector>

#include "stairguide/core/config.hpp"
#include "stairguide/perception/scene.hpp"
#include "stairguide/stairs/stair_result.hpp"

namespace stairguide {

/// A level found by detection: the regions fused into it and its height.
struct LevelSeed {
  /// 0 = the floor, k = k-th step from the floor. Consecutive seeds are consecutive steps; the
  /// first step seed may have an index above 1 when the steps before it are out of view.
  int index = 0;
  float height = 0.f;        ///< m from the floor along its normal (negative below), point-weighted
  int point_count = 0;       ///< points of the fused regions
  std::vector<int> regions;  ///< indices into SceneResult::regions
};

/// The levels of one direction (ascending or descending).
struct StairHypothesis {
  int direction = 0;                                   ///< +1 ascending, -1 descending
  StairVerdict verdict = StairVerdict::kNoCandidates;  ///< kDetected when at least one level was found
  int candidates = 0;                                  ///< step candidates on this side of the floor
  int rejected = 0;                                    ///< of those, left out (not connected, wrong height)
  int hidden_steps = 0;           ///< steps between the floor and the first level seen, out of view
  std::vector<LevelSeed> levels;  ///< [0] is the floor (its regions may be empty), then steps 1..n
  int step_levels() const { return levels.empty() ? 0 : static_cast<int>(levels.size()) - 1; }
};

/// Output of detection on one frame.
struct StairDetectionOutput {
  StairVerdict verdict = StairVerdict::kNoCandidates;  ///< kNoFloor / kNoCandidates / kDetected
  int candidates = 0;
  StairHypothesis ascending, descending;
};

/// Algorithm 1. Pure: no I/O, no exceptions; buffers are kept between frames.
class StairDetection {
 public:
  StairDetection(const ClassificationConfig& classification, const StairDetectionConfig& config);

  /// Runs detection on one perception result.
  void run(const SceneResult& scene, StairDetectionOutput& out);

 private:
  struct Candidate {
    int region = -1;
    float height = 0.f;                   ///< m above the floor (signed)
    Eigen::Vector3f lo, hi;               ///< bounding box of the sample, camera frame
    std::vector<Eigen::Vector3f> sample;  ///< evenly subsampled points
    int stride = 1;                       ///< points per sample point
  };

  void prepare(const SceneResult& scene, int region, Candidate& c) const;
  /// Points of `c` within the radius of the regions of `level`, >= the minimum (scaled by stride).
  /// With `horizontal`, distances are taken in the horizontal plane (heights left out). A positive
  /// `radius` replaces the configured connection radius.
  bool connected(const Candidate& c, const LevelSeed& level, bool horizontal = false,
                 float radius = 0.f) const;
  void build(int direction, StairHypothesis& hyp);
  /// Algorithm 1's loop: adds unassigned candidates to the levels of `hyp` until nothing changes.
  void sweep(StairHypothesis& hyp);
  /// True when an unassigned candidate other than order_[i] (`pts` points) would also be the next
  /// level above `top` at another height nearer the riser so far, is connected to the levels, and
  /// is kBiggerLevel times larger: the sweep then leaves order_[i] out for it.
  bool bigger_next_level(const StairHypothesis& hyp, std::size_t i, float top, int pts) const;
  /// The hidden-first-steps route (see the file comment); true when it found a staircase.
  bool build_hidden(StairHypothesis& hyp);
  /// Ascending, when no first step touches the floor: a stack of two or more evenly spaced levels
  /// whose lowest lies one riser above the floor and beside it seen from above (the floor seen
  /// only beside the stairs, the foot of the flight hidden); true when it found one.
  bool build_stack(StairHypothesis& hyp);
  /// Lowest image row (as y/z) that any region of the scene reaches: the bottom of the view.
  float view_bottom(const SceneResult& scene) const;
  /// Ascending: a solid upright face stands between level k-1 and level k of `hyp` (its riser):
  /// facing the user, from the lower level up to the upper one's near edge, level k behind it,
  /// across most of level k's width. What a shelf board or a seat over open space lacks.
  bool riser_seen(const StairHypothesis& hyp, int k);
  /// A region of level k of `hyp` reaches the bottom of the view (its depth there is cut).
  bool reaches_view_bottom(const StairHypothesis& hyp, int k);
  /// How far level k-1 of `hyp` (0: the floor) reaches before level k starts, horizontally (m).
  float going(const StairHypothesis& hyp, int k);
  /// The sampled points of level k of `hyp` (0: the floor) into `pts`.
  void level_points(const StairHypothesis& hyp, int k, std::vector<Eigen::Vector3f>& pts) const;

  ClassificationConfig cls_;
  StairDetectionConfig cfg_;
  std::vector<Candidate> pool_;   ///< prepared regions (candidates and floor), reused
  std::vector<int> region_slot_;  ///< region index -> slot in pool_, -1 when none
  std::vector<int> candidates_;   ///< slots of step candidates
  std::vector<int> floor_slots_;  ///< slots of floor regions
  std::vector<int> order_;
  std::vector<char> assigned_;
  // Scratch for setting a lone first level aside (build): the sweep's state before, reused.
  std::vector<LevelSeed> saved_levels_;
  std::vector<char> saved_assigned_, left_out_;
  std::vector<float> dist_;
  std::vector<Eigen::Vector3f> upper_, lower_;  ///< scratch for riser_seen: the two levels' points
  int used_ = 0;
  bool floor_tracked_ = false;
  bool hidden_sweep_ = false;  ///< build_hidden's sweep: the first level's index is provisional
  Eigen::Vector3f up_ = -Eigen::Vector3f::UnitY();  ///< floor's up, camera frame
  float up_offset_ = 0.f;                           ///< height above the floor = up_ . p + up_offset_
  float view_bottom_ = 0.f;                         ///< of the current scene, see view_bottom()
  const SceneResult* scene_ = nullptr;              ///< the scene being run (only during run())
};

}  // namespace stairguide
