// Stair modelling, phase "profile" (stair_profile.hpp): the riser from the level heights, the step
// edges placed by the risers facing the user, the tread from the edges by consensus.
#include "stairguide/stairs/stair_profile.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "stair_modelling_internal.hpp"
#include "stairguide/stairs/stair_modelling.hpp"

namespace stairguide {

using namespace modelling;

EdgeLineFit fit_edge_line(const std::vector<float>& k_all, const std::vector<float>& e_all,
                          float max_residual, std::vector<char>& inlier, std::vector<float>& k_in,
                          std::vector<float>& e_in) {
  // Consensus over the lines through two edges: the line most edges lie near (within
  // max_residual), refitted to those.
  const std::vector<float>& fit_k_ = k_all;
  const std::vector<float>& fit_e_ = e_all;
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
        if (r <= max_residual) {
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
  inlier.assign(m, 0);
  k_in.clear();
  e_in.clear();
  for (std::size_t k = 0; k < m; ++k) {
    if (std::fabs(fit_e_[k] - (best.intercept + best.slope * fit_k_[k])) <= max_residual) {
      k_in.push_back(fit_k_[k]);
      e_in.push_back(fit_e_[k]);
      inlier[k] = 1;
    }
  }
  EdgeLineFit fit;
  fit.line = fit_line(k_in, e_in);
  // Most edges must agree: two thirds of them, and at least two.
  fit.consistent = fit.line.ok && 3 * k_in.size() >= 2 * m;
  for (std::size_t k = 0; k < k_in.size(); ++k)
    fit.max_residual =
        std::max(fit.max_residual, std::fabs(e_in[k] - (fit.line.intercept + fit.line.slope * k_in[k])));
  return fit;
}

float StairModelling::fit_riser(const StairHypothesis& hyp, int n) {
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
  return n >= 2 ? std::fabs(hfit.slope) : std::fabs(fit_e_[1]);
}

// ---- risers: where a tread's near edge is hidden, its riser shows where the step starts ----
// Seen at a grazing angle, the first pixel rows of a tread behind its nosing are mixed with the
// riser below and left out of the tread's region (or the image border takes them): its near
// edge then comes out too far, and the tread too long or short. The riser below that edge
// faces the user and is measured over many pixels. Ascending only (a descending flight turns its
// risers away). The riser plane lies a nosing (a few cm) before the edge; where the tread's
// edge lies beyond its riser by more than that, the riser (plus the nosing measured on the
// levels where both agree) stands for the edge. A riser moves an edge nearer, and further only
// where the tread took in the riser's top rows (far views, below).
void StairModelling::find_risers(const SceneResult& scene, const StairFrame& frame, int n,
                                 const StairSpan& span, const StairResult& out) {
  const Eigen::Vector3f &xs = frame.xs, &zs = frame.zs, &up = frame.up;
  const float a_min = span.a_min, a_max = span.a_max;
  riser_at_.assign(static_cast<std::size_t>(n + 1), std::numeric_limits<float>::quiet_NaN());
  riser_n_.assign(static_cast<std::size_t>(n + 1), 0);
  const float sin_vert = std::sin(cls_.parallel_threshold), cos_face = std::cos(cls_.parallel_threshold);
  for (const PlaneRegion& r : scene.regions) {
    if (r.points.size() < 40 || std::fabs(r.normal.dot(up)) > sin_vert ||
        std::fabs(r.normal.dot(zs)) < cos_face)
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
}

void StairModelling::place_edges_at_risers(const SceneResult& scene, const StairFrame& frame, int n,
                                           const StairSpan& span, StairResult& out) {
  const Eigen::Vector3f &xs = frame.xs, &zs = frame.zs, &up = frame.up;
  const float a_min = span.a_min, a_max = span.a_max;
  find_risers(scene, frame, n, span, out);
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
  const Eigen::Vector3f ray =
      (xs * 0.5f * (a_min + a_max) + up * levels_[1].plane + zs * out.level_data[1].edge).normalized();
  const bool grazing = std::fabs(ray.dot(zs)) > std::fabs(ray.dot(up));
  for (int k = 1; k <= n; ++k) {
    StairLevel& o = out.level_data[static_cast<std::size_t>(k)];
    const float rk = riser_at_[static_cast<std::size_t>(k)];
    if (std::isfinite(rk) && (grazing || o.edge - rk > kMaxNosing || rk - o.edge > cfg_.edge_max_residual))
      o.edge = rk + nosing;
  }
}

void StairModelling::fit_tread(const StairHypothesis& hyp, int n, int dir, const FloorSeen& floor,
                               int steps_not_landing, StairSpan& span, StairProfile& profile,
                               const StairResult& out) {
  fit_k_.clear();
  fit_e_.clear();
  fit_level_.clear();
  if (floor.edge) {
    fit_k_.push_back(0.f);
    fit_e_.push_back(out.level_data[0].edge);
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
  const EdgeLineFit fit = fit_edge_line(fit_k_, fit_e_, cfg_.edge_max_residual, fit_in_, tmp_, sorted_);
  outlier_.assign(static_cast<std::size_t>(n + 1), 0);
  for (std::size_t k = 0; k < fit_k_.size(); ++k)
    if (!fit_in_[k]) outlier_[static_cast<std::size_t>(fit_level_[k])] = 1;
  profile.tread = fit.line;
  profile.edge_consistent = fit.consistent;
  profile.edge_residual = fit.max_residual;
  // The width and centre leave out the levels whose edge is off the staircase's.
  bool any_outlier = false;
  for (int k = 1; k <= n; ++k) any_outlier = any_outlier || outlier_[static_cast<std::size_t>(k)];
  if (any_outlier) {
    float lo = std::numeric_limits<float>::max(), hi = -lo;
    for (int k = 1; k <= n; ++k) {
      if (outlier_[static_cast<std::size_t>(k)] ||
          (steps_not_landing > 0 && landing_[static_cast<std::size_t>(k)]))
        continue;
      lo = std::min(lo, out.level_data[static_cast<std::size_t>(k)].lateral_min);
      hi = std::max(hi, out.level_data[static_cast<std::size_t>(k)].lateral_max);
    }
    if (hi > lo) {
      span.width = hi - lo;
      span.a_mid = 0.5f * (lo + hi);
    }
  }
}

}  // namespace stairguide
