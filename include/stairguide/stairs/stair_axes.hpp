#pragma once
/// \file stair_axes.hpp
/// Stair modelling, phase "axes": the stair frame's axes in the camera frame.
///
/// - Vertical axis y_S: all horizontal levels (floor and steps) share one normal, fitted to all
///   their points together (each region centred on its own mean). A floor normal 1 degree off tilts
///   every height by 5 mm per 30 cm of tread, so the steps' own points are worth adding. A fit far
///   from the floor's normal means the levels are not all flat: the floor's is kept.
/// - Horizontal axes: the rotation about y_S minimising the summed bounding-rectangle areas of the
///   steps (levels far larger than the median one left out), the Manhattan axes when they agree,
///   then which of the two axes runs into the staircase and which way (StairModelling::fit_axes).

#include <Eigen/Core>

#include "stairguide/perception/scene.hpp"
#include "stairguide/stairs/stair_detection.hpp"

namespace stairguide {

/// The stair frame's axes: the vertical and a horizontal basis (e1, e2) of the plane it is normal
/// to, then x_S and z_S both in that basis (x2, z2) and in the camera frame (xs, zs).
struct StairFrame {
  Eigen::Vector3f up = Eigen::Vector3f::Zero();  ///< y_S, camera frame, unit
  Eigen::Vector3f e1 = Eigen::Vector3f::Zero();  ///< horizontal basis: the camera's forward made horizontal
  Eigen::Vector3f e2 = Eigen::Vector3f::Zero();  ///< up x e1
  Eigen::Vector2f x2 = Eigen::Vector2f::Zero();  ///< x_S in (e1, e2)
  Eigen::Vector2f z2 = Eigen::Vector2f::Zero();  ///< z_S in (e1, e2): from the user into the staircase
  Eigen::Vector3f xs = Eigen::Vector3f::Zero();  ///< x_S, camera frame
  Eigen::Vector3f zs = Eigen::Vector3f::Zero();  ///< z_S, camera frame
};

/// The common normal of the horizontal levels of `hyp` (camera frame, on the side of `up0`), or
/// `up0` (the floor's up) when the levels give too few points (50) or a normal more than 3 degrees
/// from it. Pure.
Eigen::Vector3f fit_stair_vertical(const SceneResult& scene, const StairHypothesis& hyp,
                                   const Eigen::Vector3f& up0);

/// A frame with vertical `up` and its horizontal basis: e1 is the camera's forward (z) made
/// horizontal (its x when looking straight down), e2 = up x e1. x2, z2, xs, zs are left zero.
StairFrame horizontal_basis(const Eigen::Vector3f& up);

/// Sets z_S (z2 in the basis) and with it x2 = (-z2.y, z2.x), zs and xs = up x zs.
void set_stair_direction(StairFrame& f, const Eigen::Vector2f& z2);

}  // namespace stairguide
