// Dense odometry, per frame: the pyramid of grey and inverse-depth images (2x2 box reductions),
// and the reference frame's per-level point lists with their Jacobians (eq. 10 and 11).

// The per-pixel loops are written branch-free (selects instead of branches); GCC only turns
// such selects on float compares into SIMD when it may assume no floating-point traps, which
// nothing here relies on. Set before every include so that all inline functions of this unit
// share the option (GCC does not inline across differing optimize options).
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC optimize("no-trapping-math")
#endif
#include "dense_odometry_internal.hpp"

namespace stairguide {

int DenseOdometry::Impl::fill_level0(const cv::Mat& gray, const cv::Mat& depth, Image& I, Image& W) {
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

void DenseOdometry::Impl::reduce_level(Pyramid& P, int l) const {
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

void DenseOdometry::Impl::build_pyramid(const cv::Mat& gray, const cv::Mat& depth, Pyramid& P) {
  P.valid0 = fill_level0(gray, depth, P.I[0], P.W[0]);
  for (int l = 1; l < levels; ++l) reduce_level(P, l);
}

void DenseOdometry::Impl::build_points(const Pyramid& P, int l, PointList& L) const {
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
      const float gIy = 0.125f * (2.f * (Id[x] - Iu[x]) + (Id[x - 1] - Iu[x - 1]) + (Id[x + 1] - Iu[x + 1]));
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

void DenseOdometry::Impl::build_reference(const Pyramid& P) {
  for (int l = 0; l < levels; ++l) build_points(P, l, pts[l]);
}

}  // namespace stairguide
