#pragma once
/// \file stair_levels.hpp
/// Stair modelling, phase "levels": each level of a hypothesis laid into the horizontal plane.
///
/// Decides where each level's points lie in the horizontal basis (e1, e2) and at which height
/// (its plane offset along up), and gives each step its outline (convex hull), principal axis and
/// extent (hull area over the PCA rectangle's area). The step with the greatest extent seeds the
/// horizontal axes (stair_axes.hpp): a tread seen whole is a clean rectangle, a tread cut by an
/// occluder or the image border is not.
///
/// Why along the ray: depth noise lies along the camera ray, so sliding each point along its ray
/// onto the level's plane removes most of it; points whose ray meets the plane far from where they
/// were measured are strays and are dropped.

#include <Eigen/Core>
#include <cstddef>
#include <vector>

#include "stairguide/perception/scene.hpp"
#include "stairguide/stairs/stair_detection.hpp"

namespace stairguide {

/// One level of a staircase in the horizontal plane.
struct StairLevel2d {
  std::vector<Eigen::Vector2f> pts;  ///< ray-projected points in the horizontal basis (e1, e2)
  float plane = 0.f;                 ///< mean of up . p (camera frame), m
  Eigen::Vector2f centroid = Eigen::Vector2f::Zero();
  std::vector<Eigen::Vector2f> hull;  ///< convex hull of a subsample
  float extent = 0.f;                 ///< hull area / PCA rectangle area
  float pca_angle = 0.f;              ///< rad, major axis in (e1, e2)
};

/// Projects the regions of `seed` (an even subsample of at most about `max_points` points) along
/// their camera rays onto the level's plane (normal `up`, offset the subsample's mean of up . p)
/// and expresses them in the basis (e1, e2). Fills `out.pts`, `out.plane` and `out.centroid`.
/// Pure.
void project_level(const SceneResult& scene, const LevelSeed& seed, const Eigen::Vector3f& up,
                   const Eigen::Vector3f& e1, const Eigen::Vector3f& e2, std::size_t max_points,
                   StairLevel2d& out);

/// The outline of a projected step: the convex hull of an even subsample of its points (at most
/// about `hull_points`; `sub` is scratch), its principal axis and its extent. Fills `L.hull`,
/// `L.pca_angle` and `L.extent`. Pure.
void level_shape(StairLevel2d& L, std::size_t hull_points, std::vector<Eigen::Vector2f>& sub);

}  // namespace stairguide
