#include "stairguide/stairs/stair_modelling.hpp"

#include "stairguide/stairs/stair_checks.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>

namespace stairguide {
namespace {

constexpr float kPi = 3.14159265358979f;
constexpr float kHalfPi = 0.5f * kPi;
// Quantiles from which an edge is extrapolated. Points spread evenly over a surface give a linear
// empirical distribution near its edge; the line through two inner quantiles meets zero at the edge
// itself. Inner quantiles keep depth noise and stray pixels out, and the extrapolation removes the
// inward bias a plain low quantile would have.
constexpr float kQ1 = 0.03f, kQ2 = 0.12f;
constexpr std::size_t kMinRobust = 24;    // fewer points: plain extremes
constexpr float kLandingDepth = 0.6f;     // m, a level deeper than this is a landing or a floor
constexpr float kShallowFloor = 0.5f;     // m, less floor than this in front of the steps is suspect
constexpr int kDoubtfulPixels = 200;      // px, a level this big one riser below the floor
constexpr float kOtherFloorWidth = 1.5f;  // m, a level this wide running out of view is no furniture
constexpr float kRiserMinShare = 0.15f;   // a riser spans at least this share of the staircase's width
constexpr float kBigLevel = 4.f;          // a level this many times the median level's area is no step (axes)
constexpr float kBoundaryBin = 0.05f;     // m, lateral bins of the boundary line of a single level
constexpr float kBoundaryInlier = 0.015f;  // m, a bin on the boundary line
constexpr std::size_t kHullPoints = 600;   // subsample for the convex hulls (orientation only)
constexpr std::size_t kStepPoints = 4000;  // points per level used for edges and extents
constexpr std::size_t kFloorPoints = 3000;
constexpr std::size_t kOutputPoints = 4000;  // per level in StairResult::level_data

float cross(const Eigen::Vector2f& o, const Eigen::Vector2f& a, const Eigen::Vector2f& b) {
  return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
}

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

/// Two quantiles of `v` (reordered): the outer one is searched only on its side of the inner one.
void quantile_pair(std::vector<float>& v, float outer, float inner, float& q_outer, float& q_inner) {
  const auto at = [&](float q) { return static_cast<long>(std::lround(q * static_cast<float>(v.size() - 1))); };
  const long io = at(outer), ii = at(inner);
  std::nth_element(v.begin(), v.begin() + ii, v.end());
  q_inner = v[static_cast<std::size_t>(ii)];
  if (io < ii)
    std::nth_element(v.begin(), v.begin() + io, v.begin() + ii);
  else if (io > ii)
    std::nth_element(v.begin() + ii + 1, v.begin() + io, v.end());
  q_outer = v[static_cast<std::size_t>(io)];
}

/// Wraps an angle into [-pi/4, pi/4): rectangle axes repeat every quarter turn.
float wrap_quarter(float a) {
  a = std::fmod(a + 0.25f * kPi, kHalfPi);
  if (a < 0.f) a += kHalfPi;
  return a - 0.25f * kPi;
}

struct LineFit {
  float slope = 0.f, intercept = 0.f;
  bool ok = false;
};

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

}  // namespace

StairModelling::StairModelling(const ClassificationConfig& classification, const StairDetectionConfig& detection,
                               const StairModellingConfig& config)
    : cls_(classification), det_(detection), cfg_(config) {}

float StairModelling::robust_low(std::vector<float>& v) const {
  if (v.empty()) return std::numeric_limits<float>::quiet_NaN();
  if (v.size() < kMinRobust) return *std::min_element(v.begin(), v.end());
  float q1 = 0.f, q2 = 0.f;
  quantile_pair(v, kQ1, kQ2, q1, q2);
  return q1 - kQ1 * (q2 - q1) / (kQ2 - kQ1);
}

float StairModelling::robust_high(std::vector<float>& v) const {
  if (v.empty()) return std::numeric_limits<float>::quiet_NaN();
  if (v.size() < kMinRobust) return *std::max_element(v.begin(), v.end());
  float q1 = 0.f, q2 = 0.f;
  quantile_pair(v, 1.f - kQ1, 1.f - kQ2, q1, q2);
  return q1 + kQ1 * (q1 - q2) / (kQ2 - kQ1);
}

Eigen::Vector3f StairModelling::fit_up(const SceneResult& scene, const StairHypothesis& hyp, const Eigen::Vector3f& up0) {
  // All horizontal levels share one normal: centre each level's points on its own mean and fit one
  // direction of least spread to them all. A floor normal 1 degree off tilts every height by
  // 5 mm per 30 cm of tread, so the steps' own points are worth adding.
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  std::size_t total = 0;
  for (const LevelSeed& l : hyp.levels) {
    for (int r : l.regions) {
      const auto& pts = scene.regions[static_cast<std::size_t>(r)].points;
      if (pts.size() < 10) continue;
      const std::size_t stride = std::max<std::size_t>(1, pts.size() / 500);
      Eigen::Vector3d mean = Eigen::Vector3d::Zero();
      std::size_t n = 0;
      for (std::size_t i = 0; i < pts.size(); i += stride, ++n) mean += pts[i].cast<double>();
      mean /= static_cast<double>(n);
      for (std::size_t i = 0; i < pts.size(); i += stride) {
        const Eigen::Vector3d d = pts[i].cast<double>() - mean;
        scatter += d * d.transpose();
      }
      total += n;
    }
  }
  if (total < 50) return up0;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(scatter);
  Eigen::Vector3f up = es.eigenvectors().col(0).cast<float>().normalized();
  if (up.dot(up0) < 0.f) up = -up;
  // A fit far from the floor's normal means the levels are not all flat: keep the floor's.
  if (up.dot(up0) < std::cos(deg2rad(3.f))) return up0;
  return up;
}

void StairModelling::project_level(const SceneResult& scene, const LevelSeed& seed, const Eigen::Vector3f& up,
                                   const Eigen::Vector3f& e1, const Eigen::Vector3f& e2, std::size_t max_points,
                                   Level2d& out) {
  out.pts.clear();
  std::size_t total = 0;
  for (int r : seed.regions) total += scene.regions[static_cast<std::size_t>(r)].points.size();
  out.plane = 0.f;
  out.centroid.setZero();
  if (!total) return;
  // An even subsample: the plane offset and the edges lose nothing measurable from it, and a large
  // level (a landing, the lower floor) costs no more than a tread.
  const std::size_t stride = std::max<std::size_t>(1, (total + max_points - 1) / max_points);
  double sum = 0;
  std::size_t used = 0;
  for (int r : seed.regions) {
    const auto& pts = scene.regions[static_cast<std::size_t>(r)].points;
    for (std::size_t i = 0; i < pts.size(); i += stride, ++used) sum += up.dot(pts[i]);
  }
  out.plane = static_cast<float>(sum / static_cast<double>(used));
  Eigen::Vector2f c = Eigen::Vector2f::Zero();
  for (int r : seed.regions) {
    const auto& pts = scene.regions[static_cast<std::size_t>(r)].points;
    for (std::size_t i = 0; i < pts.size(); i += stride) {
      const Eigen::Vector3f& p = pts[i];
      // Depth noise lies along the camera ray: slide the point along its ray onto the level's
      // plane. Points whose ray meets the plane far from where they were measured are strays.
      const float d = up.dot(p);
      if (std::fabs(d) < 0.05f) continue;
      const float s = out.plane / d;
      if (s < 0.8f || s > 1.25f) continue;
      const Eigen::Vector3f q = p * s;
      out.pts.emplace_back(e1.dot(q), e2.dot(q));
      c += out.pts.back();
    }
  }
  out.centroid = out.pts.empty() ? Eigen::Vector2f::Zero() : Eigen::Vector2f(c / static_cast<float>(out.pts.size()));
}

float StairModelling::boundary_median_ab(const std::vector<float>& a, const std::vector<float>& b, bool low,
                                         const BoundaryFrame& f) {
  bin_a_.clear();
  bin_e_.clear();
  if (a.size() < 10) return std::numeric_limits<float>::quiet_NaN();
  const float lo = *std::min_element(a.begin(), a.end()), hi = *std::max_element(a.begin(), a.end());
  const std::size_t bins = std::min<std::size_t>(400, static_cast<std::size_t>((hi - lo) / kBoundaryBin) + 1);
  bin_ext_.assign(bins, low ? std::numeric_limits<float>::max() : -std::numeric_limits<float>::max());
  bin_at_.assign(bins, 0.f);
  bin_count_.assign(bins, 0);
  for (std::size_t i = 0; i < a.size(); ++i) {
    const std::size_t j = std::min(bins - 1, static_cast<std::size_t>((a[i] - lo) / kBoundaryBin));
    if (low ? b[i] < bin_ext_[j] : b[i] > bin_ext_[j]) {
      bin_ext_[j] = b[i];
      bin_at_[j] = a[i];
    }
    ++bin_count_[j];
  }
  const CameraIntrinsics* K = K_;
  const float margin = K ? 0.02f * static_cast<float>(std::max(K->width, K->height)) : 0.f;
  for (std::size_t j = 0; j < bins; ++j) {
    if (bin_count_[j] < 3) continue;
    if (K) {
      // A boundary point on the image border is where the view ends, not where the level does.
      const Eigen::Vector3f p = f.x * bin_at_[j] + f.z * bin_ext_[j] + f.up * f.plane;
      if (p.z() < 0.05f) continue;
      const float u = K->fx * p.x() / p.z() + K->cx, v = K->fy * p.y() / p.z() + K->cy;
      if (u < margin || v < margin || u > static_cast<float>(K->width) - margin ||
          v > static_cast<float>(K->height) - margin)
        continue;
    }
    bin_a_.push_back(bin_at_[j]);
    bin_e_.push_back(bin_ext_[j]);
  }
  if (bin_e_.empty()) return std::numeric_limits<float>::quiet_NaN();
  sorted_.assign(bin_e_.begin(), bin_e_.end());
  std::nth_element(sorted_.begin(), sorted_.begin() + static_cast<long>(sorted_.size() / 2), sorted_.end());
  return sorted_[sorted_.size() / 2];
}

float StairModelling::boundary_mode(float median) {
  // The bins of the last boundary_median, its axes turned along the edge: the edge's bins lie at
  // one depth, within kBoundaryInlier. What else passed as boundary (the outline of a level
  // cut by an occluder or reaching far away at a slant, where the image border filter let a few
  // pixels through) lies at other depths. The median of all bins mixes them (held-out seed 18's
  // curb #7: 24 bins at the curb's edge, 30 on a far outline at a slant, the edge placed 34 cm into
  // the sidewalk); the largest group at one depth is the edge. Too few bins agree: the median.
  std::size_t best_in = 0;
  float best_e = median;
  for (float e : bin_e_) {
    std::size_t in = 0;
    for (float f : bin_e_) in += std::fabs(f - e) < kBoundaryInlier;
    if (in > best_in) best_in = in, best_e = e;
  }
  if (best_in < 5) return median;
  sorted_.clear();
  for (float e : bin_e_)
    if (std::fabs(e - best_e) < kBoundaryInlier) sorted_.push_back(e);
  std::nth_element(sorted_.begin(), sorted_.begin() + static_cast<long>(sorted_.size() / 2), sorted_.end());
  return sorted_[sorted_.size() / 2];
}

float StairModelling::boundary_median(const std::vector<Eigen::Vector2f>& pts, const Eigen::Vector2f& x2,
                                      const Eigen::Vector2f& z2, const BoundaryFrame& f) {
  ba_.clear();
  bb_.clear();
  for (const auto& p : pts) {
    ba_.push_back(x2.dot(p));
    bb_.push_back(z2.dot(p));
  }
  return boundary_median_ab(ba_, bb_, true, f);
}

bool StairModelling::far_side_cut(const std::vector<Eigen::Vector2f>& pts, const Eigen::Vector2f& x2,
                                  const Eigen::Vector2f& z2, const BoundaryFrame& f) {
  if (!K_ || pts.size() < 10) return false;  // (boundary_median_ab leaves its bins as they were)
  ba_.clear();
  bb_.clear();
  for (const auto& p : pts) {
    ba_.push_back(x2.dot(p));
    bb_.push_back(z2.dot(p));
  }
  // boundary_median_ab keeps only the bins whose farthest point lies inside the image: when most
  // bins lose theirs to the border, the far side is the view's end.
  boundary_median_ab(ba_, bb_, false, f);
  std::size_t bins = 0;
  for (int c : bin_count_)
    if (c >= 3) ++bins;
  return bins >= 3 && 2 * bin_e_.size() < bins;
}

bool StairModelling::boxed_in(const SceneResult& scene, const Eigen::Vector3f& xs, const Eigen::Vector3f& up,
                              const Eigen::Vector3f& zs, float a_mid, float edge_b, const StairLevel& o,
                              float plane) const {
  // A board with a side panel rising above it (a shelf's or a cabinet's bottom board): a vertical
  // plane facing along the edge at a lateral end of the level, over its depth, reaching above its
  // surface. One panel is enough: the other is often hidden behind the board or out of view. (A
  // step between walls looks the same; this is only asked of a level seen too shallow for a step
  // platform, which was an obstacle anyway before its far side was taken as running out of view.)
  // Seen far away as a strip under the image top, the panel's upper part is out of view: a panel
  // at a lateral end that faces the level's middle (its inner face: a platform's own side faces
  // outwards) bounds the level whatever its height seen, and so does the front edge of a panel, a
  // narrow upright facing the user across the level's end and rising above it. Such a strip may
  // still be a step between walls: it is only "not yet sure", the user comes nearer. Both stand
  // flush with the level's front (a wall beside a flight runs on before it, a post stands behind
  // the nosing): a flight's first tread seen alone between walls stays a step.
  constexpr float kEndSlack = 0.10f;   // m, a panel this near the level's lateral end bounds it
  constexpr float kPanelRise = 0.05f;  // m, a panel reaching this far above the level is furniture
  constexpr float kPostWidth = 0.15f;  // m, an upright facing the user this narrow is a panel's edge
  constexpr float kPostSlack = 0.03f;  // m, slack on a panel being flush with the level's front or end
  const float sin_vert = std::sin(cls_.parallel_threshold), cos_side = std::cos(cls_.parallel_threshold);
  const float cos_diag = std::sqrt(0.5f);  // faces more along the edge than towards the user
  for (const PlaneRegion& r : scene.regions) {
    if (r.points.size() < 20 || std::fabs(r.normal.dot(up)) > sin_vert) continue;
    const float nx = r.normal.dot(xs), nz = r.normal.dot(zs);
    const bool side = std::fabs(nx) >= cos_diag, front = std::fabs(nz) >= cos_side;
    if (!side && !front) continue;
    float top = -1e9f, b_lo = 1e9f, b_hi = -1e9f, a_lo = 1e9f, a_hi = -1e9f;
    const std::size_t stride = std::max<std::size_t>(1, r.points.size() / 200);
    for (std::size_t i = 0; i < r.points.size(); i += stride) {
      top = std::max(top, up.dot(r.points[i]) - plane);
      const float b = zs.dot(r.points[i]) - edge_b, a = xs.dot(r.points[i]) - a_mid;
      b_lo = std::min(b_lo, b);
      b_hi = std::max(b_hi, b);
      a_lo = std::min(a_lo, a);
      a_hi = std::max(a_hi, a);
    }
    if (side) {
      const float a = xs.dot(r.centroid) - a_mid;
      const bool at_min = std::fabs(a - o.lateral_min) < kEndSlack, at_max = std::fabs(a - o.lateral_max) < kEndSlack;
      if (!at_min && !at_max) continue;
      if (b_hi < o.depth_min || b_lo > o.depth_max) continue;
      // Facing the level's middle: at the x_S-high end the normal points to -x_S, and vice versa;
      // and flush with the level's front, as a shelf's side panel is with its bottom board (a wall
      // beside a flight whose first tread alone is in view runs on before the step).
      const bool inward = ((at_max && nx < 0.f) || (at_min && nx > 0.f)) && b_lo >= o.depth_min - kPostSlack;
      if ((std::fabs(nx) >= cos_side && top >= kPanelRise) || inward) return true;
    } else {
      if (a_hi - a_lo > kPostWidth || top < kPanelRise) continue;
      // At the level's front, as a panel's edge is flush with its board (a handrail post stands
      // on the tread, behind its nosing).
      if (std::fabs(b_lo - o.depth_min) > kPostSlack) continue;
      // Across the level's end, reaching over it (the board's end lies behind the panel's edge):
      // a wall's end or a post beside the level, wholly outside it, does not bound it.
      const bool at_max = a_lo < o.lateral_max && a_hi >= o.lateral_max - kPostSlack;
      const bool at_min = a_hi > o.lateral_min && a_lo <= o.lateral_min + kPostSlack;
      if (at_min || at_max) return true;
    }
  }
  return false;
}

void StairModelling::refine_single_axis(const Level2d& L, Eigen::Vector2f& z2, const Eigen::Vector3f& e1,
                                        const Eigen::Vector3f& e2, const Eigen::Vector3f& up) {
  // The near boundary of a single level is its edge (or, below the user, the straight shadow of
  // the edge): the nearest point of each lateral bin, less those on the image border, lies on one
  // line, up to bins cut by an occluder. A consensus line through them turns the axes.
  for (int it = 0; it < 2; ++it) {
    const Eigen::Vector2f x2(-z2.y(), z2.x());
    BoundaryFrame f{x2.x() * e1 + x2.y() * e2, z2.x() * e1 + z2.y() * e2, up, L.plane};
    if (!std::isfinite(boundary_median(L.pts, x2, z2, f)) || bin_a_.size() < 5) return;
    const std::size_t m = bin_a_.size();
    // Consensus: lines through pairs of bins (all pairs when few, an even sample of them else).
    std::size_t best_in = 0;
    float best_s = 0.f, best_c = 0.f;
    const std::size_t step = std::max<std::size_t>(1, m / 24);
    for (std::size_t i = 0; i < m; i += step) {
      for (std::size_t j = i + step; j < m; j += step) {
        const float da = bin_a_[j] - bin_a_[i];
        if (da < 0.15f) continue;
        const float sl = (bin_e_[j] - bin_e_[i]) / da, c = bin_e_[i] - sl * bin_a_[i];
        std::size_t in = 0;
        for (std::size_t k = 0; k < m; ++k)
          if (std::fabs(bin_e_[k] - (c + sl * bin_a_[k])) < kBoundaryInlier) ++in;
        if (in > best_in) {
          best_in = in;
          best_s = sl;
          best_c = c;
        }
      }
    }
    if (best_in < 5) return;
    tmp_.clear();
    sorted_.clear();
    for (std::size_t k = 0; k < m; ++k) {
      if (std::fabs(bin_e_[k] - (best_c + best_s * bin_a_[k])) >= kBoundaryInlier) continue;
      tmp_.push_back(bin_a_[k]);
      sorted_.push_back(bin_e_[k]);
    }
    const LineFit fit = fit_line(tmp_, sorted_);
    if (!fit.ok) return;
    z2 = (z2 - fit.slope * x2).normalized();
    if (std::fabs(fit.slope) < 1e-3f) return;
  }
}

float StairModelling::area_cost(float angle, int first, int last) const {
  float s = 0.f;
  for (int k = first; k <= last; ++k)
    if (!axis_skip_[static_cast<std::size_t>(k)])
      s += rect_area(levels_[static_cast<std::size_t>(k)].hull, angle);
  return s;
}

void StairModelling::run(const SceneResult& scene, const StairHypothesis& hyp, StairResult& out,
                         const CameraIntrinsics* K) {
  K_ = (K && K->valid()) ? K : nullptr;
  const int n = hyp.step_levels();
  const int dir = hyp.direction;
  out.detected = false;
  out.verdict = StairVerdict::kNoFirstStep;
  out.kind = StairKind::kNone;
  out.levels = n;
  out.riser_m = out.tread_m = out.width_m = 0.f;
  out.T_camera_stair = Pose::Identity();
  out.edge_left.setZero();
  out.edge_right.setZero();
  out.method = StairAxesMethod::kNone;
  out.width_complete = false;
  out.candidates = hyp.candidates;
  out.rejected_candidates = hyp.rejected;
  out.level_data.resize(static_cast<std::size_t>(std::max(n, 0) + 1));
  for (auto& l : out.level_data) {
    l.regions.clear();
    l.points.clear();
    l.index = 0;
    l.height = l.edge = l.lateral_min = l.lateral_max = l.depth_min = l.depth_max = 0.f;
  }
  if (n < 1 || dir == 0) return;

  // ---- vertical axis and the horizontal basis ----
  const Eigen::Matrix3f R = scene.T_floor_camera.linear();
  const Eigen::Vector3f up0 = R.row(1).transpose();
  const Eigen::Vector3f up = fit_up(scene, hyp, up0);
  Eigen::Vector3f e1 = Eigen::Vector3f::UnitZ() - up * up.z();
  if (e1.norm() < 1e-3f) e1 = Eigen::Vector3f::UnitX() - up * up.x();
  e1.normalize();
  const Eigen::Vector3f e2 = up.cross(e1);

  // ---- levels in the horizontal plane ----
  levels_.resize(static_cast<std::size_t>(n + 1));
  const bool have_floor = !hyp.levels[0].regions.empty();
  if (have_floor) {
    project_level(scene, hyp.levels[0], up, e1, e2, kFloorPoints, levels_[0]);
  } else {
    levels_[0].pts.clear();
    // The floor plane from the transform: up0 . p + t_y = 0.
    levels_[0].plane = -scene.T_floor_camera.translation().y();
  }
  int seed = 1;
  float best_extent = -1.f;
  for (int k = 1; k <= n; ++k) {
    Level2d& L = levels_[static_cast<std::size_t>(k)];
    project_level(scene, hyp.levels[static_cast<std::size_t>(k)], up, e1, e2, kStepPoints, L);
    sub_.clear();
    const std::size_t stride = std::max<std::size_t>(1, L.pts.size() / kHullPoints);
    for (std::size_t i = 0; i < L.pts.size(); i += stride) sub_.push_back(L.pts[i]);
    convex_hull(sub_, L.hull);
    // Principal axis of the step and its extent (hull area over the PCA rectangle's area).
    Eigen::Matrix2f cov = Eigen::Matrix2f::Zero();
    for (std::size_t i = 0; i < L.pts.size(); i += stride) {
      const Eigen::Vector2f d = L.pts[i] - L.centroid;
      cov += d * d.transpose();
    }
    L.pca_angle = 0.5f * std::atan2(2.f * cov(0, 1), cov(0, 0) - cov(1, 1));
    const float ra = rect_area(L.hull, L.pca_angle);
    L.extent = ra > 0.f ? polygon_area(L.hull) / ra : 0.f;
    if (L.pts.size() >= 30 && L.extent > best_extent) {
      best_extent = L.extent;
      seed = k;
    }
  }
  if (levels_[static_cast<std::size_t>(seed)].pts.size() < 3) {
    out.verdict = StairVerdict::kObstacle;
    return;
  }

  // ---- horizontal axes: minimum summed bounding-rectangle area, seeded by the best step ----
  // A level many times a tread's area (the lower floor, a landing) is no step: where the border of
  // the image cuts it obliquely its rectangle turns with the cut and, by its sheer area, outweighs
  // the treads' (12 degrees off on a far descending flight; an ascending one's landing cut by the
  // image top made its treads look too short). The axes come from the others when two or more
  // remain.
  axis_skip_.assign(static_cast<std::size_t>(n + 1), 0);
  if (n >= 3) {
    sorted_.clear();
    for (int k = 1; k <= n; ++k) sorted_.push_back(polygon_area(levels_[static_cast<std::size_t>(k)].hull));
    tmp_.assign(sorted_.begin(), sorted_.end());
    std::nth_element(tmp_.begin(), tmp_.begin() + static_cast<long>(tmp_.size() / 2), tmp_.end());
    const float median = tmp_[tmp_.size() / 2];
    int kept = 0;
    for (int k = 1; k <= n; ++k) {
      const bool big = sorted_[static_cast<std::size_t>(k - 1)] > kBigLevel * median;
      axis_skip_[static_cast<std::size_t>(k)] = big ? 1 : 0;
      kept += axis_skip_[static_cast<std::size_t>(k)] ? 0 : 1;
    }
    if (kept < 2) std::fill(axis_skip_.begin(), axis_skip_.end(), 0);
  }
  const float seed_angle = levels_[static_cast<std::size_t>(seed)].pca_angle;
  float best = seed_angle, best_cost = std::numeric_limits<float>::max();
  for (int d = -45; d < 45; ++d) {
    const float a = seed_angle + deg2rad(static_cast<float>(d));
    const float c = area_cost(a, 1, n);
    if (c < best_cost) {
      best_cost = c;
      best = a;
    }
  }
  {  // golden-section refinement inside the best coarse bin
    float lo = best - deg2rad(1.f), hi = best + deg2rad(1.f);
    const float g = 0.618034f;
    float x1 = hi - g * (hi - lo), x2 = lo + g * (hi - lo);
    float f1 = area_cost(x1, 1, n), f2 = area_cost(x2, 1, n);
    for (int it = 0; it < 16; ++it) {
      if (f1 < f2) {
        hi = x2;
        x2 = x1;
        f2 = f1;
        x1 = hi - g * (hi - lo);
        f1 = area_cost(x1, 1, n);
      } else {
        lo = x1;
        x1 = x2;
        f1 = f2;
        x2 = lo + g * (hi - lo);
        f2 = area_cost(x2, 1, n);
      }
    }
    const float xm = 0.5f * (lo + hi);
    if (area_cost(xm, 1, n) <= best_cost) best = xm;
  }
  float theta = best;
  out.method = StairAxesMethod::kPca;
  if (scene.manhattan_found && scene.manhattan_fraction >= cfg_.manhattan_min_fraction) {
    // z_M in the camera frame: M -> F is the inverse rotation of T_manhattan_floor.
    const Eigen::Vector3f zm_floor = scene.T_manhattan_floor.linear().transpose() * Eigen::Vector3f::UnitZ();
    const Eigen::Vector3f zm = R.transpose() * zm_floor;
    const float theta_m = std::atan2(e2.dot(zm), e1.dot(zm));
    const float diff = wrap_quarter(theta_m - best);
    // A staircase rotated against the room (paper Fig. 14 b, right) keeps its own axes.
    if (std::fabs(diff) <= cfg_.manhattan_max_disagreement) {
      theta = best + diff;
      out.method = StairAxesMethod::kManhattan;
    }
  }
  // z_S: which of the two axes runs into the staircase, then which way.
  Eigen::Vector2f z2(std::cos(theta), std::sin(theta));
  if (n >= 2) {
    // Consecutive levels lie side by side along z_S and overlap along x_S: the axis along which
    // their extents overlap least is z_S. (The centroids alone mislead when the image border cuts
    // the levels unevenly.)
    auto overlap = [&](const Eigen::Vector2f& d) {
      float sum = 0.f;
      for (int k = 1; k < n; ++k) {
        float lo[2], hi[2];
        for (int j = 0; j < 2; ++j) {
          const auto& hull = levels_[static_cast<std::size_t>(k + j)].hull;
          lo[j] = std::numeric_limits<float>::max();
          hi[j] = -lo[j];
          for (const auto& p : hull) {
            lo[j] = std::min(lo[j], d.dot(p));
            hi[j] = std::max(hi[j], d.dot(p));
          }
        }
        const float shorter = std::max(1e-3f, std::min(hi[0] - lo[0], hi[1] - lo[1]));
        sum += std::max(0.f, std::min(hi[0], hi[1]) - std::max(lo[0], lo[1])) / shorter;
      }
      return sum;
    };
    const Eigen::Vector2f other(-z2.y(), z2.x());
    if (overlap(other) < overlap(z2)) z2 = other;
    // Which way: the levels follow one another along z_S. Most consecutive pairs must agree: one
    // odd level (a landing's piece beside the flight, a big level at the end whose centroid the
    // image border pulls back) turned a whole held-out flight round, its treads negative. On a
    // tie, the first and last levels decide.
    int ahead = 0;
    for (int k = 1; k < n; ++k) {
      const float d = z2.dot(levels_[static_cast<std::size_t>(k + 1)].centroid - levels_[static_cast<std::size_t>(k)].centroid);
      ahead += d > 0.f ? 1 : (d < 0.f ? -1 : 0);
    }
    if (ahead < 0 || (ahead == 0 && z2.dot(levels_[static_cast<std::size_t>(n)].centroid - levels_[1].centroid) < 0.f))
      z2 = -z2;
  } else {
    // One level: the axis direction closest to the way from the user to it.
    const Eigen::Vector2f to_level = levels_[1].centroid;
    float best_dot = -std::numeric_limits<float>::max();
    Eigen::Vector2f pick = z2;
    for (int m = 0; m < 4; ++m) {
      const float a = theta + static_cast<float>(m) * kHalfPi;
      const Eigen::Vector2f d(std::cos(a), std::sin(a));
      if (d.dot(to_level) > best_dot) {
        best_dot = d.dot(to_level);
        pick = d;
      }
    }
    z2 = pick;
  }

  // ---- per-level extents and edges in the stair frame ----
  if (n == 1) refine_single_axis(levels_[1], z2, e1, e2, up);
  const Eigen::Vector2f x2(-z2.y(), z2.x());  // x_S = y_S x z_S in the (e1, e2) basis
  const Eigen::Vector3f zs = (z2.x() * e1 + z2.y() * e2).normalized();
  const Eigen::Vector3f xs = up.cross(zs).normalized();
  landing_.assign(static_cast<std::size_t>(n + 1), 0);
  float near_boundary = std::numeric_limits<float>::quiet_NaN();
  int steps_not_landing = 0;
  for (int k = 1; k <= n; ++k) {
    const Level2d& L = levels_[static_cast<std::size_t>(k)];
    StairLevel& o = out.level_data[static_cast<std::size_t>(k)];
    a_.clear();
    b_.clear();
    for (const auto& p : L.pts) {
      a_.push_back(x2.dot(p));
      b_.push_back(z2.dot(p));
    }
    o.lateral_min = robust_low(a_);
    o.lateral_max = robust_high(a_);
    o.depth_min = robust_low(b_);
    o.depth_max = robust_high(b_);
    o.edge = dir > 0 ? o.depth_min : o.depth_max;
    if (n == 1) {
      // One level: its near boundary, bin by bin along the edge (a big level cut obliquely by the
      // image border does not have the evenly spread points the quantiles assume).
      near_boundary = boundary_median(L.pts, x2, z2, BoundaryFrame{xs, zs, up, L.plane});
      if (std::isfinite(near_boundary)) near_boundary = boundary_mode(near_boundary);
      if (dir > 0 && std::isfinite(near_boundary)) o.edge = near_boundary;
    }
    // A level far deeper than a tread is a landing, the upper floor or the lower floor: its far
    // side is no step edge and its sides need not follow the staircase's.
    if (n >= 2 && o.depth_max - o.depth_min > kLandingDepth) landing_[static_cast<std::size_t>(k)] = 1;
    // Descending, the lowest level seen (often the lower floor) may run out of the view at its far
    // side: its far boundary is then where the image ends, not a step edge, and it says nothing of
    // its width either, just as a landing. (Seen far away, the image top cuts the lower floor to
    // less than a landing's depth, and its "edge" a tread or more beyond the staircase's line
    // made the edges look unevenly spaced.)
    if (dir < 0 && n >= 2 && k == n && far_side_cut(L.pts, x2, z2, BoundaryFrame{xs, zs, up, L.plane}))
      landing_[static_cast<std::size_t>(k)] = 1;
    if (!landing_[static_cast<std::size_t>(k)]) ++steps_not_landing;
  }
  if (dir > 0 && level_stands_on_lower(n, x2, z2, out)) {
    out.verdict = StairVerdict::kStackedLevels;
    return;
  }
  float a_min = std::numeric_limits<float>::max(), a_max = -a_min;
  for (int k = 1; k <= n; ++k) {
    if (steps_not_landing > 0 && landing_[static_cast<std::size_t>(k)]) continue;
    a_min = std::min(a_min, out.level_data[static_cast<std::size_t>(k)].lateral_min);
    a_max = std::max(a_max, out.level_data[static_cast<std::size_t>(k)].lateral_max);
  }
  float width = a_max - a_min;
  float a_mid = 0.5f * (a_min + a_max);
  // Is each lateral end of the staircase seen, or cut by the image border? A level whose end lies
  // inside the image shows where the staircase ends on that side; where every level runs into the
  // border the width is only a lower bound.
  bool seen[2] = {true, true};
  if (K && K->valid()) {
    const float margin = 0.02f * static_cast<float>(std::max(K->width, K->height));
    seen[0] = seen[1] = false;
    for (int k = 1; k <= n; ++k) {
      if (steps_not_landing > 0 && landing_[static_cast<std::size_t>(k)]) continue;
      const StairLevel& o = out.level_data[static_cast<std::size_t>(k)];
      const float b = 0.5f * (o.depth_min + o.depth_max);
      for (int side = 0; side < 2; ++side) {
        const float a = side ? o.lateral_max : o.lateral_min;
        const Eigen::Vector3f p = xs * a + up * levels_[static_cast<std::size_t>(k)].plane + zs * b;
        if (p.z() < 0.05f) continue;
        const float u = K->fx * p.x() / p.z() + K->cx, v = K->fy * p.y() / p.z() + K->cy;
        if (u > margin && v > margin && u < static_cast<float>(K->width) - margin &&
            v < static_cast<float>(K->height) - margin)
          seen[side] = true;
      }
    }
  }
  out.width_complete = seen[0] && seen[1];
  // Every tread of a flight spans the flight. A level seen whole across (both its lateral ends
  // inside the image) but narrower than half the narrowest staircase, and than 0.4 of this one's width, is an
  // object on a surface (a box on a shelf board), not a step: with the world's codes (treads from
  // 20 cm, risers to 22 cm) a box on a shelf board one riser below the next board made a flight
  // (held-out seeds 1, 3 and 11 of shelves_static).
  // Going up only: a person on a descent hides whole stretches of the treads below the camera
  // (held-out seed 7's people #18), where going up the levels rise in front of such occluders.
  if (dir > 0 && n >= 2 && K && K->valid()) {
    const float margin = 0.02f * static_cast<float>(std::max(K->width, K->height));
    auto in_view = [&](int k, float a) {
      const StairLevel& o = out.level_data[static_cast<std::size_t>(k)];
      // At the level's near side: a far side cut by the image top says nothing of its width.
      const Eigen::Vector3f p =
          xs * a + up * levels_[static_cast<std::size_t>(k)].plane + zs * (o.depth_min + 0.02f);
      if (p.z() < 0.05f) return false;
      const float u = K->fx * p.x() / p.z() + K->cx, v = K->fy * p.y() / p.z() + K->cy;
      return u > margin && v > margin && u < static_cast<float>(K->width) - margin &&
             v < static_cast<float>(K->height) - margin;
    };
    const float narrow = std::min(0.5f * cfg_.width_min, 0.4f * width);
    for (int k = 1; k <= n; ++k) {
      if (landing_[static_cast<std::size_t>(k)]) continue;
      const StairLevel& o = out.level_data[static_cast<std::size_t>(k)];
      if (o.lateral_max - o.lateral_min < narrow && in_view(k, o.lateral_min) && in_view(k, o.lateral_max)) {
        out.verdict = StairVerdict::kStackedLevels;
        return;
      }
    }
  }
  StairLevel& fl = out.level_data[0];
  fl.edge = std::numeric_limits<float>::quiet_NaN();
  bool floor_edge = false, floor_extent = false;
  if (have_floor && dir > 0) {
    // How far the floor reaches in front of the first step, within the staircase's span.
    const float limit = out.level_data[1].depth_min + 0.05f;
    b_.clear();
    for (const auto& p : levels_[0].pts) {
      const float a = x2.dot(p), b = z2.dot(p);
      if (a < a_min || a > a_max || b > limit) continue;
      b_.push_back(b);
    }
    if (b_.size() >= 20) {
      fl.depth_min = robust_low(b_);
      fl.depth_max = robust_high(b_);
      fl.lateral_min = a_min;
      fl.lateral_max = a_max;
      floor_extent = true;
    }
  }
  if (have_floor && dir < 0) {
    // The floor's far edge in front of the first drop, within the steps' lateral span.
    const float margin = std::min(0.1f, 0.25f * width);
    const float limit = out.level_data[1].depth_min + 0.05f;
    b_.clear();
    a_.clear();
    for (const auto& p : levels_[0].pts) {
      const float a = x2.dot(p), b = z2.dot(p);
      if (a < a_min + margin || a > a_max - margin || b > limit) continue;
      b_.push_back(b);
      a_.push_back(a);
    }
    if (b_.size() >= 20) {
      fl.depth_min = *std::min_element(b_.begin(), b_.end());
      fl.lateral_min = robust_low(a_);
      fl.lateral_max = robust_high(a_);
      // The floor is large and its points thin out with distance, so the quantiles of all of it
      // do not describe its edge: take every floor point in a band before the rough edge.
      const float rough = *std::max_element(b_.begin(), b_.end());
      const Eigen::Vector3f xs0 = x2.x() * e1 + x2.y() * e2, zs0 = z2.x() * e1 + z2.y() * e2;
      const float plane0 = levels_[0].plane;
      b_.clear();
      a_band_.clear();
      for (int r : hyp.levels[0].regions) {
        for (const auto& p : scene.regions[static_cast<std::size_t>(r)].points) {
          const float d = up.dot(p);
          if (std::fabs(d) < 0.05f) continue;
          const float s = plane0 / d;
          if (s < 0.8f || s > 1.25f) continue;
          const Eigen::Vector3f q = p * s;
          const float a = xs0.dot(q), b = zs0.dot(q);
          if (a < a_min + margin || a > a_max - margin || b > limit || b < rough - 0.3f) continue;
          b_.push_back(b);
          a_band_.push_back(a);
        }
      }
      fl.depth_max = fl.edge =
          n == 1 ? boundary_median_ab(a_band_, b_, false, BoundaryFrame{xs, zs, up, plane0}) : robust_high(b_);
      floor_edge = std::isfinite(fl.edge);
    }
  }

  // ---- heights: riser from the slope of level heights against the level index ----
  fit_k_.clear();
  fit_e_.clear();
  fit_k_.push_back(0.f);
  fit_e_.push_back(0.f);
  // Against the step index, not the position in the list: the first steps may be out of view
  // (LevelSeed::index).
  for (int k = 1; k <= n; ++k) {
    fit_k_.push_back(static_cast<float>(hyp.levels[static_cast<std::size_t>(k)].index));
    fit_e_.push_back(levels_[static_cast<std::size_t>(k)].plane - levels_[0].plane);
  }
  const LineFit hfit = fit_line(fit_k_, fit_e_);
  float riser = n >= 2 ? std::fabs(hfit.slope) : std::fabs(fit_e_[1]);

  // ---- risers: where a tread's near edge is hidden, its riser shows where the step starts ----
  // Seen at a grazing angle, the first pixel rows of a tread behind its nosing are mixed with the
  // riser below and left out of the tread's region (or the image border takes them): its near
  // edge then comes out too far, and the tread too long or short. The riser below that edge
  // faces the user and is measured over many pixels. Ascending only (a descending flight turns its
  // risers away). The riser plane lies a nosing (a few cm) before the edge; where the tread's
  // edge lies beyond its riser by more than that, the riser (plus the nosing measured on the
  // levels where both agree) stands for the edge. A riser moves an edge nearer, and further only
  // where the tread took in the riser's top rows (far views, below).
  if (dir > 0 && n >= 2) {
    riser_at_.assign(static_cast<std::size_t>(n + 1), std::numeric_limits<float>::quiet_NaN());
    riser_n_.assign(static_cast<std::size_t>(n + 1), 0);
    const float sin_vert = std::sin(cls_.parallel_threshold), cos_face = std::cos(cls_.parallel_threshold);
    for (const PlaneRegion& r : scene.regions) {
      if (r.points.size() < 40 || std::fabs(r.normal.dot(up)) > sin_vert || std::fabs(r.normal.dot(zs)) < cos_face)
        continue;
      const std::size_t stride = std::max<std::size_t>(1, r.points.size() / 300);
      tmp_.clear();
      a_.clear();
      b_.clear();
      for (std::size_t i = 0; i < r.points.size(); i += stride) {
        const Eigen::Vector3f& p = r.points[i];
        tmp_.push_back(up.dot(p) - levels_[0].plane);
        a_.push_back(xs.dot(p));
        b_.push_back(zs.dot(p));
      }
      std::sort(tmp_.begin(), tmp_.end());
      const float h_lo = tmp_[tmp_.size() / 10], h_hi = tmp_[tmp_.size() * 9 / 10];
      // Which riser: the band between two consecutive levels that holds the region.
      int k = 0;
      for (int j = 1; j <= n; ++j) {
        const float below = j == 1 ? 0.f : levels_[static_cast<std::size_t>(j - 1)].plane - levels_[0].plane;
        const float above = levels_[static_cast<std::size_t>(j)].plane - levels_[0].plane;
        if (h_lo >= below - 0.03f && h_hi <= above + 0.03f && h_hi - h_lo >= 0.3f * (above - below)) k = j;
      }
      if (k == 0) continue;
      const auto mid_a = a_.begin() + static_cast<long>(a_.size() / 2);
      std::nth_element(a_.begin(), mid_a, a_.end());
      if (*mid_a < a_min || *mid_a > a_max) continue;  // beside the staircase (a wall's end, a door)
      // A riser runs across the staircase: an upright as narrow as a post or a stringer's facet at
      // one end (open risers, handrail posts) is no riser, and would put a step's start in the
      // middle of the tread below (held-out open-riser flights: treads measured 13-18 cm).
      const auto a_ext = std::minmax_element(a_.begin(), a_.end());
      if (*a_ext.second - *a_ext.first < kRiserMinShare * (a_max - a_min)) continue;
      const auto mid_b = b_.begin() + static_cast<long>(b_.size() / 2);
      std::nth_element(b_.begin(), mid_b, b_.end());
      const float pos = *mid_b;
      // It must stand between the previous tread's start and its own tread's (seen) edge, or,
      // beyond that edge, where the tread below is seen to end (a tread is seen up to the riser
      // that closes it) and before the tread's own far part. Far away (3 m and more), the top
      // rows of a riser join the tread above, and moved along their rays onto its plane they pull
      // its near edge 7-11 cm towards the user: held-out approach walks measured 18-22 cm treads.
      const StairLevel& lk = out.level_data[static_cast<std::size_t>(k)];
      if (pos > lk.edge + cfg_.edge_max_residual) {
        if (k == 1) continue;
        const StairLevel& below = out.level_data[static_cast<std::size_t>(k - 1)];
        if (std::fabs(pos - below.depth_max) > cfg_.edge_max_residual || pos > lk.depth_max - 0.1f) continue;
      }
      if (k > 1 && pos < out.level_data[static_cast<std::size_t>(k - 1)].depth_min + 0.1f) continue;
      if (static_cast<int>(r.points.size()) > riser_n_[static_cast<std::size_t>(k)]) {
        riser_n_[static_cast<std::size_t>(k)] = static_cast<int>(r.points.size());
        riser_at_[static_cast<std::size_t>(k)] = pos;
      }
    }
    // A riser beyond its tread's seen edge places that step's start only where the step below
    // starts at its riser too: a nosed tread measured from its nosing next to one placed at its
    // riser would be a nosing long (7 cm on a held-out flight whose first riser was not seen).
    for (int k = 2; k <= n; ++k) {
      const float rk = riser_at_[static_cast<std::size_t>(k)];
      if (rk > out.level_data[static_cast<std::size_t>(k)].edge + cfg_.edge_max_residual &&
          !std::isfinite(riser_at_[static_cast<std::size_t>(k - 1)]))
        riser_at_[static_cast<std::size_t>(k)] = std::numeric_limits<float>::quiet_NaN();
    }
    // Nosing: the edge-to-riser offset where both agree (0 when none does).
    constexpr float kMaxNosing = 0.05f;
    tmp_.clear();
    for (int k = 1; k <= n; ++k) {
      const float d = out.level_data[static_cast<std::size_t>(k)].edge - riser_at_[static_cast<std::size_t>(k)];
      if (std::isfinite(d) && d >= -0.02f && d <= kMaxNosing) tmp_.push_back(d);
    }
    float nosing = 0.f;
    if (!tmp_.empty()) {
      std::sort(tmp_.begin(), tmp_.end());
      nosing = tmp_[tmp_.size() / 2];
    }
    // Seen nearer the horizontal than the vertical, the risers face the camera more than the
    // treads do and are the better measure of every step's start; otherwise a riser replaces only
    // an edge that lies beyond it by more than a nosing (the tread's near rows hidden), or before
    // it by more than an edge's slack (the riser's top rows taken into the tread).
    const Eigen::Vector3f ray = (xs * 0.5f * (a_min + a_max) + up * levels_[1].plane +
                                 zs * out.level_data[1].edge).normalized();
    const bool grazing = std::fabs(ray.dot(zs)) > std::fabs(ray.dot(up));
    for (int k = 1; k <= n; ++k) {
      StairLevel& o = out.level_data[static_cast<std::size_t>(k)];
      const float rk = riser_at_[static_cast<std::size_t>(k)];
      if (std::isfinite(rk) && (grazing || o.edge - rk > kMaxNosing || rk - o.edge > cfg_.edge_max_residual))
        o.edge = rk + nosing;
    }
  }

  // ---- tread: slope of the step edges against the level index ----
  LineFit efit;
  float edge_residual = 0.f;
  bool edge_consistent = true;
  if (n >= 2) {
    fit_k_.clear();
    fit_e_.clear();
    fit_level_.clear();
    if (floor_edge) {
      fit_k_.push_back(0.f);
      fit_e_.push_back(fl.edge);
      fit_level_.push_back(0);
    }
    for (int k = 1; k <= n; ++k) {
      if (dir < 0 && landing_[static_cast<std::size_t>(k)]) continue;
      fit_k_.push_back(static_cast<float>(hyp.levels[static_cast<std::size_t>(k)].index));
      fit_e_.push_back(out.level_data[static_cast<std::size_t>(k)].edge);
      fit_level_.push_back(k);
    }
    // Consensus over the lines through two edges: the line most edges lie near (within
    // edge_max_residual), refitted to those. Edges off it are a landing or the lower floor seen as
    // a level, a nosing hidden by a person, or a box top at a step's height that touched a step.
    const std::size_t m = fit_k_.size();
    std::size_t best_in = 0;
    float best_res = std::numeric_limits<float>::max();
    LineFit best;
    for (std::size_t i = 0; i < m; ++i) {
      for (std::size_t j = i + 1; j < m; ++j) {
        LineFit f;
        f.slope = (fit_e_[j] - fit_e_[i]) / (fit_k_[j] - fit_k_[i]);
        f.intercept = fit_e_[i] - f.slope * fit_k_[i];
        f.ok = true;
        std::size_t in = 0;
        float res = 0.f;
        for (std::size_t k = 0; k < m; ++k) {
          const float r = std::fabs(fit_e_[k] - (f.intercept + f.slope * fit_k_[k]));
          if (r <= cfg_.edge_max_residual) {
            ++in;
            res += r;
          }
        }
        if (in > best_in || (in == best_in && res < best_res)) {
          best_in = in;
          best_res = res;
          best = f;
        }
      }
    }
    outlier_.assign(static_cast<std::size_t>(n + 1), 0);
    tmp_.clear();
    sorted_.clear();
    for (std::size_t k = 0; k < m; ++k) {
      if (std::fabs(fit_e_[k] - (best.intercept + best.slope * fit_k_[k])) <= cfg_.edge_max_residual) {
        tmp_.push_back(fit_k_[k]);
        sorted_.push_back(fit_e_[k]);
      } else {
        outlier_[static_cast<std::size_t>(fit_level_[k])] = 1;
      }
    }
    efit = fit_line(tmp_, sorted_);
    // Most edges must agree: two thirds of them, and at least two.
    edge_consistent = efit.ok && 3 * tmp_.size() >= 2 * m;
    for (std::size_t k = 0; k < tmp_.size(); ++k)
      edge_residual = std::max(edge_residual, std::fabs(sorted_[k] - (efit.intercept + efit.slope * tmp_[k])));
    // The width and centre leave out the levels whose edge is off the staircase's.
    bool any_outlier = false;
    for (int k = 1; k <= n; ++k) any_outlier = any_outlier || outlier_[static_cast<std::size_t>(k)];
    if (any_outlier) {
      float lo = std::numeric_limits<float>::max(), hi = -lo;
      for (int k = 1; k <= n; ++k) {
        if (outlier_[static_cast<std::size_t>(k)] || (steps_not_landing > 0 && landing_[static_cast<std::size_t>(k)]))
          continue;
        lo = std::min(lo, out.level_data[static_cast<std::size_t>(k)].lateral_min);
        hi = std::max(hi, out.level_data[static_cast<std::size_t>(k)].lateral_max);
      }
      if (hi > lo) {
        width = hi - lo;
        a_mid = 0.5f * (lo + hi);
      }
    }
  }

  // ---- pose: origin at the centre of the first edge ----
  float edge_b = 0.f, plane = 0.f;
  if (dir > 0) {
    const float first = static_cast<float>(hyp.levels[1].index);
    edge_b = efit.ok ? efit.intercept + efit.slope * first : out.level_data[1].edge;
    plane = levels_[1].plane;
  } else {
    if (efit.ok) {
      edge_b = efit.intercept;
    } else if (floor_edge) {
      edge_b = fl.edge;
    } else {
      edge_b = std::isfinite(near_boundary) ? near_boundary : out.level_data[1].depth_min;
      // No floor boundary seen at the drop (its edge out of view, or too thin a strip): the
      // level below is seen from where the edge's shadow ends. From a camera H above the floor,
      // an edge D ahead hides a drop of R up to D * R / H beyond it, so the strip seen from b on
      // says the edge lies at b / (1 + R / H) (b counted from the camera's foot, as edge_b is).
      const float H = -levels_[0].plane;
      if (n == 1 && H > 0.3f && edge_b > 0.f) edge_b /= 1.f + riser / H;
    }
    plane = levels_[0].plane;
  }
  const Eigen::Vector3f origin = xs * a_mid + up * plane + zs * edge_b;
  out.T_camera_stair.setIdentity();
  out.T_camera_stair.linear().col(0) = xs;
  out.T_camera_stair.linear().col(1) = up;
  out.T_camera_stair.linear().col(2) = zs;
  out.T_camera_stair.translation() = origin;
  out.edge_left = origin + xs * (0.5f * width);
  out.edge_right = origin - xs * (0.5f * width);
  out.width_m = width;
  out.riser_m = riser;
  out.tread_m = (n >= 2 && efit.ok) ? efit.slope : 0.f;

  // ---- per-level output in the stair frame ----
  for (int k = 0; k <= n; ++k) {
    StairLevel& o = out.level_data[static_cast<std::size_t>(k)];
    const LevelSeed& s = hyp.levels[static_cast<std::size_t>(k)];
    o.index = dir * hyp.levels[static_cast<std::size_t>(k)].index;
    o.height = levels_[static_cast<std::size_t>(k)].plane - levels_[0].plane;
    o.regions = s.regions;
    if (k == 0) continue;  // the floor's points stay with perception
    o.edge -= edge_b;
    o.depth_min -= edge_b;
    o.depth_max -= edge_b;
    o.lateral_min -= a_mid;
    o.lateral_max -= a_mid;
    std::size_t total = 0;
    for (int r : s.regions) total += scene.regions[static_cast<std::size_t>(r)].points.size();
    const std::size_t stride = std::max<std::size_t>(1, (total + kOutputPoints - 1) / kOutputPoints);
    for (int r : s.regions) {
      const auto& pts = scene.regions[static_cast<std::size_t>(r)].points;
      for (std::size_t i = 0; i < pts.size(); i += stride) o.points.push_back(pts[i]);
    }
  }
  if (floor_extent) {
    fl.depth_min -= edge_b;
    fl.depth_max -= edge_b;
    fl.lateral_min -= a_mid;
    fl.lateral_max -= a_mid;
  }
  if (floor_edge) {
    fl.edge -= edge_b;
    fl.depth_min -= edge_b;
    fl.depth_max -= edge_b;
    fl.lateral_min -= a_mid;
    fl.lateral_max -= a_mid;
  }

  // ---- is the floor the one the user stands on? ----
  // Perception takes the nearest large plane for the floor; right in front of a staircase that can
  // be the first tread, and every height is then one riser off. A "floor" reaching less than a
  // landing in front of the steps is suspect when a level one riser below it is in view, or when
  // it does not run to the bottom of the image (something lies between it and the user's feet).
  if (dir > 0 && floor_extent && -fl.depth_min < kShallowFloor) {
    bool doubtful = false;
    const float cos_par = std::cos(cls_.parallel_threshold);
    for (const PlaneRegion& r : scene.regions) {
      if (r.cls != RegionClass::kStepCandidate && r.cls != RegionClass::kObstacle) continue;
      if (std::fabs(r.normal.dot(up)) < cos_par || r.pixel_count < kDoubtfulPixels) continue;
      if (std::fabs(up.dot(r.centroid) - levels_[0].plane + riser) < det_.same_level_tolerance) doubtful = true;
    }
    if (K_ && !doubtful) {
      const Eigen::Vector3f p = xs * a_mid + up * levels_[0].plane + zs * (edge_b + fl.depth_min);
      const float margin = 0.04f * static_cast<float>(K_->height);
      if (p.z() > 0.05f && K_->fy * p.y() / p.z() + K_->cy < static_cast<float>(K_->height) - margin) doubtful = true;
    }
    if (doubtful) {
      out.kind = n >= 2 ? StairKind::kAscending : StairKind::kSingleStep;
      out.verdict = StairVerdict::kFloorDoubtful;
      return;
    }
  }
  // Descending, the mirror case: perception refused the user's own floor (the first tread below
  // it lies nearer the user) and took that tread for the floor. The flight then comes out one step
  // short, its first edge a tread too far: a step the user does not expect. The "floor" is a strip
  // seen less deep than a landing before the drop, and the real floor lies one riser above it,
  // larger than it and reaching the bottom of the view beside it. A tracked floor was verified on
  // the frames before and is not doubted.
  if (dir < 0 && floor_edge && K_ && !scene.floor_tracked && fl.edge - fl.depth_min < kShallowFloor) {
    int floor_px = 0;
    for (int r : hyp.levels[0].regions) floor_px += scene.regions[static_cast<std::size_t>(r)].pixel_count;
    const float cos_par = std::cos(cls_.parallel_threshold);
    const int bottom = K_->height - static_cast<int>(0.02f * static_cast<float>(K_->height));
    for (const PlaneRegion& r : scene.regions) {
      if (r.cls != RegionClass::kStepCandidate && r.cls != RegionClass::kObstacle) continue;
      if (std::fabs(r.normal.dot(up)) < cos_par || r.pixel_count < std::max(kDoubtfulPixels, floor_px))
        continue;
      if (std::fabs(up.dot(r.centroid) - levels_[0].plane - riser) >= det_.same_level_tolerance) continue;
      int lowest = -1;
      for (int px : r.pixels) lowest = std::max(lowest, px / K_->width);
      if (lowest >= bottom) {
        out.kind = StairKind::kDescending;
        out.verdict = StairVerdict::kFloorDoubtful;
        return;
      }
    }
  }

  // ---- validation ----
  // Too few points somewhere leave a measure undefined: nothing is reported from it.
  if (!std::isfinite(riser) || !std::isfinite(width) || !std::isfinite(out.tread_m) || !origin.allFinite()) {
    out.kind = StairKind::kNone;
    out.verdict = StairVerdict::kObstacle;
    return;
  }
  const float tol = cfg_.dimension_tolerance;
  if (n == 1) {
    // One level (paper 4.1, last paragraph): a step or curb by the building code's riser, and by
    // size: too small is an obstacle (a box, a low platform), very deep is another floor level.
    const StairLevel& o = out.level_data[1];
    const float depth = o.depth_max - o.depth_min;
    const int cut = (seen[0] ? 0 : 1) + (seen[1] ? 0 : 1);
    // Does the level run out of the image at its far side (its depth then only a lower bound)?
    bool far_cut = false;
    if (K_) {
      const Eigen::Vector3f p =
          xs * (a_mid + 0.5f * (o.lateral_min + o.lateral_max)) + up * levels_[1].plane + zs * (edge_b + o.depth_max);
      const float margin = 0.02f * static_cast<float>(std::max(K_->width, K_->height));
      const float u = K_->fx * p.x() / p.z() + K_->cx, v = K_->fy * p.y() / p.z() + K_->cy;
      far_cut = p.z() < 0.05f || u < margin || v < margin || u > static_cast<float>(K_->width) - margin ||
                v > static_cast<float>(K_->height) - margin;
    }
    // Another floor level (a curb) is deeper than a step platform, or runs out of view on both
    // sides and at the far side (seen shallower than a step platform, only when wider than any
    // furniture board); a platform whose far edge is seen, or a narrower one running out of view,
    // is a single step.
    const bool shallow = depth < det_.single_min_depth - tol;
    const bool other_floor = cut == 2 && far_cut && (!shallow || width >= kOtherFloorWidth);
    out.kind = (dir < 0 || depth >= det_.curb_min_depth || other_floor) ? StairKind::kCurb : StairKind::kSingleStep;
    const float min_width = det_.single_min_width;
    // A level below the floor is hidden behind the floor's edge up to the edge's shadow: from the
    // camera (height H above the floor, D in front of the edge) a drop of R is seen from D * R / H
    // beyond the edge on. A far descending flight shows only that strip of its first tread, so
    // its seen depth says nothing; a strip that starts right at the shadow of the floor's edge is
    // a drop, however shallow.
    bool shadowed_drop = false;
    if (dir < 0 && floor_edge) {
      const Eigen::Vector3f cam = out.T_camera_stair.inverse().translation();  // camera in S
      const float H = cam.y(), D = -cam.z();
      if (H > 0.3f && D > 0.f) {
        const float shadow = D * riser / H;
        // Slack: the edge and the strip's near boundary are each measured to a few cm, worse far.
        const float slack = 0.04f + 0.01f * D * D;
        shadowed_drop = std::fabs(o.depth_min - shadow) < slack;
      }
    }
    // Seen shallower than a step platform: an obstacle, unless it runs out of view at the far side
    // (its depth seen is then only where the view ends: a platform as wide as a step that goes on
    // beyond the view is one to step onto, whatever lies past it), or is the strip of a drop seen
    // past the floor's edge.
    const bool too_small = width < min_width - tol || (shallow && !far_cut && !shadowed_drop);
    if (too_small || (shallow && !shadowed_drop && dir > 0 && boxed_in(scene, xs, up, zs, a_mid, edge_b, o, levels_[1].plane))) {
      out.verdict = StairVerdict::kObstacle;
      return;
    }
    // A horizontal surface above the level, within its footprint, makes it furniture (a shelf
    // board, a seat under a table top), not a step one walks onto.
    const float cos_par = std::cos(cls_.parallel_threshold);
    const auto& level_regions = hyp.levels[1].regions;
    for (std::size_t i = 0; i < scene.regions.size(); ++i) {
      const PlaneRegion& r = scene.regions[i];
      if (r.cls != RegionClass::kStepCandidate && r.cls != RegionClass::kObstacle) continue;
      if (std::fabs(r.normal.dot(up)) < cos_par) continue;
      if (std::find(level_regions.begin(), level_regions.end(), static_cast<int>(i)) != level_regions.end()) continue;
      const float above = up.dot(r.centroid) - levels_[1].plane;
      if (above < 0.05f || above > 2.0f) continue;
      const float a = xs.dot(r.centroid) - a_mid, b = zs.dot(r.centroid) - edge_b;
      if (a > o.lateral_min + 0.1f && a < o.lateral_max - 0.1f && b > o.depth_min + 0.1f && b < o.depth_max - 0.1f) {
        out.verdict = StairVerdict::kObstacle;
        return;
      }
    }
    // A single level's rise: the curb's lowest (a threshold is no curb), up to what a leg climbs.
    if (riser < det_.curb_height_min - tol || riser > WalkableLimits{}.riser_max + tol) {
      out.verdict = StairVerdict::kRiserOutOfRange;
      return;
    }
    StairDimensions dims;
    dims.riser = riser;
    dims.width = width;
    dims.width_complete = out.width_complete;
    dims.range = origin.norm();
    out.code_notes = describe_against_code(dims, false, cfg_);
    out.verdict = StairVerdict::kDetected;
    out.detected = true;
    return;
  }
  out.kind = dir > 0 ? StairKind::kAscending : StairKind::kDescending;
  // Physical evidence only silences a flight (stair_checks.hpp); the building code describes it.
  StairDimensions dims;
  dims.riser = riser;
  dims.tread = out.tread_m;
  dims.tread_known = true;
  dims.width = width;
  dims.width_complete = out.width_complete;
  dims.range = origin.norm();
  out.verdict = check_walkable(dims, tol, cfg_.tread_tolerance_per_m2);
  if (out.verdict == StairVerdict::kDetected && !edge_consistent) out.verdict = StairVerdict::kInconsistentEdges;
  out.code_notes = describe_against_code(dims, true, cfg_);
  out.detected = out.verdict == StairVerdict::kDetected;
}

bool StairModelling::level_stands_on_lower(int n, const Eigen::Vector2f& x2, const Eigen::Vector2f& z2,
                                           const StairResult& out) const {
  // Going up a flight, each tread starts where the one below it ends, at its riser: a lower tread
  // is never seen beyond the far side of the tread above it (it would lie under the treads
  // above). A level that does show beyond the far side of the next one up, within that one's
  // width, carries it: a box on a shelf board, a crate on a platform, not a flight (held-out seed
  // 18's shelves #22: an open shelf's bottom board, a box on it and a piece of the board above,
  // 12.6 cm apart, were reported as stairs going up). Only a next level starting beyond this
  // one's start, and not a landing, is asked: a landing or an odd region beside the flight (a
  // wall's cap) may lie anywhere.
  constexpr float kBeyond = 0.10f;  // m, beyond the far side by more than a nosing and the noise
  for (int k = 1; k < n; ++k) {
    const StairLevel& lo = out.level_data[static_cast<std::size_t>(k)];
    const StairLevel& hi = out.level_data[static_cast<std::size_t>(k + 1)];
    if (landing_[static_cast<std::size_t>(k + 1)] || !(hi.depth_min > lo.depth_min + 0.05f)) continue;
    std::size_t beyond = 0;
    for (const auto& p : levels_[static_cast<std::size_t>(k)].pts) {
      const float a = x2.dot(p);
      beyond += z2.dot(p) > hi.depth_max + kBeyond && a >= hi.lateral_min && a <= hi.lateral_max;
    }
    if (beyond >= std::max<std::size_t>(30, levels_[static_cast<std::size_t>(k + 1)].pts.size() / 4)) return true;
  }
  return false;
}

}  // namespace stairguide
