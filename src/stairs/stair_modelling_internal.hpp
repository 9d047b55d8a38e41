#pragma once
// Internal to stair modelling's phases (stair_*.cpp): the constants they share and the small 2D
// geometry they are built from (hulls, rectangles, robust extremes). Not a public interface.

#include <Eigen/Core>
#include <cstddef>
#include <vector>

namespace stairguide {
namespace modelling {

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

/// Andrew's monotone chain; sorts `pts` in place.
void convex_hull(std::vector<Eigen::Vector2f>& pts, std::vector<Eigen::Vector2f>& hull);
float polygon_area(const std::vector<Eigen::Vector2f>& poly);
/// Area of the rectangle bounding `hull` with one side at `angle` (rad).
float rect_area(const std::vector<Eigen::Vector2f>& hull, float angle);
/// Wraps an angle into [-pi/4, pi/4): rectangle axes repeat every quarter turn.
float wrap_quarter(float a);
/// Robust low and high extremes of `v` (reordered), extrapolated from two inner quantiles; the
/// plain extreme below kMinRobust values, NaN when empty.
float robust_low(std::vector<float>& v);
float robust_high(std::vector<float>& v);

}  // namespace modelling
}  // namespace stairguide
