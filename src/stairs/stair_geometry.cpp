// The small 2D geometry stair modelling's phases are built from (stair_modelling_internal.hpp),
// and the line fit of stair_profile.hpp.
#include <algorithm>
#include <cmath>
#include <limits>

#include "stair_modelling_internal.hpp"
#include "stairguide/stairs/stair_profile.hpp"

namespace stairguide {
namespace modelling {
namespace {

float cross(const Eigen::Vector2f& o, const Eigen::Vector2f& a, const Eigen::Vector2f& b) {
  return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
}

/// Two quantiles of `v` (reordered): the outer one is searched only on its side of the inner one.
void quantile_pair(std::vector<float>& v, float outer, float inner, float& q_outer, float& q_inner) {
  const auto at = [&](float q) {
    return static_cast<long>(std::lround(q * static_cast<float>(v.size() - 1)));
  };
  const long io = at(outer), ii = at(inner);
  std::nth_element(v.begin(), v.begin() + ii, v.end());
  q_inner = v[static_cast<std::size_t>(ii)];
  if (io < ii)
    std::nth_element(v.begin(), v.begin() + io, v.begin() + ii);
  else if (io > ii)
    std::nth_element(v.begin() + ii + 1, v.begin() + io, v.end());
  q_outer = v[static_cast<std::size_t>(io)];
}

}  // namespace

// Andrew's monotone chain; sorts `pts` in place. Hand-written: 2D and tiny, PCL's ConvexHull wants
// point clouds and qhull for the same job.
void convex_hull(std::vector<Eigen::Vector2f>& pts, std::vector<Eigen::Vector2f>& hull) {
  hull.clear();
  if (pts.size() < 3) {
    hull = pts;
    return;
  }
  std::sort(pts.begin(), pts.end(), [](const Eigen::Vector2f& a, const Eigen::Vector2f& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  hull.resize(2 * pts.size());
  std::size_t k = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    while (k >= 2 && cross(hull[k - 2], hull[k - 1], pts[i]) <= 0.f) --k;
    hull[k++] = pts[i];
  }
  for (std::size_t i = pts.size() - 1, t = k + 1; i > 0; --i) {
    while (k >= t && cross(hull[k - 2], hull[k - 1], pts[i - 1]) <= 0.f) --k;
    hull[k++] = pts[i - 1];
  }
  hull.resize(k > 1 ? k - 1 : k);
}

float polygon_area(const std::vector<Eigen::Vector2f>& poly) {
  float a = 0.f;
  for (std::size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++)
    a += poly[j].x() * poly[i].y() - poly[i].x() * poly[j].y();
  return 0.5f * std::fabs(a);
}

float rect_area(const std::vector<Eigen::Vector2f>& hull, float angle) {
  if (hull.empty()) return 0.f;
  const Eigen::Vector2f d(std::cos(angle), std::sin(angle)), n(-d.y(), d.x());
  float lo0 = std::numeric_limits<float>::max(), hi0 = -lo0, lo1 = lo0, hi1 = -lo0;
  for (const auto& p : hull) {
    const float u = d.dot(p), v = n.dot(p);
    lo0 = std::min(lo0, u);
    hi0 = std::max(hi0, u);
    lo1 = std::min(lo1, v);
    hi1 = std::max(hi1, v);
  }
  return (hi0 - lo0) * (hi1 - lo1);
}

/// Wraps an angle into [-pi/4, pi/4): rectangle axes repeat every quarter turn.
float wrap_quarter(float a) {
  a = std::fmod(a + 0.25f * kPi, kHalfPi);
  if (a < 0.f) a += kHalfPi;
  return a - 0.25f * kPi;
}

float robust_low(std::vector<float>& v) {
  if (v.empty()) return std::numeric_limits<float>::quiet_NaN();
  if (v.size() < kMinRobust) return *std::min_element(v.begin(), v.end());
  float q1 = 0.f, q2 = 0.f;
  quantile_pair(v, kQ1, kQ2, q1, q2);
  return q1 - kQ1 * (q2 - q1) / (kQ2 - kQ1);
}

float robust_high(std::vector<float>& v) {
  if (v.empty()) return std::numeric_limits<float>::quiet_NaN();
  if (v.size() < kMinRobust) return *std::max_element(v.begin(), v.end());
  float q1 = 0.f, q2 = 0.f;
  quantile_pair(v, 1.f - kQ1, 1.f - kQ2, q1, q2);
  return q1 + kQ1 * (q1 - q2) / (kQ2 - kQ1);
}

}  // namespace modelling

LineFit fit_line(const std::vector<float>& x, const std::vector<float>& y) {
  LineFit f;
  const std::size_t n = x.size();
  if (n < 2) return f;
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (std::size_t i = 0; i < n; ++i) {
    sx += x[i];
    sy += y[i];
    sxx += static_cast<double>(x[i]) * x[i];
    sxy += static_cast<double>(x[i]) * y[i];
  }
  const double den = static_cast<double>(n) * sxx - sx * sx;
  if (std::fabs(den) < 1e-12) return f;
  f.slope = static_cast<float>((static_cast<double>(n) * sxy - sx * sy) / den);
  f.intercept = static_cast<float>((sy - f.slope * sx) / static_cast<double>(n));
  f.ok = true;
  return f;
}

}  // namespace stairguide
