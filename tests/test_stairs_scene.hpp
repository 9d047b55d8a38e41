#pragma once
// Hand-built perception results for the stairs tests: points sampled on the treads of a known
// staircase (with the descending self-occlusion), the floor, tables and boxes, with depth noise
// along the camera ray, as perception would hand them over.

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "stairguide/core/ground_truth.hpp"
#include "stairguide/perception/scene.hpp"

namespace sgtest {

using stairguide::Pose;
using stairguide::RegionClass;
using stairguide::SceneResult;

struct StairSpec {
  int direction = 1;  // +1 ascending, -1 descending
  int steps = 6;
  float riser = 0.17f, tread = 0.29f, width = 1.2f;
  float distance = 1.5f;  // m from the camera's foot to the first edge, along the camera's forward
  float lateral = 0.f;    // m, sideways offset of the first edge's centre (to the left)
  float yaw_deg = 10.f;   // stair direction against the camera's forward
};

class SceneBuilder {
 public:
  SceneBuilder(float camera_height = 1.3f, float tilt_deg = 45.f, unsigned seed = 1, float noise_k = 0.0015f)
      : rng_(seed), noise_k_(noise_k) {
    const float t = tilt_deg * 0.017453293f;
    // Camera axes in the floor frame (x left, y up, z forward).
    Eigen::Matrix3f R;
    R.col(0) = Eigen::Vector3f(-1, 0, 0);
    R.col(1) = Eigen::Vector3f(0, -std::cos(t), -std::sin(t));
    R.col(2) = Eigen::Vector3f(0, -std::sin(t), std::cos(t));
    T_floor_camera_.setIdentity();
    T_floor_camera_.linear() = R;
    T_floor_camera_.translation() = Eigen::Vector3f(0, camera_height, 0);
    scene.floor_found = true;
    scene.T_floor_camera = T_floor_camera_;
    scene.camera_height = camera_height;
    scene.camera_tilt = t;
  }

  SceneResult scene;
  stairguide::StairTruth truth;

  /// Floor frame pose of the stair frame for a spec.
  Pose floor_stair(const StairSpec& s) const {
    const float y = s.yaw_deg * 0.017453293f;
    Pose T = Pose::Identity();
    T.linear().col(0) = Eigen::Vector3f(std::cos(y), 0, -std::sin(y));
    T.linear().col(1) = Eigen::Vector3f(0, 1, 0);
    T.linear().col(2) = Eigen::Vector3f(std::sin(y), 0, std::cos(y));
    T.translation() = Eigen::Vector3f(s.lateral, s.direction > 0 ? s.riser : 0.f, s.distance);
    return T;
  }

  /// Adds a staircase: one region per visible tread (descending treads cut by self-occlusion) and
  /// the floor before it. `split_level` > 0 cuts that level into two regions with a gap (a person).
  void add_stairs(const StairSpec& s, int split_level = 0, float floor_depth = 3.0f) {
    const Pose T_fs = floor_stair(s);
    const Pose T_cs = T_floor_camera_.inverse() * T_fs;
    truth = {};
    truth.kind = s.direction > 0 ? stairguide::StairKind::kAscending : stairguide::StairKind::kDescending;
    truth.steps = s.steps;
    truth.riser_m = s.riser;
    truth.tread_m = s.tread;
    truth.width_m = s.width;
    truth.T_camera_stair = T_cs;
    truth.first_edge_visible = truth.both_ends_visible = true;
    const Eigen::Vector3f cam_s = T_cs.inverse().translation();
    const float base = s.direction > 0 ? -s.riser : 0.f;  // floor height in S
    // Floor: in front of the first edge, wider than the staircase.
    add_patch(T_cs, -1.5f - s.width / 2, 1.5f + s.width / 2, -floor_depth, 0.f, base, RegionClass::kFloor,
              cam_s, {});
    scene.floor_region = static_cast<int>(scene.regions.size()) - 1;
    for (int k = 1; k <= s.steps; ++k) {
      const float y =
          s.direction > 0 ? static_cast<float>(k - 1) * s.riser : -static_cast<float>(k) * s.riser;
      const float z0 = static_cast<float>(k - 1) * s.tread, z1 = static_cast<float>(k) * s.tread;
      // Ascending treads above the camera are not seen.
      if (cam_s.y() < y + 0.05f) break;
      std::vector<Eigen::Vector2f> nosings;  // (z, y) of the edges that can hide this tread
      if (s.direction < 0)
        for (int j = 0; j < k; ++j)
          nosings.emplace_back(static_cast<float>(j) * s.tread, -static_cast<float>(j) * s.riser);
      const std::size_t before = scene.regions.size();
      if (k == split_level) {
        add_patch(T_cs, -s.width / 2, -0.15f, z0, z1, y, RegionClass::kStepCandidate, cam_s, nosings);
        add_patch(T_cs, 0.15f, s.width / 2, z0, z1, y, RegionClass::kStepCandidate, cam_s, nosings);
      } else {
        add_patch(T_cs, -s.width / 2, s.width / 2, z0, z1, y, RegionClass::kStepCandidate, cam_s, nosings);
      }
      if (scene.regions.size() > before) truth.visible_steps.push_back(k);
    }
  }

