#include "stairguide/perception/region_classification.hpp"

#include <cmath>
#include <limits>

namespace stairguide {

void classify_regions(SceneResult& scene, const ClassificationConfig& cfg) {
  if (!scene.floor_found) {
    for (PlaneRegion& r : scene.regions) {
      r.cls = RegionClass::kUnclassified;
      r.height = std::numeric_limits<float>::quiet_NaN();
    }
    return;
  }
  const Eigen::Matrix3f Rf = scene.T_floor_camera.linear();
  const Eigen::Vector3f tf = scene.T_floor_camera.translation();
  const Eigen::Matrix3f Rm = scene.T_manhattan_floor.linear();
  const float cos_par = std::cos(cfg.parallel_threshold);
  const float sin_perp = std::sin(cfg.parallel_threshold);
  for (int i = 0; i < static_cast<int>(scene.regions.size()); ++i) {
    PlaneRegion& r = scene.regions[i];
    const Eigen::Vector3f nf = Rf * r.normal;
    r.height = (Rf * r.centroid + tf).y();
    if (std::fabs(nf.y()) >= cos_par) {
      // A horizontal region is parallel to the floor: its own fit (few rows for a thin far tread,
      // seen at a grazing angle) constrains the tilt poorly, while the floor's normal comes from a
      // large, well-spread plane. Take the floor's normal and refit only the offset through the
      // centroid (the least-squares offset for a fixed normal). Only regions already within
      // parallel_threshold of horizontal are changed, so no class changes.
      const float sgn = nf.y() > 0.f ? 1.f : -1.f;
      r.normal = Rf.transpose() * Eigen::Vector3f(0.f, sgn, 0.f);
      r.offset = -r.normal.dot(r.centroid);
      const float H = r.height;
      if (i == scene.floor_region || std::fabs(H) <= cfg.floor_height_tolerance) {
        r.cls = RegionClass::kFloor;
      } else if (std::fabs(H) >= cfg.step_height_min - cfg.step_height_tolerance && H < scene.camera_height &&
                 nf.y() > 0.f) {
        // Seen from above (normal up towards the camera) at a step's height or more.
        r.cls = RegionClass::kStepCandidate;
      } else {
        r.cls = RegionClass::kObstacle;
      }
    } else if (std::fabs(nf.y()) <= sin_perp) {
      if (!scene.manhattan_found) {
        r.cls = RegionClass::kVertical;
        continue;
      }
      const Eigen::Vector3f nm = Rm * nf;  // Manhattan coordinates: x_M left, z_M forward
      if (std::fabs(nm.z()) >= cos_par) {
        r.cls = RegionClass::kVerticalFront;
      } else if (std::fabs(nm.x()) >= cos_par) {
        // A wall on the user's left faces right (-x_M).
        r.cls = nm.x() < 0.f ? RegionClass::kVerticalLeft : RegionClass::kVerticalRight;
      } else {
        r.cls = RegionClass::kObstacle;
      }
    } else {
      r.cls = RegionClass::kOther;
    }
  }
}

}  // namespace stairguide
