#include "stairguide/odometry/trajectory_metrics.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace stairguide {

double ErrorSums::rmse() const { return count ? std::sqrt(sum_sq / static_cast<double>(count)) : 0.0; }

ErrorSums& ErrorSums::operator+=(const ErrorSums& o) {
  sum_sq += o.sum_sq;
  count += o.count;
  return *this;
}

RpeResult relative_pose_error(const std::vector<StampedPose>& estimate, const std::vector<StampedPose>& truth,
                              double delta_s, double max_dt) {
  RpeResult r;
  const std::size_t n = std::min(estimate.size(), truth.size());
  std::size_t j = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double target = estimate[i].timestamp + delta_s;
    // Timestamps increase: the partner of i+1 is never before the partner of i.
    j = std::max(j, i + 1);
    while (j + 1 < n &&
           std::fabs(estimate[j + 1].timestamp - target) <= std::fabs(estimate[j].timestamp - target))
      ++j;
    if (j >= n || std::fabs(estimate[j].timestamp - target) > max_dt) continue;
    const double dt = estimate[j].timestamp - estimate[i].timestamp;
    if (!(dt > 0.0)) continue;
    const Eigen::Isometry3d P =
        (estimate[i].T_world_camera.inverse() * estimate[j].T_world_camera).cast<double>();
    const Eigen::Isometry3d G = (truth[i].T_world_camera.inverse() * truth[j].T_world_camera).cast<double>();
    const Eigen::Isometry3d E = G.inverse() * P;
    const double t = E.translation().norm() / dt;
    const double a = Eigen::AngleAxisd(E.linear()).angle() * 180.0 / M_PI / dt;
    r.translation_m_s.sum_sq += t * t;
    r.translation_m_s.count += 1;
    r.rotation_deg_s.sum_sq += a * a;
    r.rotation_deg_s.count += 1;
  }
  return r;
}

ErrorSums absolute_trajectory_error(const std::vector<StampedPose>& estimate,
                                    const std::vector<StampedPose>& truth) {
  ErrorSums s;
  const std::size_t n = std::min(estimate.size(), truth.size());
  if (n < 3) return s;
  Eigen::Matrix3Xd src(3, n), dst(3, n);
  for (std::size_t i = 0; i < n; ++i) {
    src.col(static_cast<Eigen::Index>(i)) = estimate[i].T_world_camera.translation().cast<double>();
    dst.col(static_cast<Eigen::Index>(i)) = truth[i].T_world_camera.translation().cast<double>();
  }
  // Rigid alignment (no scale): an RGB-D odometry has metric scale.
  const Eigen::Matrix4d A = Eigen::umeyama(src, dst, false);
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d p =
        A.topLeftCorner<3, 3>() * src.col(static_cast<Eigen::Index>(i)) + A.topRightCorner<3, 1>();
    s.sum_sq += (p - dst.col(static_cast<Eigen::Index>(i))).squaredNorm();
    s.count += 1;
  }
  return s;
}

double percentile(std::vector<double> values, double p) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const double pos = std::clamp(p, 0.0, 1.0) * static_cast<double>(values.size() - 1);
  const std::size_t lo = static_cast<std::size_t>(std::floor(pos));
  const std::size_t hi = std::min(lo + 1, values.size() - 1);
  const double f = pos - static_cast<double>(lo);
  return values[lo] * (1.0 - f) + values[hi] * f;
}

}  // namespace stairguide
