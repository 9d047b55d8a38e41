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

// The per-pixel loops are written branch-free (selects instead of branches); GCC only turns
// such selects on float compares into SIMD when it may assume no floating-point traps, which
// nothing here relies on. Set before every include so that all inline functions of this unit
// share the option (GCC does not inline across differing optimize options).
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC optimize("no-trapping-math")
#endif
#include "stairguide/odometry/dense_odometry.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <opencv2/imgproc.hpp>
#include <vector>

namespace stairguide {

const char* to_string(OdometryStatus s) {
  switch (s) {
    case OdometryStatus::kOk:
      return "ok";
    case OdometryStatus::kFirstFrame:
      return "first frame";
    case OdometryStatus::kBadInput:
      return "frame does not match the configured camera";
    case OdometryStatus::kTooFewPixels:
      return "too few valid pixels";
    case OdometryStatus::kDiverged:
      return "diverged";
    case OdometryStatus::kJump:
      return "jump beyond walking motion";
  }
  return "?";
}

namespace {

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
Eigen::Matrix3d rot_exp(const Eigen::Vector3d& w) {
  const double a = w.norm();
  if (a < 1e-12) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(a, w / a).toRotationMatrix();
}

Eigen::Vector3d rot_log(const Eigen::Matrix3d& R) {
  const Eigen::AngleAxisd aa(R);
  return aa.axis() * aa.angle();
}

}  // namespace

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

