// The chest camera and the walker. Gait is modelled as what a chest-mounted camera feels: a
// vertical bob at step frequency, a lateral sway and roll at stride frequency (half the step
// frequency), a little pitch nod, all scaled by walking speed; standing still leaves a small
// breathing sway. Samples are integrated at 10x the frame rate so the gait phase follows the
// distance walked even when the step length changes (treads on stairs).
#include "stairguide/synth/trajectory.hpp"

#include <algorithm>
#include <cmath>

namespace stairguide::synth {

Pose camera_pose(const Eigen::Vector3f& position, float yaw, float tilt, float roll) {
  // Level camera looking along the heading: z forward, x right, y down.
  const Eigen::Vector3f z(std::cos(yaw), std::sin(yaw), 0.f);
  const Eigen::Vector3f x(std::sin(yaw), -std::cos(yaw), 0.f);
  const Eigen::Vector3f y = z.cross(x);
  Eigen::Matrix3f R_level;
  R_level.col(0) = x;
  R_level.col(1) = y;
  R_level.col(2) = z;
  const Eigen::Matrix3f R = R_level * Eigen::AngleAxisf(-tilt, Eigen::Vector3f::UnitX()).toRotationMatrix() *
                            Eigen::AngleAxisf(roll, Eigen::Vector3f::UnitZ()).toRotationMatrix();
  Pose T = Pose::Identity();
  T.linear() = R;
  T.translation() = position;
  return T;
}

float pose_tilt(const Pose& T) { return std::asin(std::clamp(-T.linear()(2, 2), -1.f, 1.f)); }
float pose_roll(const Pose& T) { return std::atan2(-T.linear()(2, 0), -T.linear()(2, 1)); }

float smooth_ramp(float x, float a, float b) {
  if (b <= a) return x >= b ? 1.f : 0.f;
  const float t = std::clamp((x - a) / (b - a), 0.f, 1.f);
  return t * t * t * (t * (t * 6.f - 15.f) + 10.f);
}

Walk::Walk(const WalkSpec& spec, double fps, long frames) {
  const int sub = 10;
  const double dt = 1.0 / (fps * sub);
  const long n_live = std::max<long>(1, static_cast<long>(spec.duration_s * fps));
  states_.reserve(static_cast<std::size_t>(std::max(frames, 1L)));
  double phase = 0.0;  // steps taken
  float s_prev = spec.distance(0.0);
  float speed = 0.f;
  for (long f = 0; f < std::max(frames, 1L); ++f) {
    const double t_frame = static_cast<double>(std::min(f, n_live - 1)) / fps;
    const double t_breath = static_cast<double>(f) / fps;
    if (f > 0 && f < n_live) {
      for (int k = 1; k <= sub; ++k) {
        const double t = t_frame - 1.0 / fps + k * dt;
        const float s = spec.distance(t);
        const float ds = s - s_prev;
        phase +=
            std::abs(ds) / std::max(0.1f, spec.stride_length ? spec.stride_length(s) : spec.step_length_m);
        s_prev = s;
      }
      speed = std::abs(spec.distance(t_frame) - spec.distance(t_frame - 1.0 / fps)) * static_cast<float>(fps);
    } else if (f >= n_live) {
      speed = 0.f;
    }
    const float s = spec.distance(t_frame);
    const float yaw = spec.heading(t_frame);
    const float gait = std::clamp(speed / 0.5f, 0.f, 1.f);
    const float two_pi = 6.2831853f;
    const float ph = static_cast<float>(phase);
    const float breath = static_cast<float>(std::sin(two_pi * 0.25 * t_breath));
    const float bob = gait * spec.bob_amplitude_m * -std::cos(two_pi * ph) + 0.002f * breath;
    const float sway = gait * spec.sway_amplitude_m * std::sin(0.5f * two_pi * ph) + 0.003f * breath;
    const float roll = spec.roll_rad + gait * deg2rad(1.5f) * std::sin(0.5f * two_pi * ph + 0.3f);
    const float tilt = spec.tilt_rad + gait * deg2rad(1.0f) * std::sin(two_pi * ph + 0.8f);
    const float yaw_wobble = gait * deg2rad(1.5f) * std::sin(0.5f * two_pi * ph + 1.1f);

    WalkerState st;
    const Eigen::Vector3f fwd(std::cos(yaw), std::sin(yaw), 0.f);
    const Eigen::Vector3f left(-std::sin(yaw), std::cos(yaw), 0.f);
    st.yaw = yaw;
    st.support_z = spec.support_step(s);
    st.body = spec.start + Eigen::Vector3f(s, 0.f, 0.f);
    st.body.z() = spec.start.z() + st.support_z;
    Eigen::Vector3f cam =
        spec.start + Eigen::Vector3f(s, 0.f, 0.f) + spec.chest_forward_m * fwd + sway * left;
    cam.z() = spec.start.z() + spec.support_smooth(s) + spec.camera_height_m + bob;
    st.support_z += spec.start.z();
    st.T_world_camera = camera_pose(cam, yaw + yaw_wobble, tilt, roll);
    states_.push_back(st);
  }
}

WalkerState Walk::at(long frame) const {
  if (states_.empty()) return {};
  const long i = std::clamp(frame, 0L, static_cast<long>(states_.size()) - 1);
  return states_[static_cast<std::size_t>(i)];
}

}  // namespace stairguide::synth
