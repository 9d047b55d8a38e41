#pragma once
/// \file floor_detection.hpp
/// Camera-to-floor transform (paper 3.2.1). The floor is chosen among the planar regions:
///  - its normal must fit a chest camera: tilt (optical axis below horizontal) within
///    [tilt_min, tilt_max] and |roll| <= roll_max;
///  - the camera must be height_min..height_max above it;
///  - it must be near the user: the search window on z_C starts at search_start and grows by
///    search_step up to search_max; the first window in which some candidate has min_area of
///    footprint wins, and among the candidates the one with the largest footprint in it.
/// Tracking: once a floor is known, a candidate within track_max_height_jump and
/// track_max_angle_jump of it is preferred, so that the first step (nearer than the floor when the
/// user stands in front of it) never replaces the floor. Candidates parallel to the floor and
/// higher (nearer the camera) are never taken while the tracked floor is still in view.

#include <optional>
#include <string>
#include <vector>

#include "stairguide/core/config.hpp"
#include "stairguide/core/types.hpp"
#include "stairguide/perception/scene.hpp"

namespace stairguide {

/// The floor found in one frame.
struct FloorEstimate {
  bool found = false;
  std::string why;                    ///< when !found
  int region = -1;                    ///< index of the floor region
  bool tracked = false;               ///< chosen by agreement with the previous frame's floor
  Eigen::Vector3f normal = -Eigen::Vector3f::UnitY();  ///< floor up direction, camera frame
  float offset = 0.f;                 ///< n.p + offset = 0 for floor points; = camera height
  float height = 0.f;                 ///< m
  float tilt = 0.f;                   ///< rad
  float roll = 0.f;                   ///< rad
  Pose T_floor_camera = Pose::Identity();
};

/// Floor frame from a floor plane seen by the camera: y_F along `up` (unit, camera frame), z_F
/// the optical axis projected on the floor, x_F = y_F x z_F (left), origin under the camera.
Pose floor_pose_from_plane(const Eigen::Vector3f& up, float camera_height);
/// Tilt (optical axis below horizontal) and roll of a camera seeing floor `up` (camera frame), with
/// the synthetic world's convention: roll = atan2(-up_x, -up_y).
void tilt_roll_from_up(const Eigen::Vector3f& up, float& tilt, float& roll);

class FloorDetector {
 public:
  explicit FloorDetector(const FloorConfig& config = {});

  /// Chooses the floor among `regions` (from Segmentation on `frame`).
  FloorEstimate detect(const std::vector<PlaneRegion>& regions, const RgbdFrame& frame);
  /// Forgets the tracked floor (a new sequence).
  void reset() { prev_.reset(); }
  const FloorConfig& config() const { return cfg_; }

 private:
  FloorConfig cfg_;
  struct Prev {
    Eigen::Vector3f normal;
    float offset;
  };
  std::optional<Prev> prev_;
  std::vector<float> window_area_;
};

}  // namespace stairguide
