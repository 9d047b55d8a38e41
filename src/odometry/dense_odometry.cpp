// Dense RGB-D odometry with inverse depth (paper 5.1).
//
// Layout of the work, chosen for speed:
//  - Each frame is turned once into a pyramid of grey (float) and inverse-depth images, 2x2 box
//    reductions so that the pixel-centre convention matches CameraIntrinsics::scaled().
//  - The previous frame (A, the reference) is turned once into per-level point lists: 3D point,
//    I_A, W_A and the two 6-vector Jacobians of eq. 10 and 11. They depend on A only (the
//    linearisation of the paper uses A's gradients), so an iteration only has to warp, sample B
//    and accumulate. Lists are structure-of-arrays, padded to a multiple of 8 with zeros.
//  - An iteration walks the list in blocks of kBlock points: a scalar pass warps and samples B
//    (gathers do not vectorise), then the 6x6 normal equations are summed over the block with
//    8 independent lanes, which the compiler turns into SIMD without -ffast-math.
//  - Everything runs on the calling thread: the stage is pure (threads live in src/runtime), and
//    a helper thread over image rows measured no gain.
// This file: set-up and tracking; the pyramid and the reference's points are in
// dense_odometry_pyramid.cpp, the accumulation pass in dense_odometry_accumulate.cpp.

// The per-pixel loops are written branch-free (selects instead of branches); GCC only turns
// such selects on float compares into SIMD when it may assume no floating-point traps, which
// nothing here relies on. Set before every include so that all inline functions of this unit
// share the option (GCC does not inline across differing optimize options).
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC optimize("no-trapping-math")
#endif
#include "stairguide/odometry/dense_odometry.hpp"

#include "dense_odometry_internal.hpp"

