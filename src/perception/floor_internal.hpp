#pragma once
// Small geometric helpers shared by the floor detector's files (floor_detection.cpp, floor_tread_checks.cpp).
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

#include <Eigen/Core>

namespace stairguide::floor_detail {

// Horizontal distance from the camera's foot (the camera projected on the plane along `up`).
inline float foot_distance(const Eigen::Vector3f& up, const Eigen::Vector3f& q) {
  const float np = up.dot(q);
  return std::sqrt(std::max(0.f, q.squaredNorm() - np * np));
}
// Tangent of the angle between the ray to q and the nadir (-up): how near the user's feet the
// camera sees q, independent of how high q is. Points level with or above the camera: +inf.
inline float nadir_tan(const Eigen::Vector3f& up, const Eigen::Vector3f& q) {
  const float below = -up.dot(q);
  if (below <= 1e-3f) return 1e9f;
  return foot_distance(up, q) / below;
}
inline float median(std::vector<float>& v) {
  std::nth_element(v.begin(), v.begin() + static_cast<long>(v.size() / 2), v.end());
  return v[v.size() / 2];
}
inline float percentile(std::vector<float>& v, std::size_t per_mille) {
  if (v.empty()) return 1e9f;
  const std::size_t k = v.size() * per_mille / 1000;
  std::nth_element(v.begin(), v.begin() + static_cast<long>(k), v.end());
  return v[k];
}

}  // namespace stairguide::floor_detail
