// Dense odometry, per iteration: one pass over the reference's points, warped into the current
// frame, with Student-t weights and the 6x6 normal equations summed in 8 lanes (the hot loop).

// The per-pixel loops are written branch-free (selects instead of branches); GCC only turns
// such selects on float compares into SIMD when it may assume no floating-point traps, which
// nothing here relies on. Set before every include so that all inline functions of this unit
// share the option (GCC does not inline across differing optimize options).
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC optimize("no-trapping-math")
#endif
#include "dense_odometry_internal.hpp"

namespace stairguide {

void DenseOdometry::Impl::accumulate(const PointList& L, const Image& IB, const Image& WB,
                                     const CameraIntrinsics& k, float ratio, const Eigen::Isometry3f& G,
                                     float sigma_I, float sigma_W, bool stats_only, Scratch& S,
                                     Accum& acc) const {
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

}  // namespace stairguide
