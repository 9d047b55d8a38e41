#pragma once
/// \file region_classification.hpp
/// Classification of regions (paper 3.3, Fig. 5). With the floor known, every region gets its
/// height H (centroid above the floor) and a class:
///  - horizontal (normal within parallel_threshold of the floor normal): floor when |H| is within
///    floor_height_tolerance (or it is the floor region itself); step candidate when
///    |H| >= H_min - step_height_tolerance and it is below the camera; otherwise obstacle.
///    A horizontal region's normal is replaced by the floor's (facing the same way) and its
///    offset refitted through its centroid: a thin far tread's own fit constrains its tilt poorly;
///  - vertical (normal within parallel_threshold of horizontal): left / right / front by the
///    Manhattan axes, or kVertical without a Manhattan frame; a vertical plane that fits neither
///    Manhattan axis is an obstacle;
///  - anything else: kOther.
/// Without a floor nothing can be placed: every region stays kUnclassified with NaN height.

#include <vector>

#include "stairguide/core/config.hpp"
#include "stairguide/perception/scene.hpp"

namespace stairguide {

/// Classifies `scene.regions` in place from the floor and Manhattan fields of `scene` (and sets
/// horizontal regions' normal and offset, see above).
void classify_regions(SceneResult& scene, const ClassificationConfig& config);

}  // namespace stairguide
