// Stair modelling, phase "levels" (stair_levels.hpp): each level laid into the horizontal plane.
#include "stairguide/stairs/stair_levels.hpp"

#include <algorithm>
#include <cmath>

#include "stair_modelling_internal.hpp"
#include "stairguide/stairs/stair_modelling.hpp"

namespace stairguide {

using namespace modelling;

void project_level(const SceneResult& scene, const LevelSeed& seed, const Eigen::Vector3f& up,
                   const Eigen::Vector3f& e1, const Eigen::Vector3f& e2, std::size_t max_points,
                   StairLevel2d& out) {
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
  out.centroid =
      out.pts.empty() ? Eigen::Vector2f::Zero() : Eigen::Vector2f(c / static_cast<float>(out.pts.size()));
}

void level_shape(StairLevel2d& L, std::size_t hull_points, std::vector<Eigen::Vector2f>& sub) {
  sub.clear();
  const std::size_t stride = std::max<std::size_t>(1, L.pts.size() / hull_points);
  for (std::size_t i = 0; i < L.pts.size(); i += stride) sub.push_back(L.pts[i]);
  convex_hull(sub, L.hull);
  // Principal axis of the step and its extent (hull area over the PCA rectangle's area).
  Eigen::Matrix2f cov = Eigen::Matrix2f::Zero();
  for (std::size_t i = 0; i < L.pts.size(); i += stride) {
    const Eigen::Vector2f d = L.pts[i] - L.centroid;
    cov += d * d.transpose();
  }
  L.pca_angle = 0.5f * std::atan2(2.f * cov(0, 1), cov(0, 0) - cov(1, 1));
  const float ra = rect_area(L.hull, L.pca_angle);
  L.extent = ra > 0.f ? polygon_area(L.hull) / ra : 0.f;
}

StairModelling::LevelsSeen StairModelling::project_levels(const SceneResult& scene,
                                                          const StairHypothesis& hyp, int n,
                                                          const StairFrame& frame) {
  const Eigen::Vector3f &up = frame.up, &e1 = frame.e1, &e2 = frame.e2;
  LevelsSeen seen;
  levels_.resize(static_cast<std::size_t>(n + 1));
  seen.have_floor = !hyp.levels[0].regions.empty();
  if (seen.have_floor) {
    project_level(scene, hyp.levels[0], up, e1, e2, kFloorPoints, levels_[0]);
  } else {
    levels_[0].pts.clear();
    // The floor plane from the transform: up0 . p + t_y = 0.
    levels_[0].plane = -scene.T_floor_camera.translation().y();
  }
  float best_extent = -1.f;
  for (int k = 1; k <= n; ++k) {
    StairLevel2d& L = levels_[static_cast<std::size_t>(k)];
    project_level(scene, hyp.levels[static_cast<std::size_t>(k)], up, e1, e2, kStepPoints, L);
    level_shape(L, kHullPoints, sub_);
    if (L.pts.size() >= 30 && L.extent > best_extent) {
      best_extent = L.extent;
      seen.seed = k;
    }
  }
  return seen;
}

}  // namespace stairguide
