#pragma once
// Measures of the Manhattan frame shared by test_perception and test_walk_manhattan.
#include <cmath>
#include <vector>

#include <Eigen/Geometry>

#include "stairguide/core/ground_truth.hpp"
#include "stairguide/perception/scene.hpp"

namespace sg_test {

constexpr float kManhattanDeg = 3.14159265358979f / 180.f;

/// Wraps an angle (rad) to (-45, 45] degrees: a direction modulo 90 degrees.
inline float wrap45(float a) {
  const float q = 90.f * kManhattanDeg;
  while (a > 0.5f * q) a -= q;
  while (a <= -0.5f * q) a += q;
  return a;
}

/// Yaw error (degrees) of the reported k_M against the world's axes or any staircase's, modulo 90
/// degrees (a staircase may be turned against the room); < 0 when no frame is reported. The frame
/// is measured about its own upright frame (the floor's, or a floor-like plane's without a floor).
inline float manhattan_yaw_error_deg(const stairguide::SceneResult& sc, const stairguide::FrameTruth& truth) {
  if (!sc.manhattan_found) return -1.f;
  const Eigen::Matrix3f Rwc = truth.T_world_camera.linear();
  const Eigen::Vector3f kF(std::sin(sc.manhattan_yaw), 0.f, std::cos(sc.manhattan_yaw));
  const Eigen::Vector3f kW = Rwc * (sc.T_upright_camera.linear().transpose() * kF);
  float err = std::fabs(wrap45(std::atan2(kW.y(), kW.x())));
  for (const stairguide::StairTruth& st : truth.stairs) {
    const Eigen::Vector3f zs = Rwc * st.T_camera_stair.linear().col(2);
    err = std::min(err, std::fabs(wrap45(std::atan2(kW.y(), kW.x()) - std::atan2(zs.y(), zs.x()))));
  }
  return err / kManhattanDeg;
}

/// Views of a still world: k_M and the floor's up carried into the world by each view's pose.
struct WorldManhattan {
  std::vector<Eigen::Vector3f> k, up;
  /// Adds a view's frame, `R_wc` being its camera's orientation in the world.
  void add(const stairguide::SceneResult& sc, const Eigen::Matrix3f& R_wc) {
    const Eigen::Matrix3f R_cf = sc.T_upright_camera.linear().transpose();  // upright (floor) into camera
    k.push_back(R_wc * (R_cf * Eigen::Vector3f(std::sin(sc.manhattan_yaw), 0.f, std::cos(sc.manhattan_yaw))));
    up.push_back(R_wc * (R_cf * Eigen::Vector3f::UnitY()));
  }
  /// Each view's yaw (rad) about the views' mean vertical, from a fixed horizontal axis.
  std::vector<float> yaws() const {
    Eigen::Vector3f u = Eigen::Vector3f::Zero();
    for (const auto& v : up) u += v;
    u.normalize();
    Eigen::Vector3f e = Eigen::Vector3f::UnitX() - u * u.x();
    if (e.norm() < 0.1f) e = Eigen::Vector3f::UnitZ() - u * u.z();
    e.normalize();
    const Eigen::Vector3f e2 = u.cross(e);
    std::vector<float> out;
    for (const auto& v : k) out.push_back(std::atan2(e2.dot(v), e.dot(v)));
    return out;
  }
  /// The views' mean yaw modulo 90 degrees (circular mean of 4 * yaw), rad.
  float mean_yaw() const {
    float c = 0.f, s = 0.f;
    for (const float a : yaws()) {
      c += std::cos(4.f * a);
      s += std::sin(4.f * a);
    }
    return 0.25f * std::atan2(s, c);
  }
};

}  // namespace sg_test
