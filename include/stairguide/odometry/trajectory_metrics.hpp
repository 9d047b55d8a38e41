#pragma once
/// \file trajectory_metrics.hpp
/// Odometry accuracy against ground truth, as in the TUM RGB-D benchmark (Sturm et al. 2012):
/// relative pose error (RPE) over a fixed time span and absolute trajectory error (ATE) after a
/// rigid alignment. Pure functions; the estimate and the truth may use different world frames.

#include <cstddef>
#include <vector>

#include "stairguide/core/types.hpp"

namespace stairguide {

/// One timestamped camera pose (T_world_camera).
struct StampedPose {
  double timestamp = 0.0;  ///< s
  Pose T_world_camera = Pose::Identity();
};

/// Sums behind an RMSE, so that several sequences can be pooled.
struct ErrorSums {
  double sum_sq = 0.0;  ///< sum of squared errors
  std::size_t count = 0;
  double rmse() const;  ///< 0 when count == 0
  ErrorSums& operator+=(const ErrorSums& o);
};

/// RPE over `delta_s`: for every estimated pose i, the pose j nearest to t_i + delta_s (within
/// `max_dt` of it), E = (G_i^-1 G_j)^-1 (P_i^-1 P_j); translation |t(E)| / (t_j - t_i) in m/s and
/// rotation angle(E) / (t_j - t_i) in deg/s. `estimate` and `truth` are index-aligned (same frames).
struct RpeResult {
  ErrorSums translation_m_s;
  ErrorSums rotation_deg_s;
};
RpeResult relative_pose_error(const std::vector<StampedPose>& estimate, const std::vector<StampedPose>& truth,
                              double delta_s = 1.0, double max_dt = 0.02);

/// ATE: positions of `estimate` rigidly aligned to `truth` (rotation + translation, no scale:
/// Horn/Umeyama), RMSE of the remaining position differences in metres. Index-aligned inputs;
/// fewer than 3 poses give count 0.
ErrorSums absolute_trajectory_error(const std::vector<StampedPose>& estimate,
                                    const std::vector<StampedPose>& truth);

/// Median and 95th percentile of `values` (copied); 0 for an empty list.
double percentile(std::vector<double> values, double p);

}  // namespace stairguide
