#pragma once
// What the phases of the segmentation (src/perception/segmentation/*.cpp) share: the plane solves
// behind fit_plane and fit_plane_fixed_normal that the cell tests call alone, and the residual of
// moments under a plane. Internal to the stage: not a public header.
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <numeric>
#include <vector>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "stairguide/perception/segmentation.hpp"

namespace stairguide {
namespace segmentation_detail {
/// A region is planar when its residual RMS is within this share of the inlier tolerance.
constexpr float kPlanarRms = 0.6f;

/// The plane 1/z = a u' + b v' + c of moments `m` by the centred normal equations (better
/// conditioned for small cells far from the image centre), with what fit_plane and the cell tests
/// take from it: g = |(a, b, c)|, the residual rms and 1/z at the mean pixel (wm). False for fewer
/// than three points, points on a line, or a degenerate plane.
struct CentredPlane {
  double a, b, c, g, rms_w, wm, mu, mv;
};
inline bool solve_centred_plane(const InvDepthMoments& m, CentredPlane& p) {
  if (m.n < 3.0) return false;
  const double in = 1.0 / m.n;
  const double mu = m.su * in, mv = m.sv * in, mw = m.sw * in;
  const double cuu = m.suu * in - mu * mu, cuv = m.suv * in - mu * mv, cvv = m.svv * in - mv * mv;
  const double cuw = m.suw * in - mu * mw, cvw = m.svw * in - mv * mw, cww = m.sww * in - mw * mw;
  const double det = cuu * cvv - cuv * cuv;
  if (!(det > 1e-6 * (cuu * cvv + 1e-30)) || !(det > 1e-24)) return false;  // points on a line
  const double a = (cuw * cvv - cvw * cuv) / det;
  const double b = (cvw * cuu - cuw * cuv) / det;
  const double c = mw - a * mu - b * mv;
  const double g = std::sqrt(a * a + b * b + c * c);
  if (!(g > 1e-9)) return false;
  p = {a, b, c, g, std::sqrt(std::max(0.0, cww - a * cuw - b * cvw)), a * mu + b * mv + c, mu, mv};
  return true;
}

/// fit_plane's ok, rms_w and mean.z() alone (the same solve), for the cell tests that keep nothing
/// else of the fit: thousands of cells a frame, and the rest of a fit (normal, offset, centroid:
/// six more divisions, a struct of 30 floats) was most of its cost.
inline bool plane_rms_depth(const InvDepthMoments& m, float& rms_w, float& mean_z) {
  CentredPlane p;
  if (!solve_centred_plane(m, p)) return false;
  rms_w = static_cast<float>(p.rms_w);
  mean_z = p.wm > 1e-9 ? static_cast<float>(1.0 / p.wm) : 0.f;
  return true;
}

/// The one unknown of a plane with its normal n fixed: 1/z = g s, s = -(n . (u', v', 1)),
/// g = 1/d. False when the moments are empty or the points would lie behind the camera on such a
/// plane; ssw is the sum of s w the residual needs.
inline bool fixed_normal_gain(const InvDepthMoments& m, const Eigen::Vector3f& n, double& g, double& ssw) {
  if (m.n < 1.0) return false;
  const double nx = n.x(), ny = n.y(), nz = n.z();
  ssw = -(nx * m.suw + ny * m.svw + nz * m.sw);
  const double sss = nx * nx * m.suu + ny * ny * m.svv + nz * nz * m.n + 2.0 * nx * ny * m.suv +
                     2.0 * nx * nz * m.su + 2.0 * ny * nz * m.sv;
  if (!(sss > 1e-30)) return false;
  g = ssw / sss;
  return g > 1e-9;
}

/// fit_plane_fixed_normal's ok and rms_w alone (what the cell tests need), by the same expressions.
inline bool fixed_normal_rms(const InvDepthMoments& m, const Eigen::Vector3f& n, float& rms_w) {
  double g = 0.0, ssw = 0.0;
  if (!fixed_normal_gain(m, n, g, ssw)) return false;
  rms_w = static_cast<float>(std::sqrt(std::max(0.0, (m.sww - g * ssw) / m.n)));
  return true;
}

inline double InvDepthMomentsMsr(const InvDepthMoments& m, double a, double b, double c) {
  // Mean squared residual of the points under 1/z = a u' + b v' + c, from the moments.
  if (m.n <= 0) return 0.0;
  const double s = m.sww - 2 * a * m.suw - 2 * b * m.svw - 2 * c * m.sw + a * a * m.suu + 2 * a * b * m.suv +
                   b * b * m.svv + 2 * a * c * m.su + 2 * b * c * m.sv + c * c * m.n;
  return std::max(0.0, s / m.n);
}
}  // namespace segmentation_detail
}  // namespace stairguide
