#pragma once
/// \file drop_detection.hpp
/// Drop-offs (issue 42 item 4): the floor the wearer stands on ends at an edge with nothing within
/// a step below it (a platform edge, a loading dock, a hole, a sunken floor).
///
/// Physical evidence only. With the floor known (perception's T_floor_camera), each sampled image
/// column is followed from the bottom of the view outwards along the floor. Where the floor's
/// readings end, the rays just beyond the edge (those whose continued floor lies within a short
/// look-ahead past it) say what is there:
///  - a surface above the floor (a wall, furniture, a person): the floor is occluded, no drop;
///  - the floor again: a gap in the readings (a dark patch, a hole in the data), no drop;
///  - a level within a step below the floor (less than `min_depth`): a step or a staircase going
///    down, which the stair stage tells, no drop;
///  - surfaces more than `min_depth` below the floor: the evidence of a drop;
///  - no reading at all where the floor, continued, would lie within `sensor_range` and be seen:
///    consistent with a drop whose bottom is out of range; it extends an edge but never makes one
///    alone (a dark floor reads nothing beyond a few metres, just the same).
/// Adjacent columns whose edges join make an edge; an edge at least `min_width` long with surfaces
/// seen below on at least a fifth of its columns (and two) is a drop. The nearest point of such an
/// edge within `max_distance` is reported.
///
/// Pure: no state, no I/O; works at any image size and intrinsics.

#include <limits>

#include "stairguide/core/config.hpp"
#include "stairguide/core/types.hpp"
#include "stairguide/perception/scene.hpp"
#include "stairguide/stairs/stair_result.hpp"
#include "stairguide/stairs/traversal_result.hpp"

namespace stairguide {

/// Why a frame has no drop (or that it has one).
enum class DropVerdict {
  kDetected,     ///< a drop edge was found
  kDisabled,     ///< drops.enabled is off
  kNoFloor,      ///< perception found no floor: no height to measure a drop from
  kNoEdge,       ///< the floor's readings never end before something that is not a drop
  kNoDepthSeen,  ///< edges with no reading beyond them, but nothing seen below: not told
  kTooNarrow,    ///< drop evidence, on an edge shorter than min_width
  kTooFar        ///< a drop edge, farther than max_distance
};
/// "drop", "disabled", "no floor", "no edge", "nothing seen below the edge", "edge too short",
/// "too far".
const char* to_string(DropVerdict v);

/// What the drop stage found in one frame.
struct DropResult {
  bool ok = false;        ///< the stage ran on a view with a floor
  bool detected = false;  ///< a drop edge within max_distance
  DropVerdict verdict = DropVerdict::kNoFloor;
  /// m, along the floor from the point under the camera to the nearest point of the edge; NaN none.
  float distance_m = std::numeric_limits<float>::quiet_NaN();
  /// rad, bearing of that point from the camera's forward direction on the floor (positive right).
  float bearing_rad = std::numeric_limits<float>::quiet_NaN();
  /// m, median depth below the floor of the surfaces seen beyond the edge.
  float depth_m = std::numeric_limits<float>::quiet_NaN();
  float width_m = 0.f;   ///< m, length of the edge found
  int columns = 0;       ///< sampled columns on the edge
  int deep_columns = 0;  ///< ... of which saw a surface below the floor beyond it
  double ms = 0.0;       ///< time spent
};

/// Looks for a drop-off in `frame` given perception's `scene` (its floor).
DropResult detect_drop(const RgbdFrame& frame, const SceneResult& scene, const DropConfig& config);

/// What the user is told of `drop`: nothing when the stair stage's `stairs` of the same frame is a
/// staircase, step or curb going down (a level a step below: the stair cue wins; `by_stairs`).
DropSummary summarize_drop(const DropResult& drop, const StairResult& stairs);

}  // namespace stairguide
