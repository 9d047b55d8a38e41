#pragma once
/// \file trajectory.hpp
/// The chest-mounted camera: mounting (height, tilt, roll), and walking trajectories with bob and
/// sway, sampled at the frame rate.

#include <functional>
#include <vector>

#include "stairguide/core/types.hpp"

namespace stairguide::synth {

/// World pose of a camera at `position` looking along heading `yaw` (rad, from world +x towards
/// +y), pitched down by `tilt` (rad below horizontal) and rolled by `roll` (rad, about the
/// optical axis; positive turns the image clockwise as seen by the camera).
Pose camera_pose(const Eigen::Vector3f& position, float yaw, float tilt, float roll);

/// Tilt (rad below horizontal) and roll (rad) of a camera pose, inverse of camera_pose.
float pose_tilt(const Pose& T_world_camera);
float pose_roll(const Pose& T_world_camera);

/// State of the walker at one instant.
struct WalkerState {
  Pose T_world_camera = Pose::Identity();
  Eigen::Vector3f body{0.f, 0.f, 0.f};  ///< ground point under the user's body (world, z = support)
  float yaw = 0.f;                      ///< rad, heading of the torso
  float support_z = 0.f;                ///< m, world height of the surface the user stands on
};

/// A walk along a straight line (world +x from `start`) with a heading that may turn.
/// Distance along the line, heading offset and the ground profile are functions of time or
/// distance; the walk adds bob (vertical, at step frequency, scaled by speed) and sway (lateral
/// and roll, at stride frequency).
struct WalkSpec {
  Eigen::Vector3f start{0.f, 0.f, 0.f};
  float duration_s = 20.f;
  float camera_height_m = 1.3f;  ///< above the support surface
  float tilt_rad = deg2rad(45.f);
  float roll_rad = 0.f;
  float chest_forward_m = 0.12f;  ///< camera ahead of the body's ground point
  float bob_amplitude_m = 0.01f;  ///< half of peak-to-peak (~2 cm p-p)
  float sway_amplitude_m = 0.015f;
  float step_length_m = 0.55f;                   ///< on level ground
  std::function<float(double t)> distance;       ///< m along +x at time t
  std::function<float(double t)> heading;        ///< rad, heading at time t
  std::function<float(float s)> support_step;    ///< exact surface height under body at distance s
  std::function<float(float s)> support_smooth;  ///< height the chest follows (smooth over steps)
  std::function<float(float s)> stride_length;   ///< m per step at distance s (tread on stairs)
};

/// Precomputed samples of a WalkSpec at `fps`; frames past the end hold the final pose
/// (the user stands, breathing sway only).
class Walk {
 public:
  Walk() = default;
  Walk(const WalkSpec& spec, double fps, long frames);
  WalkerState at(long frame) const;
  long frames() const { return static_cast<long>(states_.size()); }

 private:
  std::vector<WalkerState> states_;
};

/// Smooth 0->1 ramp (quintic smootherstep) of x over [a, b].
float smooth_ramp(float x, float a, float b);

}  // namespace stairguide::synth