namespace stairguide {

const char* to_string(OdometryStatus s) {
  switch (s) {
    case OdometryStatus::kOk: return "ok";
    case OdometryStatus::kFirstFrame: return "first frame";
    case OdometryStatus::kBadInput: return "frame does not match the configured camera";
    case OdometryStatus::kTooFewPixels: return "too few valid pixels";
    case OdometryStatus::kDiverged: return "diverged";
    case OdometryStatus::kJump: return "jump beyond walking motion";
  }
  return "?";
}

void DenseOdometry::Impl::setup(const OdometryConfig& c, const CameraIntrinsics& k) {
  cfg = c;
  K0 = k;
  levels = std::clamp(c.pyramid_levels, 1, kMaxLevels);
  cfg.iterations = std::clamp(c.iterations, 1, 100);
  cfg.max_points_per_level = std::max(c.max_points_per_level, 100);
  // Do not go below ~20 px on a side.
  while (levels > 1 && ((K0.width >> (levels - 1)) < 20 || (K0.height >> (levels - 1)) < 20)) --levels;
  for (int l = 0; l < levels; ++l) {
    K[l] = K0.scaled(1.f / static_cast<float>(1 << l));
    K[l].width = K0.width >> l;
    K[l].height = K0.height >> l;
    int s = 1;
    while (static_cast<long>(K[l].width / s) * (K[l].height / s) > cfg.max_points_per_level) ++s;
    stride[l] = s;
    // An inverse-depth step spans 2^l full-resolution pixels at level l.
    edge_ratio[l] = cfg.max_inv_depth_step * static_cast<float>(1 << l);
  }
  sized = false;
  has_ref = false;
  forget_motion();
}

void DenseOdometry::Impl::forget_motion() {
  T_last_ref.setIdentity();
  velocity.setIdentity();
  velocity_dt = 0.0;
  has_last_timestamp = false;
  consecutive_failures = 0;
  prev_skipped = false;
}

void DenseOdometry::Impl::allocate() {
  for (auto& P : pyr) {
    P.levels = levels;
    for (int l = 0; l < levels; ++l) {
      P.I[l].resize(K[l].width, K[l].height);
      P.W[l].resize(K[l].width, K[l].height);
    }
  }
  gray_buf.create(K0.height, K0.width, CV_8UC1);  // so that a colour-only frame allocates nothing
  for (int l = 0; l < levels; ++l) {
    const int cap = (K[l].width / stride[l] + 1) * (K[l].height / stride[l] + 1);
    pts[l].reserve(cap);
  }
  sized = true;
}

DenseOdometry::Impl::Solve DenseOdometry::Impl::estimate(const Pyramid& cur, const Eigen::Isometry3d& G0) {
  Solve out;
  Eigen::Isometry3d G = G0;
  Accum acc;
  // Scales of the weights. The paper fixes them (sigma_I = 5, sigma_W = 0.0025); far from the
  // solution nearly every residual is then an "outlier" and the few that agree by chance steer
  // the step, which narrows the basin of convergence. With adaptive_scale the scales start at
  // the RMS of the initial residuals and follow the Student-t maximum-likelihood fixed point,
  // never going below the configured values: once aligned, the paper's fixed scales rule.
  double est_I = 0.0, est_W = 0.0;
  if (cfg.adaptive_scale) {
    const int l = levels - 1;
    const Eigen::Isometry3f Gf = G.cast<float>();
    accumulate(pts[l], cur.I[l], cur.W[l], K[l], edge_ratio[l], Gf, 1e6f, 1e6f, true, scratch, acc);
    if (acc.used > 0) {
      est_I = std::sqrt(acc.sum_rI2 / static_cast<double>(acc.used));
      est_W = std::sqrt(acc.sum_rW2 / static_cast<double>(acc.used));
    }
  }
  for (int l = levels - 1; l >= 0; --l) {
    const int npts = ref_points(l);
    const long min_used = std::max<long>(60, npts / 4);
    if (npts < 60) {
      if (l == 0) {
        out.status = OdometryStatus::kTooFewPixels;
        return out;
      }
      continue;  // a coarse level with almost nothing: let the finer ones work
    }
    bool level_converged = false;
    for (int it = 0; it < cfg.iterations; ++it) {
      const Eigen::Isometry3f Gf = G.cast<float>();
      const float sI = static_cast<float>(std::max<double>(cfg.sigma_intensity, est_I));
      const float sW = static_cast<float>(std::max<double>(cfg.sigma_inv_depth, est_W));
      accumulate(pts[l], cur.I[l], cur.W[l], K[l], edge_ratio[l], Gf, sI, sW, false, scratch, acc);
      out.last = acc;
      if (cfg.adaptive_scale && acc.used > 0) {
        est_I = std::sqrt(acc.sum_tI / static_cast<double>(acc.used));
        est_W = std::sqrt(acc.sum_tW / static_cast<double>(acc.used));
      }
      ++out.iterations;
      if (acc.used < min_used) {
        out.status = OdometryStatus::kTooFewPixels;
        return out;
      }
      const Eigen::LDLT<Mat6d> ldlt(acc.H);
      if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) {
        out.status = OdometryStatus::kDiverged;
        return out;
      }
      const Vec6d xi = -ldlt.solve(acc.g);
      if (!xi.allFinite()) {
        out.status = OdometryStatus::kDiverged;
        return out;
      }
      // Eq. 13: the increment maps A to the warped B; T_curr_ref <- T_curr_ref * (exp(theta), r).
      Eigen::Isometry3d D = Eigen::Isometry3d::Identity();
      D.linear() = rot_exp(xi.tail<3>());
      D.translation() = xi.head<3>();
      G = G * D;
      if (xi.head<3>().norm() < cfg.min_update_translation && xi.tail<3>().norm() < cfg.min_update_rotation) {
        level_converged = true;
        break;
      }
    }
    if (l == 0) out.converged = level_converged;
  }
  // Re-orthonormalise (products of many float-built rotations drift slightly).
  const Eigen::Quaterniond q(G.linear());
  G.linear() = q.normalized().toRotationMatrix();
  out.G = G;
  out.ok = true;
  return out;
}

Eigen::Isometry3d DenseOdometry::Impl::predicted_step(double timestamp) const {
  if (velocity_dt <= 0.0 || !has_last_timestamp) return velocity;
  const double dt = timestamp - last_timestamp;
  if (!(dt > 0.0)) return velocity;
  const double ratio = std::clamp(dt / velocity_dt, 0.0, 4.0);
  if (std::fabs(ratio - 1.0) < 0.2) return velocity;
  Eigen::Isometry3d V = Eigen::Isometry3d::Identity();
  V.linear() = rot_exp(rot_log(velocity.linear()) * ratio);
  V.translation() = velocity.translation() * ratio;
  return V;
}

