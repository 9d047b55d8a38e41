#pragma once
/// \file stair_profile.hpp
/// Stair modelling, phase "profile": the riser and the tread from the levels' heights and edges.
///
/// - Riser: slope of the level heights (centroid to centroid, the floor included) against the step
///   index (LevelSeed::index, so hidden first steps count).
/// - Risers facing the user place a step's start where its tread's near rows are hidden or where
///   the tread took in the riser's top rows (StairModelling::place_edges_at_risers).
/// - Tread: slope of the step edges against the step index, by consensus (fit_edge_line): the line
///   most edges lie near, refitted to those. Edges off it are a landing or the lower floor seen as
///   a level, a nosing hidden by a person, or a box top at a step's height that touched a step; the
///   staircase's width and centre then leave those levels out.

#include <cstddef>
#include <vector>

namespace stairguide {

/// A straight line y = intercept + slope * x.
struct LineFit {
  float slope = 0.f, intercept = 0.f;
  bool ok = false;  ///< two or more points with distinct x
};

/// Least-squares line through (x[i], y[i]).
LineFit fit_line(const std::vector<float>& x, const std::vector<float>& y);

/// The step edges' line (edge position against the step index) by consensus.
struct EdgeLineFit {
  LineFit line;              ///< refitted to the edges near the consensus line
  bool consistent = false;   ///< line.ok and two thirds of the edges at least lie on it
  float max_residual = 0.f;  ///< m, largest distance of an edge on the line from the refitted line
};

/// Over the lines through two edges (k[i], e[i]), the one with most edges within `max_residual`
/// (ties: the smaller summed residual), refitted to those edges. `inlier[i]` says whether edge i
/// was kept; `k_in`, `e_in` receive the kept edges. Pure.
EdgeLineFit fit_edge_line(const std::vector<float>& k, const std::vector<float>& e, float max_residual,
                          std::vector<char>& inlier, std::vector<float>& k_in, std::vector<float>& e_in);

}  // namespace stairguide
