#pragma once
/// \file dense_odometry.hpp
/// Frame-to-frame dense RGB-D visual odometry with inverse depth (Perez-Yus et al. 2017, section
/// 5.1, after Gutierrez-Gomez et al.): photometric (eq. 10) and inverse-depth (eq. 11) residuals
/// minimised jointly by iteratively reweighted least squares with Student-t weights, coarse to
/// fine over an image pyramid, the SE(3) update of eq. 13, constant-velocity initialisation.
///
/// Each frame is tracked against a reference (keyframe) that is kept while the camera stays within
/// OdometryConfig::keyframe_max_translation / keyframe_max_rotation of it and it still overlaps
/// (keyframe_min_overlap); keyframe_max_translation = 0 gives pure frame-to-frame tracking.
///
/// The stage is pure: it runs on the calling thread only (no threads of its own), no logging, no
/// I/O, no exceptions on the per-frame path. After the first frame of a given size, `track()`
/// allocates nothing.

#include <Eigen/Core>
#include <memory>

#include "stairguide/core/config.hpp"
#include "stairguide/core/types.hpp"

namespace stairguide {

/// Why a frame's estimate is not trusted (or kOk).
enum class OdometryStatus {
  kOk,            ///< estimated and plausible
  kFirstFrame,    ///< no previous frame: pose is the start pose (ok = true)
  kBadInput,      ///< the frame's size or type does not match the configured camera
  kTooFewPixels,  ///< too few pixels with depth (in either frame, or in their overlap)
  kDiverged,      ///< the solver failed, the cost grew, or too few residuals agree (inliers)
  kJump           ///< the estimate moves more than a walking person can between two frames
};

/// Short fixed text for a status ("ok", "too few valid pixels", ...).
const char* to_string(OdometryStatus s);

/// Per-frame output of DenseOdometry::track().
struct OdometryResult {
  /// True when the estimate was measured and passed every check (also for the first frame).
  /// False: the pose is the constant-velocity guess, `status`/`why` say why.
  bool ok = false;
  OdometryStatus status = OdometryStatus::kOk;
  const char* why = "";                    ///< static text, "" when ok (never freed, never allocated)
  Pose T_prev_curr = Pose::Identity();     ///< maps current-camera points into the previous camera
  Pose T_world_camera = Pose::Identity();  ///< C0 -> Ck: current camera into the first camera
  bool converged = false;                  ///< the last update at the finest level fell below the thresholds
  int pixels_used = 0;                     ///< residual pairs in the last finest-level iteration
  int iterations = 0;                      ///< Gauss-Newton iterations over all levels
  float residual = 0.f;                    ///< weighted RMS of the normalised residuals r/sigma (both terms)
  float photometric_rms = 0.f;             ///< grey levels, RMS over the used pixels (unweighted)
  float inv_depth_rms = 0.f;               ///< 1/m, RMS over the used pixels (unweighted)
  float inlier_fraction = 0.f;             ///< share of used pixels whose residuals are both within 3 sigma
  /// Gauss-Newton information (sum of w J^T J / sigma^2) of the relative motion at the final
  /// iteration, order (tx, ty, tz, rx, ry, rz) in m and rad, for a perturbation applied on the
  /// left of T_prev_curr (expressed in the previous camera's frame). Zero when !ok.
  Eigen::Matrix<float, 6, 6> information = Eigen::Matrix<float, 6, 6>::Zero();
  int consecutive_failures = 0;  ///< frames in a row with ok == false, this one included
};

/// Dense RGB-D odometry, one instance per camera stream. Not thread-safe.
class DenseOdometry {
 public:
  DenseOdometry();
  DenseOdometry(const OdometryConfig& config, const CameraIntrinsics& intrinsics);
  ~DenseOdometry();
  DenseOdometry(const DenseOdometry&) = delete;
  DenseOdometry& operator=(const DenseOdometry&) = delete;

  /// Sets the configuration and the camera; forgets the previous frame (next track() is a first
  /// frame). Out-of-range values are clamped to the ranges documented in OdometryConfig.
  void configure(const OdometryConfig& config, const CameraIntrinsics& intrinsics);

  /// Tracks `frame` against the previous one. `frame.depth` is CV_32FC1 metres (0 = no reading);
  /// the grey image is `frame.gray` (CV_8UC1) when set, else converted from `frame.color` (BGR);
  /// with neither, only the inverse-depth term is used. The frame's size must be the configured
  /// intrinsics' size.
  OdometryResult track(const RgbdFrame& frame);

  /// Forgets the previous frame and the velocity; the next frame starts at `T_world_camera`.
  void reset(const Pose& T_world_camera = Pose::Identity());

  /// Current accumulated pose C0 -> Ck.
  const Pose& pose() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace stairguide
