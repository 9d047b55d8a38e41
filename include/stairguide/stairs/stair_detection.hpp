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
/// and the frame is refused (kFloorDoubtful). Whether the levels form a
/// valid staircase, single step or curb is decided by modelling (stair_modelling.hpp).

#include <Eigen/Core>
#include <vector>

#include "stairguide/core/config.hpp"
#include "stairguide/perception/scene.hpp"
#include "stairguide/stairs/stair_result.hpp"

namespace stairguide {

/// A level found by detection: the regions fused into it and its height.
struct LevelSeed {
  int index = 0;             ///< 0 = the floor, k = k-th step from the floor
  float height = 0.f;        ///< m from the floor along its normal (negative below), point-weighted
  int point_count = 0;       ///< points of the fused regions
  std::vector<int> regions;  ///< indices into SceneResult::regions
};

/// The levels of one direction (ascending or descending).
struct StairHypothesis {
  int direction = 0;                 ///< +1 ascending, -1 descending
  StairVerdict verdict = StairVerdict::kNoCandidates;  ///< kDetected when at least one level was found
  int candidates = 0;                ///< step candidates on this side of the floor
  int rejected = 0;                  ///< of those, left out (not connected, wrong height)
  std::vector<LevelSeed> levels;     ///< [0] is the floor (its regions may be empty), then steps 1..n
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
    float height = 0.f;                    ///< m above the floor (signed)
    Eigen::Vector3f lo, hi;                ///< bounding box of the sample, camera frame
    std::vector<Eigen::Vector3f> sample;   ///< evenly subsampled points
    int stride = 1;                        ///< points per sample point
  };

  void prepare(const SceneResult& scene, int region, Candidate& c) const;
  /// Points of `c` within the radius of the regions of `level`, >= the minimum (scaled by stride).
  bool connected(const Candidate& c, const LevelSeed& level) const;
  void build(int direction, StairHypothesis& hyp);

  ClassificationConfig cls_;
  StairDetectionConfig cfg_;
  std::vector<Candidate> pool_;        ///< prepared regions (candidates and floor), reused
  std::vector<int> region_slot_;       ///< region index -> slot in pool_, -1 when none
  std::vector<int> candidates_;        ///< slots of step candidates
  std::vector<int> floor_slots_;       ///< slots of floor regions
  std::vector<int> order_;
  std::vector<char> assigned_;
  std::vector<float> dist_;
  int used_ = 0;
};

}  // namespace stairguide