  /// Adds a horizontal rectangle in the floor frame (centre x, z; size along x, z; height).
  void add_box_top(float cx, float cz, float sx, float sz, float height, RegionClass cls) {
    Pose T = T_floor_camera_.inverse();
    add_patch(T, cx - sx / 2, cx + sx / 2, cz - sz / 2, cz + sz / 2, height, cls, T.inverse().translation(),
              {});
  }

  /// Adds the floor alone (x within +-2 m, z from 0.3 m to `depth`).
  void add_floor(float depth = 4.0f) {
    add_box_top(0.f, 0.3f + (depth - 0.3f) / 2, 4.f, depth - 0.3f, 0.f, RegionClass::kFloor);
    scene.floor_region = static_cast<int>(scene.regions.size()) - 1;
  }

  /// Sets a Manhattan frame rotated by `yaw_deg` about the floor's y.
  void set_manhattan(float yaw_deg, float fraction = 0.3f) {
    const float y = yaw_deg * 0.017453293f;
    scene.manhattan_found = true;
    scene.manhattan_yaw = y;
    scene.manhattan_fraction = fraction;
    scene.T_manhattan_floor = Pose(Eigen::AngleAxisf(-y, Eigen::Vector3f::UnitY()));
  }

 private:
  // Samples a horizontal rectangle [x0,x1] x [z0,z1] at height y of a frame T (camera <- frame) on a
  // jittered 2 cm grid, drops points hidden behind the given nosings, adds noise along the ray.
  void add_patch(const Pose& T_c_s, float x0, float x1, float z0, float z1, float y, RegionClass cls,
                 const Eigen::Vector3f& cam_s, const std::vector<Eigen::Vector2f>& nosings) {
    stairguide::PlaneRegion r;
    r.id = static_cast<int>(scene.regions.size());
    r.cls = cls;
    std::uniform_real_distribution<float> jit(-0.008f, 0.008f);
    std::normal_distribution<float> gauss(0.f, 1.f);
    const float step = 0.02f;
    for (float x = x0 + step / 2; x < x1; x += step) {
      for (float z = z0 + step / 2; z < z1; z += step) {
        Eigen::Vector3f ps(std::clamp(x + jit(rng_), x0, x1), y, std::clamp(z + jit(rng_), z0, z1));
        bool hidden = false;
        for (const auto& n : nosings) {
          if (ps.z() <= n.x()) continue;
          const float t = (n.x() - cam_s.z()) / (ps.z() - cam_s.z());
          if (cam_s.y() + t * (ps.y() - cam_s.y()) < n.y()) hidden = true;
        }
        if (hidden) continue;
        Eigen::Vector3f pc = T_c_s * ps;
        if (pc.z() < 0.3f) continue;  // behind or too near the camera
        const float d = pc.norm();
        const float sigma = noise_k_ * pc.z() * pc.z();
        pc *= (d + sigma * gauss(rng_)) / d;
        r.points.push_back(pc);
      }
    }
    if (r.points.size() < 10) return;
    Eigen::Vector3f c = Eigen::Vector3f::Zero();
    for (const auto& p : r.points) c += p;
    r.centroid = c / static_cast<float>(r.points.size());
    r.pixel_count = static_cast<int>(r.points.size());
    Eigen::Vector3f n = T_c_s.linear().col(1);  // plane normal: y of the frame
    if (n.dot(r.centroid) > 0) n = -n;          // facing the camera
    r.normal = n;
    r.offset = -n.dot(r.centroid);
    const Eigen::Vector3f up = T_floor_camera_.linear().row(1).transpose();
    r.height = up.dot(r.centroid) + T_floor_camera_.translation().y();
    scene.regions.push_back(std::move(r));
  }

  std::mt19937 rng_;
  float noise_k_;
  Pose T_floor_camera_;
};

}  // namespace sgtest
