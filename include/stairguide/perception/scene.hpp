#pragma once
/// \file scene.hpp
/// What perception (segmentation, floor, Manhattan frame, classification; paper section 3) hands
/// to stair detection. Fields may be added; the ones here are the contract with the stairs stage.

#include <Eigen/Core>
#include <limits>
#include <string>
#include <vector>

#include "stairguide/core/types.hpp"

namespace stairguide {

/// Class of a region (paper 3.3, Fig. 3 f / Fig. 5).
enum class RegionClass {
  kUnclassified,
  kFloor,          ///< horizontal, at floor height
  kStepCandidate,  ///< horizontal, |H| >= H_min above or below the floor
  kObstacle,       ///< horizontal at a non-step height, non-planar cluster, unknown vertical
  kVerticalLeft,   ///< vertical, facing right (a wall on the user's left)
  kVerticalRight,  ///< vertical, facing left
  kVerticalFront,  ///< vertical, facing the user (riser, wall ahead)
  kVertical,       ///< vertical, no Manhattan frame to place it
  kOther           ///< neither horizontal nor vertical
};
const char* to_string(RegionClass c);

/// A planar region from segmentation, with its classification.
struct PlaneRegion {
  int id = -1;
  Eigen::Vector3f normal = Eigen::Vector3f::Zero();    ///< unit, camera frame, facing the camera
  float offset = 0.f;                                  ///< plane: normal . p + offset = 0 (m)
  Eigen::Vector3f centroid = Eigen::Vector3f::Zero();  ///< camera frame, m
  std::vector<Eigen::Vector3f> points;                 ///< inlier points, camera frame (may be downsampled)
  std::vector<int> pixels;  ///< pixel indices v*width+u of the full-resolution inliers
  int pixel_count = 0;      ///< full-resolution pixels in the region
  float area = 0.f;         ///< m^2, area of the concave hull (or pixel footprint)
  float curvature = 0.f;    ///< mean surface variation
  /// Bounding rectangle in the region's own principal axes (in-plane), camera frame.
  Eigen::Vector3f rect_center = Eigen::Vector3f::Zero();
  Eigen::Vector3f rect_axis_major = Eigen::Vector3f::UnitX();
  Eigen::Vector3f rect_axis_minor = Eigen::Vector3f::UnitY();
  float rect_length_major = 0.f;  ///< m
  float rect_length_minor = 0.f;  ///< m
  float hull_extent = 0.f;        ///< concave-hull area / rectangle area, 0..1 (paper 4.2 "extent")

  RegionClass cls = RegionClass::kUnclassified;
  float height =
      std::numeric_limits<float>::quiet_NaN();  ///< m above the floor (centroid), NaN without floor
};

/// A non-planar cluster (paper 3.1, Euclidean cluster extraction): an obstacle.
struct ObstacleCluster {
  std::vector<Eigen::Vector3f> points;  ///< camera frame
  Eigen::Vector3f centroid = Eigen::Vector3f::Zero();
  Eigen::Vector3f min = Eigen::Vector3f::Zero(), max = Eigen::Vector3f::Zero();  ///< box, camera frame
};

/// Per-stage timings, milliseconds.
struct PerceptionTimings {
  double segmentation_ms = 0, floor_ms = 0, manhattan_ms = 0, classification_ms = 0, total_ms = 0;
};

/// Result of perception on one frame.
struct SceneResult {
  bool floor_found = false;
  std::string why;                         ///< why no floor (when !floor_found)
  Pose T_floor_camera = Pose::Identity();  ///< camera into floor frame F (x left, y up, z forward)
  float camera_height = 0.f;               ///< m
  float camera_tilt = 0.f;                 ///< rad, optical axis below horizontal
  float camera_roll = 0.f;                 ///< rad
  int floor_region = -1;                   ///< index into regions, -1 when the floor is not a region
  /// The floor was chosen by agreement with the previous frames' floor (FloorEstimate::tracked):
  /// either it passed every check again, or it was kept at the top of a descent while the camera
  /// stays at the height last verified on a clear view. Its height is then the one the user's feet
  /// stand on even where the treads below are nearer the user than the floor seen beside them.
  bool floor_tracked = false;
  /// m, the camera's height above the user's feet as last measured on a floor that passed every
  /// check, while it is remembered (FloorConfig::track_forget_frames), also on frames where no
  /// floor is found; 0 when unknown. A property of the wearer, not of the place: with the floor
  /// out of view (at the foot of a staircase) it still says where the user's feet are.
  float remembered_camera_height = 0.f;
  int frames_since_floor = -1;  ///< frames since the floor was last found; -1 never (or forgotten)

  bool manhattan_found = false;
  std::string manhattan_why;                  ///< why no Manhattan frame (when !manhattan_found)
  Pose T_manhattan_floor = Pose::Identity();  ///< floor frame into Manhattan frame M (rotation about y)
  float manhattan_yaw = 0.f;                  ///< rad, angle of k_M from z_F about y_F
  float manhattan_fraction = 0.f;             ///< share of points on Manhattan-aligned vertical planes
  /// Camera into the upright frame (x left, y up, z forward, as F) the Manhattan yaw is measured
  /// about: T_floor_camera when the floor is found. With no floor found, a floor-like plane the
  /// floor's checks refused (it may be a tread or a seat: FloorEstimate::level_region) still gives
  /// the vertical: the frame is then measured about that plane's normal (manhattan_without_floor,
  /// T_upright_camera placed on that plane); the floor's fields stay unset.
  Pose T_upright_camera = Pose::Identity();
  bool manhattan_without_floor = false;
  /// The frame reported is the one held in the world from earlier views, carried by the odometry
  /// (Perception::apply_odometry): this view's own planes made none, or one that the held frame
  /// outweighs; manhattan_why says which.
  bool manhattan_carried = false;
  float manhattan_carried_age = 0.f;  ///< s since a view last saw the frame carried

  std::vector<PlaneRegion> regions;
  std::vector<ObstacleCluster> clusters;
  PerceptionTimings timings;
};

}  // namespace stairguide
