#pragma once
/// \file stair_result.hpp
/// What stair detection and modelling (paper section 4) return for one frame.
///
/// Stair frame S (see core/ground_truth.hpp): y_S up, z_S along the direction of travel into the
/// staircase, x_S = y_S x z_S along the step edge (to the user's left); the origin is the centre of
/// the first step's edge (ascending: nosing of tread 1; descending: the floor's edge; single step
/// or curb: the edge of the other level nearest the user).

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "stairguide/core/ground_truth.hpp"
#include "stairguide/core/types.hpp"

namespace stairguide {

/// How the stair axes were found (paper 4.2).
enum class StairAxesMethod {
  kNone,       ///< no model
  kManhattan,  ///< axes of the scene's Manhattan frame
  kPca         ///< PCA of the greatest-extent step, rotated to minimise the bounding rectangles
};
const char* to_string(StairAxesMethod m);

/// Why a frame has no staircase (or why a candidate staircase was rejected).
enum class StairVerdict {
  kDetected,           ///< a staircase, single step or curb was found and validated
  kNoFloor,            ///< perception found no floor: heights are unknown
  kFloorDoubtful,      ///< a level below the floor lies nearer the user than the floor: the floor is not
                       ///< the one the user stands on, so no height can be trusted
  kNoCandidates,       ///< no horizontal region at step height
  kNoFirstStep,        ///< no candidate at one riser from the floor and connected to it
  kObstacle,           ///< a single level too small for a step (a box, a seat, a low platform)
  kRiserOutOfRange,    ///< riser outside what a leg climbs (stair_checks.hpp: 5-25 cm), not a step
  kTreadTooShort,      ///< tread too shallow to hold a foot (stair_checks.hpp: under 15 cm)
  kBlondelOutOfRange,  ///< unused since issue 39: 2R+T only describes (StairResult::code_notes)
  kTooNarrow,          ///< too narrow for a body (stair_checks.hpp: under 0.5 m)
  kInconsistentEdges,  ///< step edges not evenly spaced (not a staircase)
  kStackedLevels,      ///< a level stands on the one below it (a box on a shelf board), not a step
  kTreadTooLong  ///< consecutive levels farther apart than a stride (stair_checks.hpp: 60 cm): no flight
};
/// Short human-readable reason ("no floor", "tread too short", ...).
const char* to_string(StairVerdict v);

/// One level of a detected staircase (level 0 is the floor the user stands on).
struct StairLevel {
  int index = 0;             ///< steps from the floor (1 = first step); signed by direction
  float height = 0.f;        ///< m above the floor (negative for descending)
  std::vector<int> regions;  ///< indices into SceneResult::regions fused into this level
  std::vector<Eigen::Vector3f>
      points;        ///< camera frame, the fused regions' points (evenly subsampled, <= 4000)
  float edge = 0.f;  ///< m, position of the level's step edge along z_S (stair frame)
  float lateral_min = 0.f, lateral_max = 0.f;  ///< m, extent along x_S (stair frame)
  float depth_min = 0.f, depth_max = 0.f;      ///< m, extent along z_S (stair frame)
};

/// Timings of the stage, milliseconds.
struct StairTimings {
  double detection_ms = 0, modelling_ms = 0, total_ms = 0;
};

/// Result of stair detection and modelling on one frame.
struct StairResult {
  bool detected = false;                               ///< a validated staircase, single step or curb
  StairVerdict verdict = StairVerdict::kNoCandidates;  ///< kDetected or why not
  StairKind kind = StairKind::kNone;       ///< kind of what was detected (or of the rejected candidate)
  int levels = 0;                          ///< levels seen above/below the floor (steps in view)
  float riser_m = 0.f;                     ///< m, riser height (centroid to centroid)
  float tread_m = 0.f;                     ///< m, tread length (edge to edge); 0 with one level
  float width_m = 0.f;                     ///< m, widest step seen
  bool width_complete = false;             ///< both lateral ends seen (not cut by the image border)
  Pose T_camera_stair = Pose::Identity();  ///< stair frame S into the camera frame C
  Eigen::Vector3f edge_left = Eigen::Vector3f::Zero();   ///< camera frame, +x_S end of the first edge
  Eigen::Vector3f edge_right = Eigen::Vector3f::Zero();  ///< camera frame, -x_S end of the first edge
  StairAxesMethod method = StairAxesMethod::kNone;
  /// Found without a floor (stairs/floorless.hpp): level 0 is a virtual level one riser beyond the
  /// first seen level, heights are relative to it, and the distance from the user's feet (and
  /// whether the first seen level is the first step) is unknown.
  bool without_floor = false;
  /// Found by the floorless route with no floor in view but the camera's height above the user's
  /// feet remembered (SceneResult::remembered_camera_height): the floor is the plane that far below
  /// the camera along the steps' own vertical, so heights, step indices, the first edge and the
  /// distance are known as with a floor (`without_floor` is false). Level 0 is the floor (seen or
  /// not); a first step out of view (at the feet) is placed one tread before the first seen edge
  /// and the first seen level's index is then 2 (level_data[k].index counts from the floor).
  bool floor_remembered = false;
  std::vector<StairLevel> level_data;  ///< floor first (index 0), then each step level in order
  /// How the staircase compares with the configured building code (bits of StairCodeNote in
  /// stair_checks.hpp; 0 = within code). It describes, it never silences.
  std::uint32_t code_notes = 0;
  int candidates = 0;           ///< step candidates considered
  int rejected_candidates = 0;  ///< candidates left out as obstacles (tables, ...)
  StairTimings timings;

  /// Which way what was found goes from the user's floor: +1 up (ascending, single step, curb up),
  /// -1 down (descending, curb down), 0 when nothing (not even a rejected candidate) was modelled.
  /// A curb's kind does not say it: its level's height does.
  int direction() const {
    switch (kind) {
      case StairKind::kAscending:
      case StairKind::kSingleStep: return 1;
      case StairKind::kDescending: return -1;
      case StairKind::kCurb:
        if (level_data.size() > 1 && level_data[1].height != 0.f) return level_data[1].height > 0.f ? 1 : -1;
        return 0;
      default: return 0;
    }
  }

  /// Centre of the first edge in the camera frame.
  Eigen::Vector3f origin() const { return T_camera_stair.translation(); }

  /// Nothing found, for `why`: every field back to its default except the timings (level_data
  /// keeps its capacity), with `candidates` counted and all of them left out.
  void clear(StairVerdict why, int candidates_considered) {
    detected = false;
    verdict = why;
    kind = StairKind::kNone;
    levels = 0;
    riser_m = tread_m = width_m = 0.f;
    width_complete = false;
    T_camera_stair = Pose::Identity();
    edge_left.setZero();
    edge_right.setZero();
    method = StairAxesMethod::kNone;
    without_floor = false;
    floor_remembered = false;
    code_notes = 0;
    level_data.clear();
    candidates = rejected_candidates = candidates_considered;
  }
};

}  // namespace stairguide
