#pragma once
/// \file ground_truth.hpp
/// Ground truth carried by synthetic frames and by labelled dataset folders (`labels.yaml`).
///
/// The stair frame S follows the paper's Fig. 8: y_S points up (against gravity), z_S points
/// along the direction of travel into the staircase (away from the user who approaches it),
/// x_S = y_S x z_S runs along the step edge (to the user's left). The origin is the centre of
/// the first step's edge:
///  - ascending: the front (nosing) edge of the first tread, one riser above the floor;
///  - descending: the edge where the floor ends and the first drop begins (height 0);
///  - single step / curb: the edge of the raised (or lowered) surface nearest the user.

#include <limits>
#include <string>
#include <vector>

#include "stairguide/core/types.hpp"

namespace stairguide {

enum class StairKind { kNone, kAscending, kDescending, kSingleStep, kCurb };

/// "none", "ascending", "descending", "single_step", "curb".
const char* to_string(StairKind k);
/// Parses the names above; returns false on an unknown name.
bool parse_stair_kind(const std::string& s, StairKind& out);
/// Why a label's `down` contradicts its kind (an ascending flight or a single step that goes down,
/// a descending one that does not), or "" when they agree. A curb goes either way.
std::string down_contradiction(StairKind kind, bool down);

/// One staircase (or single step / curb) of a scene, as seen in one frame.
struct StairTruth {
  int id = 0;  ///< index of the staircase in the scene
  StairKind kind = StairKind::kNone;
  int steps = 0;        ///< number of risers
  float riser_m = 0.f;  ///< m, vertical distance between consecutive treads
  float tread_m = 0.f;  ///< m, horizontal distance edge to edge
  float width_m = 0.f;  ///< m
  bool open_risers = false;
  /// A curb: the ground beyond its edge is lower than the user's floor (a curb down taken for a
  /// step up is a fall, and the kind alone cannot say which way a curb goes). For the other kinds
  /// the kind says it; use goes_down().
  bool down = false;
  Pose T_camera_stair = Pose::Identity();  ///< stair frame S into camera frame C
  std::vector<int> visible_steps;          ///< 1-based indices of treads with >= 200 visible pixels
  std::vector<int> visible_pixels;         ///< visible tread pixels, one per entry of visible_steps
  bool first_edge_visible = false;         ///< the first step's edge is in view (not occluded)
  bool both_ends_visible = false;          ///< both ends of the first edge are in view (width measurable)
  int user_step = 0;                       ///< tread the user stands on: 0 = floor before it, k = step k

  /// The surface beyond the first edge is lower than the user's floor: descending, or a curb down.
  bool goes_down() const { return kind == StairKind::kDescending || (kind == StairKind::kCurb && down); }
};

/// Ground truth of one frame.
struct FrameTruth {
  std::uint64_t index = 0;
  double timestamp = 0.0;                  ///< s
  std::string scene;                       ///< preset name
  Pose T_world_camera = Pose::Identity();  ///< world: z up, origin on the floor
  float camera_height_m = 0.f;             ///< m above the floor the user stands on
  float camera_tilt_rad = 0.f;             ///< rad, optical axis below horizontal
  float camera_roll_rad = 0.f;             ///< rad
  bool floor_visible = false;              ///< >= 5% of pixels see the floor the user stands on
  std::vector<StairTruth> stairs;          ///< staircases in the scene (visible or not)
  /// Pixels of the most visible wall or riser face (a vertical face of a wall, a riser or a step,
  /// at least 8 cm tall, within range, where the depth sensor gives a reading): what the
  /// Manhattan frame is built from. 0 for dataset frames.
  int wall_or_riser_pixels = 0;
  /// False for a whole-folder label written by hand (dataset.hpp, read_folder_label_yaml): no
  /// per-frame pose, so T_world_camera and every T_camera_stair are unknown and a detection is
  /// scored by its direction (and by riser and tread where the label gives them), not its place.
  bool pose_known = true;
  /// A drop-off (the floor ends at an edge with nothing within a step below it: a platform edge,
  /// a dock, a hole, a sunken floor; issue 42 item 4) is in view: at least 0.3 m of its edge is
  /// seen, unoccluded and in range, with the floor before it. Distance (m, along the floor from
  /// the point under the camera) and bearing (rad, from the camera's forward direction, positive
  /// to the right) of the nearest point of the edge in view; NaN when none. drop_depth_m: how far
  /// the level beyond it lies below the floor (0 without a drop in the scene).
  bool drop_in_view = false;
  float drop_distance_m = std::numeric_limits<float>::quiet_NaN();
  float drop_bearing_rad = std::numeric_limits<float>::quiet_NaN();
  float drop_depth_m = 0.f;

  /// Staircases with at least one visible step or a visible first edge.
  bool any_stair_visible() const;
};

}  // namespace stairguide