OdometryResult DenseOdometry::Impl::track(const RgbdFrame& f) {
  OdometryResult res;
  const bool size_ok = f.depth.type() == CV_32FC1 && f.depth.cols == K0.width && f.depth.rows == K0.height;
  const cv::Mat* gray = nullptr;
  if (size_ok) {
    if (!f.gray.empty() && f.gray.type() == CV_8UC1 && f.gray.size() == f.depth.size()) {
      gray = &f.gray;
    } else if (!f.color.empty() && f.color.type() == CV_8UC3 && f.color.size() == f.depth.size()) {
      cv::cvtColor(f.color, gray_buf, cv::COLOR_BGR2GRAY);
      gray = &gray_buf;
    }
  }
  static const cv::Mat kNoGray;
  if (!sized && size_ok) allocate();

  const Eigen::Isometry3d step = predicted_step(f.timestamp);
  auto fail = [&](OdometryStatus st, bool frame_usable) {
    res.ok = false;
    res.status = st;
    res.why = to_string(st);
    res.T_prev_curr = step.inverse().cast<float>();
    T_world_camera = T_world_camera * res.T_prev_curr;
    res.T_world_camera = T_world_camera;
    res.consecutive_failures = ++consecutive_failures;
    if (frame_usable) {
      // The frame has data: it becomes the reference, at the guessed pose.
      build_reference(pyr[1 - ref]);
      ref = 1 - ref;
      has_ref = true;
      T_last_ref.setIdentity();
      prev_skipped = false;
    } else {
      // Keep the old reference and remember where the guess put this frame relative to it.
      T_last_ref = step * T_last_ref;
      prev_skipped = true;
    }
    last_timestamp = f.timestamp;
    has_last_timestamp = true;
    return res;
  };

  if (!size_ok) return fail(OdometryStatus::kBadInput, false);
  Pyramid& cur = pyr[1 - ref];
  build_pyramid(gray ? *gray : kNoGray, f.depth, cur);
  const int min_valid = static_cast<int>(cfg.min_valid_fraction * static_cast<float>(K0.width * K0.height));
  const bool cur_usable = cur.valid0 >= std::max(min_valid, 1);

  if (!has_ref) {
    if (!cur_usable) return fail(OdometryStatus::kTooFewPixels, false);
    build_reference(cur);
    ref = 1 - ref;
    has_ref = true;
    T_last_ref.setIdentity();
    res.ok = true;
    res.status = OdometryStatus::kFirstFrame;
    res.T_world_camera = T_world_camera;
    res.converged = true;
    last_timestamp = f.timestamp;
    has_last_timestamp = true;
    consecutive_failures = 0;
    return res;
  }
  if (!cur_usable) return fail(OdometryStatus::kTooFewPixels, false);
  if (pyr[ref].valid0 < std::max(min_valid, 1)) return fail(OdometryStatus::kTooFewPixels, true);

  // Initial T_curr_ref: the constant-velocity step after the last output frame.
  const Solve s = estimate(cur, step * T_last_ref);
  if (!s.ok) return fail(s.status, true);
  const Eigen::Isometry3d T_prev_curr = T_last_ref * s.G.inverse();
  const double trans = T_prev_curr.translation().norm();
  const double rot = Eigen::AngleAxisd(T_prev_curr.linear()).angle();
  res.iterations = s.iterations;
  res.pixels_used = static_cast<int>(s.last.used);
  res.inlier_fraction =
      s.last.used > 0 ? static_cast<float>(s.last.inliers) / static_cast<float>(s.last.used) : 0.f;
  res.residual = s.last.sum_w > 0 ? static_cast<float>(std::sqrt(s.last.sum_wx2 / s.last.sum_w)) : 0.f;
  res.photometric_rms = s.last.used > 0 ? static_cast<float>(std::sqrt(s.last.sum_rI2 / s.last.used)) : 0.f;
  res.inv_depth_rms = s.last.used > 0 ? static_cast<float>(std::sqrt(s.last.sum_rW2 / s.last.used)) : 0.f;
  res.converged = s.converged;
  // A failure keeps the figures of the solve just made (fail() changes only the outcome and the pose).
  if (res.inlier_fraction < cfg.min_inlier_fraction) return fail(OdometryStatus::kDiverged, true);
  if (trans > cfg.max_translation || rot > cfg.max_rotation) return fail(OdometryStatus::kJump, true);

  // Information of the perturbation: xi acts on the right of T_curr_ref, i.e. on the left of
  // T_ref_curr in the reference frame; with a skipped frame the reference frame is not the
  // previous one, so the information is carried over by the adjoint of T_last_ref.
  Mat6d info = s.last.H;
  if (!T_last_ref.matrix().isIdentity(1e-12)) {
    // Adjoint of T = (R, p) for (translation, rotation) ordering: [[R, [p]x R], [0, R]].
    const Eigen::Matrix3d R = T_last_ref.linear();
    const Eigen::Vector3d p = T_last_ref.translation();
    Eigen::Matrix3d px;
    px << 0, -p.z(), p.y(), p.z(), 0, -p.x(), -p.y(), p.x(), 0;
    Mat6d Ad = Mat6d::Zero();
    Ad.topLeftCorner<3, 3>() = R;
    Ad.topRightCorner<3, 3>() = px * R;
    Ad.bottomRightCorner<3, 3>() = R;
    const Mat6d Ainv = Ad.inverse();
    info = Ainv.transpose() * info * Ainv;
  }
  res.information = info.cast<float>();
  res.ok = true;
  res.status = OdometryStatus::kOk;
  res.T_prev_curr = T_prev_curr.cast<float>();
  T_world_camera = T_world_camera * res.T_prev_curr;
  {
    // Keep the accumulated rotation orthonormal over long runs.
    const Eigen::Quaternionf q(T_world_camera.linear());
    T_world_camera.linear() = q.normalized().toRotationMatrix();
  }
  res.T_world_camera = T_world_camera;
  consecutive_failures = 0;

  // Velocity for the next frame; its time span when timestamps are usable.
  velocity = T_prev_curr.inverse();
  const double dt = f.timestamp - last_timestamp;
  velocity_dt = (has_last_timestamp && dt > 0.0 && !prev_skipped) ? dt : 0.0;
  last_timestamp = f.timestamp;
  has_last_timestamp = true;
  prev_skipped = false;

  // Keyframe policy: keep tracking against the same reference while it is close and still
  // overlaps well. Each frame-to-frame estimate carries a bias toward zero motion (the sensor's
  // fixed-pattern depth noise and the camera's vignetting stay put in the image and pull the
  // alignment toward identity), and chaining one estimate per frame adds that bias up; against
  // a keyframe it is paid once per keyframe instead.
  const double ref_trans = s.G.translation().norm();
  const double ref_rot = Eigen::AngleAxisd(s.G.linear()).angle();
  const double overlap = ref_points(0) > 0 ? static_cast<double>(s.last.used) / ref_points(0) : 0.0;
  const bool keep = cfg.keyframe_max_translation > 0.f && ref_trans < cfg.keyframe_max_translation &&
                    ref_rot < cfg.keyframe_max_rotation && overlap >= cfg.keyframe_min_overlap;
  if (keep) {
    T_last_ref = s.G;
  } else {
    build_reference(cur);
    ref = 1 - ref;
    T_last_ref.setIdentity();
  }
  return res;
}

DenseOdometry::DenseOdometry() : impl_(std::make_unique<Impl>()) {
  impl_->setup(OdometryConfig{}, CameraIntrinsics{});
}

DenseOdometry::DenseOdometry(const OdometryConfig& config, const CameraIntrinsics& intrinsics)
    : impl_(std::make_unique<Impl>()) {
  impl_->setup(config, intrinsics);
}

DenseOdometry::~DenseOdometry() = default;

void DenseOdometry::configure(const OdometryConfig& config, const CameraIntrinsics& intrinsics) {
  const Pose keep = impl_->T_world_camera;
  impl_->setup(config, intrinsics);
  impl_->T_world_camera = keep;
}

OdometryResult DenseOdometry::track(const RgbdFrame& frame) { return impl_->track(frame); }

void DenseOdometry::reset(const Pose& T_world_camera) {
  impl_->has_ref = false;
  impl_->forget_motion();
  impl_->T_world_camera = T_world_camera;
}

const Pose& DenseOdometry::pose() const { return impl_->T_world_camera; }

}  // namespace stairguide
