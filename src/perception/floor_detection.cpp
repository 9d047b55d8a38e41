#include "stairguide/perception/floor_detection.hpp"

#include <algorithm>
#include <cmath>

namespace stairguide {

Pose floor_pose_from_plane(const Eigen::Vector3f& up, float camera_height) {
  const Eigen::Vector3f y = up.normalized();
  Eigen::Vector3f z = Eigen::Vector3f::UnitZ() - y * y.z();
  if (z.norm() < 1e-4f) z = Eigen::Vector3f::UnitY() - y * y.y();  // looking straight down
  z.normalize();
  const Eigen::Vector3f x = y.cross(z);
  Eigen::Matrix3f R;  // rows: floor axes in camera coordinates
  R.row(0) = x.transpose();
  R.row(1) = y.transpose();
  R.row(2) = z.transpose();
  Pose T = Pose::Identity();
  T.linear() = R;
  // The camera sits camera_height above the floor origin, on y_F.
  T.translation() = Eigen::Vector3f(0.f, camera_height, 0.f);
  return T;
}

void tilt_roll_from_up(const Eigen::Vector3f& up, float& tilt, float& roll) {
  // Camera with no roll: up = (0, -cos t, -sin t) in camera coordinates (y down, z forward).
  tilt = std::asin(std::clamp(-up.z(), -1.f, 1.f));
  roll = std::atan2(-up.x(), -up.y());
}

FloorDetector::FloorDetector(const FloorConfig& config) : cfg_(config) {}

FloorEstimate FloorDetector::detect(const std::vector<PlaneRegion>& regions, const RgbdFrame& frame) {
  FloorEstimate est;
  const int n = static_cast<int>(regions.size());
  const float area_k = 1.f / (frame.intrinsics.fx * frame.intrinsics.fy);

  // Rule checks on orientation and distance.
  std::vector<int> cand;
  for (int i = 0; i < n; ++i) {
    const PlaneRegion& r = regions[i];
    const float h = r.offset;  // normals face the camera: offset = distance of the camera
    if (h < cfg_.height_min || h > cfg_.height_max) continue;
    float tilt, roll;
    tilt_roll_from_up(r.normal, tilt, roll);
    if (tilt < cfg_.tilt_min || tilt > cfg_.tilt_max || std::fabs(roll) > cfg_.roll_max) continue;
    if (r.area < cfg_.min_area * 0.1f) continue;
    cand.push_back(i);
  }
  if (cand.empty()) {
    est.why = "no plane with a chest camera's orientation and height";
    return est;
  }

  // Tracking: the previous floor, when it is still in view, stays the floor.
  int chosen = -1;
  if (prev_) {
    float best = 0.f;
    for (int i : cand) {
      const PlaneRegion& r = regions[i];
      const float ang = std::acos(std::clamp(r.normal.dot(prev_->normal), -1.f, 1.f));
      if (ang > cfg_.track_max_angle_jump || std::fabs(r.offset - prev_->offset) > cfg_.track_max_height_jump) continue;
      if (r.area > best) {
        best = r.area;
        chosen = i;
      }
    }
    if (chosen >= 0 && regions[chosen].area < 0.25f * cfg_.min_area) chosen = -1;
    if (chosen >= 0) est.tracked = true;
  }

  if (chosen < 0) {
    // Search window on z_C growing from search_start: the floor is what the user stands on, so
    // it is the plane nearest the camera's feet, not the biggest one. One pass per candidate
    // bins its footprint by window; the windows are then cumulative sums.
    const float step = std::max(cfg_.search_step, 1e-3f);
    const int steps = std::max(1, static_cast<int>(std::ceil((cfg_.search_max - cfg_.search_start) / step)) + 1);
    window_area_.assign(cand.size() * static_cast<std::size_t>(steps), 0.f);
    for (std::size_t c = 0; c < cand.size(); ++c) {
      const PlaneRegion& r = regions[cand[c]];
      float* bins = &window_area_[c * static_cast<std::size_t>(steps)];
      auto bin_of = [&](float z) {
        if (z <= cfg_.search_start) return 0;
        return static_cast<int>(std::ceil((z - cfg_.search_start) / step));
      };
      // The region's point subsample is enough to measure its footprint per window.
      if (!r.points.empty()) {
        const float k = area_k / std::max(std::fabs(r.offset), 0.01f) * static_cast<float>(r.pixel_count) /
                        static_cast<float>(r.points.size());
        // Without pixels (points from another segmentation, e.g. a voxel grid) each point
        // stands for an equal share of the area.
        const bool uniform = r.pixels.empty();
        const float ku = r.area / static_cast<float>(r.points.size());
        for (const auto& q : r.points) {
          const float z = q.z();
          const int b = bin_of(z);
          if (b < steps) bins[b] += uniform ? ku : z * z * z * k;
        }
      }
      for (int s = 1; s < steps; ++s) bins[s] += bins[s - 1];
    }
    for (int s = 0; s < steps && chosen < 0; ++s) {
      float best = 0.f;
      for (std::size_t c = 0; c < cand.size(); ++c) {
        const float a = window_area_[c * static_cast<std::size_t>(steps) + s];
        if (a >= cfg_.min_area && a > best) {
          best = a;
          chosen = cand[c];
        }
      }
    }
  }
  if (chosen >= 0 && !est.tracked) {
    // The user stands on the floor: of two parallel candidates a riser or more apart, the floor
    // is the one that reaches nearer the camera's foot (a first step or a landing right ahead
    // can be nearer the camera and bigger in the window, but it starts further ahead).
    auto near_distance = [](const PlaneRegion& r) {
      std::vector<float> h;
      h.reserve(r.points.size());
      for (const auto& q : r.points) {
        const float np = r.normal.dot(q);
        h.push_back(std::sqrt(std::max(0.f, q.squaredNorm() - np * np)));
      }
      if (h.empty()) return 1e9f;
      const std::size_t k = h.size() / 50;  // 2nd percentile: robust to stray points
      std::nth_element(h.begin(), h.begin() + static_cast<long>(k), h.end());
      return h[k];
    };
    float best_near = near_distance(regions[chosen]);
    const float cos_par = std::cos(cfg_.horizontal_tolerance);
    const int first = chosen;
    for (int i : cand) {
      if (i == first) continue;
      const PlaneRegion& r = regions[i];
      // Even a small patch of a lower plane at the user's feet outranks a bigger step ahead.
      if (r.area < 0.1f * cfg_.min_area || r.normal.dot(regions[first].normal) < cos_par) continue;
      if (std::fabs(r.offset - regions[first].offset) < cfg_.inlier_distance) continue;
      const float nd = near_distance(r);
      if (nd + 0.05f < best_near) {
        best_near = nd;
        chosen = i;
      }
    }
  }
  if (chosen < 0) {
    est.why = "no floor-like plane with enough area within the search window";
    return est;
  }
  const PlaneRegion& f = regions[chosen];
  est.found = true;
  est.region = chosen;
  est.normal = f.normal;
  est.offset = f.offset;
  est.height = f.offset;
  tilt_roll_from_up(f.normal, est.tilt, est.roll);
  est.T_floor_camera = floor_pose_from_plane(f.normal, f.offset);
  prev_ = Prev{f.normal, f.offset};
  return est;
}

}  // namespace stairguide
