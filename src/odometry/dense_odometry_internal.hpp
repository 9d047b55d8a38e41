#pragma once
// Internals of DenseOdometry shared by its .cpp files (not part of the public API): the image
// pyramid, the reference's point lists, the accumulation's scratch and sums, and
// DenseOdometry::Impl, whose members are defined by phase: dense_odometry.cpp (set-up and
// tracking: the Gauss-Newton iterations over the levels, the motion prior),
// dense_odometry_pyramid.cpp (each frame's pyramid and the reference's points),
// dense_odometry_accumulate.cpp (one pass of residuals, weights and normal equations).
// Every file that includes this one sets the same optimize option first (see dense_odometry.cpp).
#include "stairguide/odometry/dense_odometry.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <opencv2/imgproc.hpp>
#include <vector>

namespace stairguide::dense_odometry_detail {

constexpr int kMaxLevels = 6;
constexpr int kBlock = 256;  // points per accumulation block (its scratch stays in L1)

using Mat6d = Eigen::Matrix<double, 6, 6>;
using Vec6d = Eigen::Matrix<double, 6, 1>;

/// A float image, rows contiguous, stride == width.
struct Image {
  int w = 0, h = 0;
  std::vector<float> px;
  void resize(int width, int height) {
    w = width;
    h = height;
    px.resize(static_cast<std::size_t>(w) * static_cast<std::size_t>(h));
  }
  float* row(int y) { return px.data() + static_cast<std::ptrdiff_t>(y) * w; }
  const float* row(int y) const { return px.data() + static_cast<std::ptrdiff_t>(y) * w; }
};

struct Pyramid {
  int levels = 0;
  std::array<Image, kMaxLevels> I, W;
  int valid0 = 0;  // full-resolution pixels with depth
};

/// Points of the reference frame at one level, structure of arrays.
struct PointList {
  int n = 0;
  std::vector<float> x, y, z, ia, wa;
  std::array<std::vector<float>, 6> ji, jw;
  void reserve(int cap) {
    const std::size_t c = static_cast<std::size_t>(cap + 8);
    for (auto* v : {&x, &y, &z, &ia, &wa}) v->assign(c, 0.f);
    for (auto& v : ji) v.assign(c, 0.f);
    for (auto& v : jw) v.assign(c, 0.f);
  }
  std::size_t capacity() const { return x.size(); }
  /// Zeroes the padding after n up to the next multiple of 8, so block sums can run over it.
  void pad() {
    const int end = (n + 7) & ~7;
    for (int i = n; i < end; ++i) {
      x[i] = y[i] = ia[i] = wa[i] = 0.f;
      z[i] = 1.f;
      for (auto& v : ji) v[i] = 0.f;
      for (auto& v : jw) v[i] = 0.f;
    }
  }
};

/// Sums of one accumulation pass.
struct Accum {
  Mat6d H = Mat6d::Zero();
  Vec6d g = Vec6d::Zero();
  long used = 0, inliers = 0;
  double sum_wx2 = 0, sum_w = 0, sum_rI2 = 0, sum_rW2 = 0;
  double sum_tI = 0, sum_tW = 0;  // sum of (nu+1)/(nu+x^2) r^2: Student-t scale fixed point
  void clear() { *this = Accum(); }
};

/// Scratch of one block.
struct alignas(64) Scratch {
  alignas(64) float bx[kBlock], by[kBlock], bz[kBlock], fa[kBlock], fb[kBlock], valid[kBlock];
  alignas(64) int idx[kBlock];
  alignas(64) float iB[kBlock], wB[kBlock], inl[kBlock];
  alignas(64) float wI[kBlock], rI[kBlock], wW[kBlock], rW[kBlock];
  alignas(64) float aI[6][kBlock], aW[6][kBlock];
};

/// Sum over k < m (m a multiple of 8) of a*b + c*d (or of a*b*c with `triple`), in 8
/// independent lanes: the compiler vectorises it without reassociating float sums itself.
inline float dot2(const float* a, const float* b, const float* c, const float* d, int m, bool triple) {
  float acc[8] = {0, 0, 0, 0, 0, 0, 0, 0};
  if (triple) {
    for (int k = 0; k < m; k += 8)
      for (int l = 0; l < 8; ++l) acc[l] += a[k + l] * b[k + l] * c[k + l];
  } else {
    for (int k = 0; k < m; k += 8)
      for (int l = 0; l < 8; ++l) acc[l] += a[k + l] * b[k + l] + c[k + l] * d[k + l];
  }
  return ((acc[0] + acc[1]) + (acc[2] + acc[3])) + ((acc[4] + acc[5]) + (acc[6] + acc[7]));
}

inline float dot1(const float* a, const float* b, int m) {
  float acc[8] = {0, 0, 0, 0, 0, 0, 0, 0};
  for (int k = 0; k < m; k += 8)
    for (int l = 0; l < 8; ++l) acc[l] += a[k + l] * b[k + l];
  return ((acc[0] + acc[1]) + (acc[2] + acc[3])) + ((acc[4] + acc[5]) + (acc[6] + acc[7]));
}

inline float sum8(const float* a, int m) {
  float acc[8] = {0, 0, 0, 0, 0, 0, 0, 0};
  for (int k = 0; k < m; k += 8)
    for (int l = 0; l < 8; ++l) acc[l] += a[k + l];
  return ((acc[0] + acc[1]) + (acc[2] + acc[3])) + ((acc[4] + acc[5]) + (acc[6] + acc[7]));
}

/// Rotation vector -> rotation matrix (Rodrigues), exact also near zero.
inline Eigen::Matrix3d rot_exp(const Eigen::Vector3d& w) {
  const double a = w.norm();
  if (a < 1e-12) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(a, w / a).toRotationMatrix();
}

inline Eigen::Vector3d rot_log(const Eigen::Matrix3d& R) {
  const Eigen::AngleAxisd aa(R);
  return aa.axis() * aa.angle();
}

}  // namespace stairguide::dense_odometry_detail

