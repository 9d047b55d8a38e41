#pragma once
/// \file traversal_result.hpp
/// The typed stair and traversal results that leave the perception thread: what the feedback room
/// reads (distance, direction, step index, steps left as numbers, never parsed from text).
///
/// Frames: F is the floor frame of the frame (x left, y up, z forward, origin on the floor under
/// the camera); the user's forward is z_F. Bearings are measured about y_F from z_F, positive to the
/// user's right (a clock position of 3 o'clock is +90 deg).

#include <cmath>
#include <limits>

#include "stairguide/core/ground_truth.hpp"
#include "stairguide/core/types.hpp"

namespace stairguide {

/// One frame's stair detection, reduced to what the user is told (stairs room: StairResult).
struct StairSummary {
  bool detected = false;
  StairKind kind = StairKind::kNone;
  int direction = 0;           ///< +1 up, -1 down, 0 none (StairResult::direction)
  bool without_floor = false;  ///< no floor in view nor remembered: distance unknown
  int levels = 0;              ///< steps in view
  float riser_m = 0.f, tread_m = 0.f, width_m = 0.f;
  /// m, along the floor from the user's feet to the centre of the first edge; NaN when unknown.
  float distance_m = std::numeric_limits<float>::quiet_NaN();
  /// rad, bearing of the first edge's centre (positive to the right); NaN when unknown.
  float bearing_rad = std::numeric_limits<float>::quiet_NaN();
  Pose T_camera_stair = Pose::Identity();  ///< stair frame into the camera frame
  bool has_distance() const { return std::isfinite(distance_m); }
};

/// One frame's drop-off (stairs/drop_detection.hpp), reduced to what the user is told. A drop found
/// in a frame where the stair stage finds a staircase or step going down is not told as a drop:
/// the stair cue wins (`by_stairs`).
struct DropSummary {
  bool detected = false;
  bool by_stairs = false;  ///< a drop edge was found, but the stair stage tells a descent here
  /// m along the floor to the nearest point of the edge, rad its bearing (positive right); NaN none.
  float distance_m = std::numeric_limits<float>::quiet_NaN();
  float bearing_rad = std::numeric_limits<float>::quiet_NaN();
  float depth_m = std::numeric_limits<float>::quiet_NaN();  ///< m below the floor, as seen
};

/// Where the user is with respect to a staircase (paper 5.2).
enum class TraversalState {
  kSearching,   ///< no staircase ahead: detection and modelling run as usual
  kStairAhead,  ///< a staircase ahead, not yet on it
  kOnStairs,    ///< on the flight (step_index >= 1)
  kLastStep,    ///< the next step (or the one under the feet) is the last
  kArrived      ///< off the flight onto the new floor (held briefly, then searching)
};
/// "searching", "stair_ahead", "on_stairs", "last_step", "arrived".
inline const char* to_string(TraversalState s) {
  switch (s) {
    case TraversalState::kSearching: return "searching";
    case TraversalState::kStairAhead: return "stair_ahead";
    case TraversalState::kOnStairs: return "on_stairs";
    case TraversalState::kLastStep: return "last_step";
    case TraversalState::kArrived: return "arrived";
  }
  return "searching";
}

/// The traversal tracker's output for one frame.
struct TraversalResult {
  bool ran = false;  ///< false: no traversal tracker in this build / not run
  TraversalState state = TraversalState::kSearching;
  StairKind kind = StairKind::kNone;  ///< of the staircase tracked
  int direction = 0;                  ///< +1 up, -1 down, 0 none
  bool in_view = false;               ///< the staircase is seen in this frame (else held by odometry)
  bool remembered = false;            ///< the staircase comes from the stair memory
  /// m and rad, to the first edge along the floor and its bearing (as StairSummary); NaN unknown.
  float distance_m = std::numeric_limits<float>::quiet_NaN();
  float bearing_rad = std::numeric_limits<float>::quiet_NaN();
  int step_index = 0;       ///< step the user stands on: 0 = the floor before the flight, 1 = first step
  int steps_climbed = 0;    ///< steps gone up or down so far on this flight
  int steps_known = 0;      ///< steps in the model (grows as new steps come into view)
  int steps_left = -1;      ///< steps still to go; -1 while the end is not known
  bool last_known = false;  ///< the last step has been seen (a long tread or the floor beyond)
  /// Fused model (over the frames of this staircase, quality-weighted).
  float riser_m = 0.f, tread_m = 0.f, width_m = 0.f;
  Pose T_world_stair = Pose::Identity();  ///< stair frame in the odometry's world
  /// The correction from the live view applied this frame (eq. 15): m and rad.
  float corr_height_m = 0.f, corr_along_m = 0.f, corr_yaw_rad = 0.f;
  bool corrected = false;  ///< a correction was applied this frame
  double ms = 0.0;         ///< time spent in the tracker
  // Added by issue 32 (the tracker's own view, for replays and evaluation):
  /// m, the body centre in the stair frame: along z_S (from the first edge) and height along y_S
  /// (the feet, same origin as the stair frame); NaN while no staircase is held.
  float body_along_m = std::numeric_limits<float>::quiet_NaN();
  float body_height_m = std::numeric_limits<float>::quiet_NaN();
  float quality = 0.f;  ///< 0..1, weight of this frame's view in the fused model (0: not used)
};

}  // namespace stairguide