  void setup(const OdometryConfig& c, const CameraIntrinsics& k) {
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

  void forget_motion() {
    T_last_ref.setIdentity();
    velocity.setIdentity();
    velocity_dt = 0.0;
    has_last_timestamp = false;
    consecutive_failures = 0;
    prev_skipped = false;
  }

  void allocate() {
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

  // ---- pyramid ----------------------------------------------------------------------------

  /// Level 0: grey to float, depth to inverse depth. Returns the number of pixels with depth.
  static int fill_level0(const cv::Mat& gray, const cv::Mat& depth, Image& I, Image& W) {
    int valid = 0;
    for (int y = 0; y < I.h; ++y) {
      float* Ir = I.row(y);
      float* Wr = W.row(y);
      const float* d = depth.ptr<float>(y);
      if (!gray.empty()) {
        const unsigned char* g = gray.ptr<unsigned char>(y);
        for (int x = 0; x < I.w; ++x) Ir[x] = static_cast<float>(g[x]);
      } else {
        std::fill(Ir, Ir + I.w, 0.f);
      }
      for (int x = 0; x < W.w; ++x) {
        const float z = d[x];
        // NaN fails the comparison and counts as no reading, like 0.
        const bool ok = z > 1e-3f && z < 1e4f;
        Wr[x] = ok ? 1.f / z : 0.f;
        valid += ok;
      }
    }
    return valid;
  }

  /// 2x2 reduction of level l - 1 into level l (l >= 1). Grey: box mean. Inverse depth: mean of
  /// the valid samples when they agree within the level's edge ratio, else no reading (a mean
  /// across a depth edge is a point that exists in neither surface).
  void reduce_level(Pyramid& P, int l) const {
    const Image& Is = P.I[l - 1];
    const Image& Ws = P.W[l - 1];
    Image& I = P.I[l];
    Image& W = P.W[l];
    const float ratio = edge_ratio[l - 1];
    for (int y = 0; y < I.h; ++y) {
      const float* i0 = Is.row(2 * y);
      const float* i1 = Is.row(2 * y + 1);
      const float* w0 = Ws.row(2 * y);
      const float* w1 = Ws.row(2 * y + 1);
      float* Ir = I.row(y);
      float* Wr = W.row(y);
      for (int x = 0; x < I.w; ++x) Ir[x] = 0.25f * (i0[2 * x] + i0[2 * x + 1] + i1[2 * x] + i1[2 * x + 1]);
      for (int x = 0; x < W.w; ++x) {
        const float a = w0[2 * x], b = w0[2 * x + 1], c = w1[2 * x], d = w1[2 * x + 1];
        float lo = 1e30f, hi = 0.f, sum = 0.f;
        int n = 0;
        for (float v : {a, b, c, d}) {
          if (v > 0.f) {
            lo = std::min(lo, v);
            hi = std::max(hi, v);
            sum += v;
            ++n;
          }
        }
        Wr[x] = (n >= 2 && hi - lo <= ratio * lo) ? sum / static_cast<float>(n) : 0.f;
      }
    }
  }

  /// Builds the pyramid of frame into P. Returns the number of full-resolution depth pixels.
  void build_pyramid(const cv::Mat& gray, const cv::Mat& depth, Pyramid& P) {
    P.valid0 = fill_level0(gray, depth, P.I[0], P.W[0]);
    for (int l = 1; l < levels; ++l) reduce_level(P, l);
  }

  // ---- reference points -------------------------------------------------------------------

  /// Builds the point list of level l of P (the new reference).
  void build_points(const Pyramid& P, int l, PointList& L) const {
    const Image& I = P.I[l];
    const Image& W = P.W[l];
    const CameraIntrinsics& k = K[l];
    const int s = stride[l];
    const float ratio2 = 2.f * edge_ratio[l];  // central differences span two pixels
    const float ifx = 1.f / k.fx, ify = 1.f / k.fy;
    int n = 0;
    // Grid rows are 1, 1 + s, 1 + 2s, ... (the border rows have no central difference).
    for (int y = 1; y < I.h - 1; y += s) {
      const float* Wr = W.row(y);
      const float* Wu = W.row(y - 1);
      const float* Wd = W.row(y + 1);
      const float* Ir = I.row(y);
      const float* Iu = I.row(y - 1);
      const float* Id = I.row(y + 1);
      // Offset the grid by row so that subsampled columns do not line up (less aliasing).
      const int xstart = 1 + ((y / s) * (s / 2 + 1)) % s;
      for (int x = xstart; x < I.w - 1; x += s) {
        const float w = Wr[x];
        if (!(w > 0.f)) continue;
        const float wl = Wr[x - 1], wr = Wr[x + 1], wu = Wu[x], wd = Wd[x];
        if (!(wl > 0.f && wr > 0.f && wu > 0.f && wd > 0.f)) continue;
        const float dwx = wr - wl, dwy = wd - wu;
        if (std::fabs(dwx) > ratio2 * w || std::fabs(dwy) > ratio2 * w) continue;
        const float gWx = 0.5f * dwx, gWy = 0.5f * dwy;
        // Sobel (central difference smoothed across by 1-2-1): less sensitive to sensor noise and
        // compression artefacts than a bare central difference.
        const float gIx =
            0.125f * (2.f * (Ir[x + 1] - Ir[x - 1]) + (Iu[x + 1] - Iu[x - 1]) + (Id[x + 1] - Id[x - 1]));
        const float gIy =
            0.125f * (2.f * (Id[x] - Iu[x]) + (Id[x - 1] - Iu[x - 1]) + (Id[x + 1] - Iu[x + 1]));
        const float z = 1.f / w;
        const float X = (static_cast<float>(x) - k.cx) * ifx * z;
        const float Y = (static_cast<float>(y) - k.cy) * ify * z;
        // d(pixel)/d(point) = W (K - p e_z^T) (eq. 6), rows (fx W, 0, -fx X W^2), (0, fy W, -fy Y W^2).
        const float w2 = w * w;
        const float ax = gIx * k.fx * w, ay = gIy * k.fy * w;
        const float az = -(gIx * k.fx * X + gIy * k.fy * Y) * w2;
        // Eq. 11: W (grad W (K - p e_z^T) + W e_z^T) = grad W . dp/dX + W^2 e_z^T.
        const float bx = gWx * k.fx * w, by = gWy * k.fy * w;
        const float bz = -(gWx * k.fx * X + gWy * k.fy * Y) * w2 + w2;
        // M(p) xi = r + theta x X: d/dr = identity, d/dtheta of A.(theta x X) = X x A.
        if (static_cast<std::size_t>(n) + 8 >= L.capacity()) break;  // cannot happen (sized for stride)
        L.x[n] = X;
        L.y[n] = Y;
        L.z[n] = z;
        L.ia[n] = Ir[x];
        L.wa[n] = w;
        L.ji[0][n] = ax;
        L.ji[1][n] = ay;
        L.ji[2][n] = az;
        L.ji[3][n] = Y * az - z * ay;
        L.ji[4][n] = z * ax - X * az;
        L.ji[5][n] = X * ay - Y * ax;
        L.jw[0][n] = bx;
        L.jw[1][n] = by;
        L.jw[2][n] = bz;
        L.jw[3][n] = Y * bz - z * by;
        L.jw[4][n] = z * bx - X * bz;
        L.jw[5][n] = X * by - Y * bx;
        ++n;
      }
    }
    L.n = n;
    L.pad();
  }

  void build_reference(const Pyramid& P) {
    for (int l = 0; l < levels; ++l) build_points(P, l, pts[l]);
  }

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
                  Scratch& S, Accum& acc) const {
    acc.clear();
    const Eigen::Matrix3f R = G.linear();
    const Eigen::Vector3f t = G.translation();
    const float r00 = R(0, 0), r01 = R(0, 1), r02 = R(0, 2), r10 = R(1, 0), r11 = R(1, 1), r12 = R(1, 2),
                r20 = R(2, 0), r21 = R(2, 1), r22 = R(2, 2);
    const float tx = t.x(), ty = t.y(), tz = t.z();
    const float fx = k.fx, fy = k.fy, cx = k.cx, cy = k.cy;
    const float umax = static_cast<float>(IB.w - 1) - 1e-3f, vmax = static_cast<float>(IB.h - 1) - 1e-3f;
    const int wstride = IB.w;
    const float* __restrict Ipx = IB.px.data();
    const float* __restrict Wpx = WB.px.data();
    const float isI = 1.f / sigma_I, isW = 1.f / sigma_W;
    const float nu = cfg.student_nu, nu1 = cfg.student_nu + 1.f;
    const float cI = isI * isI, cW = isW * isW;
    // Inliers are judged with the configured scales, not the adaptive ones.
    const float inI2 = 9.f * cfg.sigma_intensity * cfg.sigma_intensity;
    const float inW2 = 9.f * cfg.sigma_inv_depth * cfg.sigma_inv_depth;

    float* __restrict bxs = S.bx;
    float* __restrict bys = S.by;
    float* __restrict bzs = S.bz;
    float* __restrict fa = S.fa;
    float* __restrict fb = S.fb;
    float* __restrict val = S.valid;
    int* __restrict idxs = S.idx;
    float* __restrict iBs = S.iB;
    float* __restrict wBs = S.wB;
    float* __restrict wIs = S.wI;
    float* __restrict wWs = S.wW;
    float* __restrict rIs = S.rI;
    float* __restrict rWs = S.rW;
    float* __restrict inl = S.inl;

    for (int s0 = 0; s0 < L.n; s0 += kBlock) {
      const int m = std::min(kBlock, L.n - s0);
      const int m8 = (m + 7) & ~7;  // the lists are zero-padded to a multiple of 8
      const float* __restrict X = L.x.data() + s0;
      const float* __restrict Y = L.y.data() + s0;
      const float* __restrict Z = L.z.data() + s0;
      const float* __restrict IA = L.ia.data() + s0;
      const float* __restrict WA = L.wa.data() + s0;

      // (a) Point of A in B with the current estimate, its pixel, the bilinear fractions.
      for (int q = 0; q < m8; ++q) {
        const float bx = r00 * X[q] + r01 * Y[q] + r02 * Z[q] + tx;
        const float by = r10 * X[q] + r11 * Y[q] + r12 * Z[q] + ty;
        const float bz = r20 * X[q] + r21 * Y[q] + r22 * Z[q] + tz;
        // Bitwise & and selects (no short-circuit): keeps the loop branch-free for the vectoriser.
        const bool front = bz > 1e-3f;
        const float bzc = front ? bz : 1.f;
        const float iz = 1.f / bzc;
        const float u = fx * bx * iz + cx, v = fy * by * iz + cy;
        const bool in = front & (u >= 0.f) & (v >= 0.f) & (u < umax) & (v < vmax) & (q < m);
        const float uc = in ? u : 0.f, vc = in ? v : 0.f;
        const int x0 = static_cast<int>(uc), y0 = static_cast<int>(vc);
        fa[q] = uc - static_cast<float>(x0);
        fb[q] = vc - static_cast<float>(y0);
        idxs[q] = y0 * wstride + x0;
        val[q] = in ? 1.f : 0.f;
        bxs[q] = bx;
        bys[q] = by;
        bzs[q] = bzc;
      }
      // (b) Bilinear samples of B. All four inverse-depth taps must have depth and lie on one
      // surface, else B has no value there.
      for (int q = 0; q < m8; ++q) {
        const int i = idxs[q];
        const float ax = fa[q], ay = fb[q];
        const float w00 = Wpx[i], w01 = Wpx[i + 1], w10 = Wpx[i + wstride], w11 = Wpx[i + wstride + 1];
        const float wlo = std::min(std::min(w00, w01), std::min(w10, w11));
        const float whi = std::max(std::max(w00, w01), std::max(w10, w11));
        const bool ok = wlo > 0.f && whi - wlo <= ratio * wlo;
        const float wt = w00 + ax * (w01 - w00), wb = w10 + ax * (w11 - w10);
        const float i00 = Ipx[i], i01 = Ipx[i + 1], i10 = Ipx[i + wstride], i11 = Ipx[i + wstride + 1];
        const float it = i00 + ax * (i01 - i00), ib = i10 + ax * (i11 - i10);
        iBs[q] = it + ay * (ib - it);
        wBs[q] = ok ? wt + ay * (wb - wt) : 1.f;
        val[q] = ok ? val[q] : 0.f;
      }
      // (c) Residuals and weights. B's measured point, scaled along the ray through (u, v),
      // mapped back into A's frame with the estimate: its inverse depth there is the warped W_B
      // of eq. 11. Student-t weights (nu + 1) / (nu + x^2), times 1/sigma^2 of eq. 12.
      for (int q = 0; q < m8; ++q) {
        const float sc = 1.f / (wBs[q] * bzs[q]);
        const float zA = r02 * (bxs[q] * sc - tx) + r12 * (bys[q] * sc - ty) + r22 * (bzs[q] * sc - tz);
        const bool front = zA > 1e-3f;
        const float okf = (val[q] > 0.f) & front ? 1.f : 0.f;
        const float zAc = front ? zA : 1.f;
        const float rI = okf * (iBs[q] - IA[q]);
        const float rW = okf * (1.f / zAc - WA[q]);
        const float rI2 = rI * rI, rW2 = rW * rW;
        wIs[q] = okf * nu1 / (nu + rI2 * cI) * cI;
        wWs[q] = okf * nu1 / (nu + rW2 * cW) * cW;
        rIs[q] = rI;
        rWs[q] = rW;
        val[q] = okf;
        inl[q] = (rI2 < inI2) & (rW2 < inW2) ? okf : 0.f;
      }
      const float used = sum8(val, m8);
      acc.used += static_cast<long>(used + 0.5f);
      acc.inliers += static_cast<long>(sum8(inl, m8) + 0.5f);
      const float stI = dot2(wIs, rIs, rIs, rIs, m8, true), stW = dot2(wWs, rWs, rWs, rWs, m8, true);
      // sum_tI = sum (nu+1)/(nu+x^2) r^2 = sum wI r^2 / cI (and the same for W).
      const float rI2s = dot1(rIs, rIs, m8), rW2s = dot1(rWs, rWs, m8);
      acc.sum_wx2 += static_cast<double>(stI) + static_cast<double>(stW);
      acc.sum_w += static_cast<double>(sum8(wIs, m8)) / cI + static_cast<double>(sum8(wWs, m8)) / cW;
      acc.sum_rI2 += rI2s;
      acc.sum_rW2 += rW2s;
      acc.sum_tI += static_cast<double>(stI) / cI;
      acc.sum_tW += static_cast<double>(stW) / cW;
      if (used < 0.5f || stats_only) continue;
      for (int j = 0; j < 6; ++j) {
        const float* __restrict jI = L.ji[j].data() + s0;
        const float* __restrict jW = L.jw[j].data() + s0;
        float* __restrict aI = S.aI[j];
        float* __restrict aW = S.aW[j];
        for (int q = 0; q < m8; ++q) {
          aI[q] = wIs[q] * jI[q];
          aW[q] = wWs[q] * jW[q];
        }
      }
      for (int a = 0; a < 6; ++a) {
        for (int b = a; b < 6; ++b)
          acc.H(a, b) += dot2(S.aI[a], L.ji[b].data() + s0, S.aW[a], L.jw[b].data() + s0, m8, false);
        acc.g(a) += dot2(S.aI[a], rIs, S.aW[a], rWs, m8, false);
      }
    }
    for (int a = 0; a < 6; ++a)
      for (int b = 0; b < a; ++b) acc.H(a, b) = acc.H(b, a);
  }

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
  Solve estimate(const Pyramid& cur, const Eigen::Isometry3d& G0) {
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
        if (xi.head<3>().norm() < cfg.min_update_translation &&
            xi.tail<3>().norm() < cfg.min_update_rotation) {
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

  /// Constant-velocity guess for the step to a frame at `timestamp`: the last good relative
  /// motion, scaled to the time elapsed when both frames carry timestamps (a dropped frame
  /// doubles the step).
  Eigen::Isometry3d predicted_step(double timestamp) const {
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

  OdometryResult track(const RgbdFrame& f) {
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
    if (res.inlier_fraction < cfg.min_inlier_fraction) {
      OdometryResult r = fail(OdometryStatus::kDiverged, true);
      r.iterations = res.iterations;
      r.pixels_used = res.pixels_used;
      r.inlier_fraction = res.inlier_fraction;
      r.residual = res.residual;
      r.photometric_rms = res.photometric_rms;
      r.inv_depth_rms = res.inv_depth_rms;
      r.converged = res.converged;
      return r;
    }
    if (trans > cfg.max_translation || rot > cfg.max_rotation) {
      OdometryResult r = fail(OdometryStatus::kJump, true);
      r.iterations = res.iterations;
      r.pixels_used = res.pixels_used;
      r.inlier_fraction = res.inlier_fraction;
      r.residual = res.residual;
      r.converged = res.converged;
      return r;
    }

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
};

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