namespace stairguide {

using namespace dense_odometry_detail;

struct DenseOdometry::Impl {
  OdometryConfig cfg;
  CameraIntrinsics K0;
  int levels = 3;
  std::array<CameraIntrinsics, kMaxLevels> K;
  std::array<int, kMaxLevels> stride{};
  std::array<float, kMaxLevels> edge_ratio{};  // max |dW| / W between neighbouring pixels

  Pyramid pyr[2];
  int ref = 0;  // index of the reference pyramid; the current frame goes into 1 - ref
  std::array<PointList, kMaxLevels> pts;
  bool has_ref = false;
  bool sized = false;

  cv::Mat gray_buf;  // colour -> grey conversion target, reused

  Pose T_world_camera = Pose::Identity();
  Eigen::Isometry3d T_last_ref = Eigen::Isometry3d::Identity();  // last output frame <- reference
  Eigen::Isometry3d velocity = Eigen::Isometry3d::Identity();    // T_curr_prev of the last good frame
  double velocity_dt = 0.0;  // s between the frames `velocity` spans (0: unknown)
  double last_timestamp = 0.0;
  bool has_last_timestamp = false;
  int consecutive_failures = 0;
  bool prev_skipped = false;  // the last output frame was an unusable frame placed by the guess

  Scratch scratch;  // per-block buffers of accumulate()

  void setup(const OdometryConfig& c, const CameraIntrinsics& k);

  void forget_motion();

  void allocate();

  // ---- pyramid ----------------------------------------------------------------------------

  /// Level 0: grey to float, depth to inverse depth. Returns the number of pixels with depth.
  static int fill_level0(const cv::Mat& gray, const cv::Mat& depth, Image& I, Image& W);

  /// 2x2 reduction of level l - 1 into level l (l >= 1). Grey: box mean. Inverse depth: mean of
  /// the valid samples when they agree within the level's edge ratio, else no reading (a mean
  /// across a depth edge is a point that exists in neither surface).
  void reduce_level(Pyramid& P, int l) const;

  /// Builds the pyramid of frame into P. Returns the number of full-resolution depth pixels.
  void build_pyramid(const cv::Mat& gray, const cv::Mat& depth, Pyramid& P);

  // ---- reference points -------------------------------------------------------------------

  /// Builds the point list of level l of P (the new reference).
  void build_points(const Pyramid& P, int l, PointList& L) const;

  void build_reference(const Pyramid& P);

  int ref_points(int l) const { return pts[l].n; }

  // ---- one Gauss-Newton accumulation ------------------------------------------------------

  /// One pass over L: residuals at the estimate G (T_curr_ref), Student-t weights with scales
  /// sigma_I and sigma_W, and (unless stats_only) the normal equations.
  ///
  /// Each block goes through three loops so that two of them vectorise: (a) warp and project,
  /// branch-free; (b) the bilinear gathers from B, scalar; (c) residuals and weights, branch-free.
  /// Invalid samples keep going through the arithmetic with harmless values and get weight 0.
  void accumulate(const PointList& L, const Image& IB, const Image& WB, const CameraIntrinsics& k,
                  float ratio, const Eigen::Isometry3f& G, float sigma_I, float sigma_W, bool stats_only,
                  Scratch& S, Accum& acc) const;

  // ---- tracking ---------------------------------------------------------------------------

  struct Solve {
    bool ok = false;
    OdometryStatus status = OdometryStatus::kOk;
    bool converged = false;
    int iterations = 0;
    Accum last;
    Eigen::Isometry3d G = Eigen::Isometry3d::Identity();
  };

  /// Estimates T_curr_ref from the reference points and the current pyramid, starting at G0.
  Solve estimate(const Pyramid& cur, const Eigen::Isometry3d& G0);

  /// Constant-velocity guess for the step to a frame at `timestamp`: the last good relative
  /// motion, scaled to the time elapsed when both frames carry timestamps (a dropped frame
  /// doubles the step).
  Eigen::Isometry3d predicted_step(double timestamp) const;

  OdometryResult track(const RgbdFrame& f);
};

}  // namespace stairguide
