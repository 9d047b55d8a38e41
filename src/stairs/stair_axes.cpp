// Stair modelling, phase "axes" (stair_axes.hpp): the vertical, then the horizontal axes x_S, z_S.
#include "stairguide/stairs/stair_axes.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>

#include "stair_modelling_internal.hpp"
#include "stairguide/stairs/stair_modelling.hpp"

namespace stairguide {

using namespace modelling;

Eigen::Vector3f fit_stair_vertical(const SceneResult& scene, const StairHypothesis& hyp,
                                   const Eigen::Vector3f& up0) {
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

StairFrame horizontal_basis(const Eigen::Vector3f& up) {
  StairFrame f;
  f.up = up;
  Eigen::Vector3f e1 = Eigen::Vector3f::UnitZ() - up * up.z();
  if (e1.norm() < 1e-3f) e1 = Eigen::Vector3f::UnitX() - up * up.x();
  e1.normalize();
  f.e1 = e1;
  f.e2 = up.cross(e1);
  return f;
}

void set_stair_direction(StairFrame& f, const Eigen::Vector2f& z2) {
  f.z2 = z2;
  f.x2 = Eigen::Vector2f(-z2.y(), z2.x());  // x_S = y_S x z_S in the (e1, e2) basis
  f.zs = (z2.x() * f.e1 + z2.y() * f.e2).normalized();
  f.xs = f.up.cross(f.zs).normalized();
}

float StairModelling::area_cost(float angle, int first, int last) const {
  float s = 0.f;
  for (int k = first; k <= last; ++k)
    if (!axis_skip_[static_cast<std::size_t>(k)])
      s += rect_area(levels_[static_cast<std::size_t>(k)].hull, angle);
  return s;
}

float StairModelling::min_area_angle(int n, float seed_angle) {
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
  return best;
}

StairAxesMethod StairModelling::fit_axes(const SceneResult& scene, int n, int seed, StairFrame& frame) {
  const Eigen::Vector3f &e1 = frame.e1, &e2 = frame.e2;
  const float best = min_area_angle(n, levels_[static_cast<std::size_t>(seed)].pca_angle);
  float theta = best;
  StairAxesMethod method = StairAxesMethod::kPca;
  if (scene.manhattan_found && scene.manhattan_fraction >= cfg_.manhattan_min_fraction) {
    // z_M in the camera frame: M -> F is the inverse rotation of T_manhattan_floor.
    const Eigen::Vector3f zm_floor = scene.T_manhattan_floor.linear().transpose() * Eigen::Vector3f::UnitZ();
    const Eigen::Matrix3f R = scene.T_floor_camera.linear();
    const Eigen::Vector3f zm = R.transpose() * zm_floor;
    const float theta_m = std::atan2(e2.dot(zm), e1.dot(zm));
    const float diff = wrap_quarter(theta_m - best);
    // A staircase rotated against the room (paper Fig. 14 b, right) keeps its own axes.
    if (std::fabs(diff) <= cfg_.manhattan_max_disagreement) {
      theta = best + diff;
      method = StairAxesMethod::kManhattan;
    }
  }
  Eigen::Vector2f z2 = orient_into_staircase(n, theta);
  if (n == 1) refine_single_axis(levels_[1], z2, e1, e2, frame.up);
  set_stair_direction(frame, z2);
  return method;
}

Eigen::Vector2f StairModelling::orient_into_staircase(int n, float theta) const {
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
      const float d = z2.dot(levels_[static_cast<std::size_t>(k + 1)].centroid -
                             levels_[static_cast<std::size_t>(k)].centroid);
      ahead += d > 0.f ? 1 : (d < 0.f ? -1 : 0);
    }
    if (ahead < 0 ||
        (ahead == 0 && z2.dot(levels_[static_cast<std::size_t>(n)].centroid - levels_[1].centroid) < 0.f))
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
  return z2;
}

void StairModelling::refine_single_axis(const StairLevel2d& L, Eigen::Vector2f& z2, const Eigen::Vector3f& e1,
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

}  // namespace stairguide
