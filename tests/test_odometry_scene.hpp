#pragma once
// A tiny ray-cast world for odometry tests that do not need the full synthetic renderer: a floor,
// side walls, a back wall and a few steps, all axis-aligned boxes with a smooth procedural texture
// (value noise fixed to the surface, so it moves with the scene, not the camera).
// World: z up, the user walks along +y. Camera: x right, y down, z forward.

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "stairguide/core/types.hpp"

namespace sgtest {

struct Box {
  Eigen::Vector3f lo, hi;
  float albedo;  // base grey level
};

inline float hash3(int x, int y, int z) {
  std::uint32_t h = static_cast<std::uint32_t>(x) * 73856093u ^ static_cast<std::uint32_t>(y) * 19349663u ^
                    static_cast<std::uint32_t>(z) * 83492791u;
  h ^= h >> 13;
  h *= 0x5bd1e995u;
  h ^= h >> 15;
  return static_cast<float>(h & 0xffffu) / 65535.f;
}

/// Smooth value noise in [0, 1] at point p (scale 1 = one cell per metre).
inline float value_noise(const Eigen::Vector3f& p) {
  const float fx = std::floor(p.x()), fy = std::floor(p.y()), fz = std::floor(p.z());
  const int ix = static_cast<int>(fx), iy = static_cast<int>(fy), iz = static_cast<int>(fz);
  auto s = [](float t) { return t * t * (3.f - 2.f * t); };
  const float ax = s(p.x() - fx), ay = s(p.y() - fy), az = s(p.z() - fz);
  float c[2][2][2];
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j)
      for (int k = 0; k < 2; ++k) c[i][j][k] = hash3(ix + i, iy + j, iz + k);
  auto lerp = [](float a, float b, float t) { return a + (b - a) * t; };
  const float x00 = lerp(c[0][0][0], c[1][0][0], ax), x10 = lerp(c[0][1][0], c[1][1][0], ax);
  const float x01 = lerp(c[0][0][1], c[1][0][1], ax), x11 = lerp(c[0][1][1], c[1][1][1], ax);
  return lerp(lerp(x00, x10, ay), lerp(x01, x11, ay), az);
}

class Scene {
 public:
  std::vector<Box> boxes;
  bool textured = true;

  /// Floor, walls at x = +-1.2, back wall at y = 6, and `steps` ascending steps from y = 2.5.
  static Scene stairs(int steps = 6) {
    Scene s;
    s.boxes.push_back({{-3.f, -3.f, -0.2f}, {3.f, 8.f, 0.f}, 120.f});
    s.boxes.push_back({{-1.4f, -3.f, 0.f}, {-1.2f, 8.f, 3.f}, 150.f});
    s.boxes.push_back({{1.2f, -3.f, 0.f}, {1.4f, 8.f, 3.f}, 100.f});
    s.boxes.push_back({{-3.f, 6.f, 0.f}, {3.f, 6.2f, 3.f}, 170.f});
    for (int i = 0; i < steps; ++i) {
      const float y0 = 2.5f + 0.3f * static_cast<float>(i);
      s.boxes.push_back({{-1.2f, y0, 0.f},
                         {1.2f, 6.f, 0.17f * static_cast<float>(i + 1)},
                         140.f + 8.f * static_cast<float>(i % 3)});
    }
    return s;
  }

  /// Grey level of a surface point (0-255).
  float shade(const Eigen::Vector3f& p, float albedo) const {
    if (!textured) return albedo;
    const float n = 0.5f * value_noise(p * 4.f) + 0.3f * value_noise(p * 13.f + Eigen::Vector3f(7, 3, 1)) +
                    0.2f * value_noise(p * 31.f + Eigen::Vector3f(1, 9, 4));
    return std::clamp(albedo + 160.f * (n - 0.5f), 0.f, 255.f);
  }

  /// Nearest hit along origin + t dir (t > 0); returns t or -1, and the box index.
  float cast(const Eigen::Vector3f& o, const Eigen::Vector3f& d, int* hit) const {
    float best = -1.f;
    for (std::size_t b = 0; b < boxes.size(); ++b) {
      float t0 = 0.f, t1 = 1e9f;
      bool miss = false;
      for (int a = 0; a < 3 && !miss; ++a) {
        if (std::fabs(d[a]) < 1e-9f) {
          if (o[a] < boxes[b].lo[a] || o[a] > boxes[b].hi[a]) miss = true;
          continue;
        }
        float ta = (boxes[b].lo[a] - o[a]) / d[a], tb = (boxes[b].hi[a] - o[a]) / d[a];
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
        if (t0 > t1) miss = true;
      }
      if (miss || t0 <= 1e-4f) continue;
      if (best < 0.f || t0 < best) {
        best = t0;
        *hit = static_cast<int>(b);
      }
    }
    return best;
  }

  struct RenderOptions {
    bool noise = false;  // depth noise (disparity-like), intensity noise, quantisation
    std::uint32_t seed = 1;
    bool depth = true;  // false: no depth at all
  };

  /// Renders the view of a camera at T_world_camera.
  stairguide::RgbdFrame render(const Eigen::Isometry3f& T_world_camera, const stairguide::CameraIntrinsics& K,
                               const RenderOptions& opt) const {
    stairguide::RgbdFrame f;
    f.intrinsics = K;
    f.depth = cv::Mat(K.height, K.width, CV_32FC1, cv::Scalar(0));
    f.gray = cv::Mat(K.height, K.width, CV_8UC1, cv::Scalar(0));
    std::mt19937 rng(opt.seed);
    std::normal_distribution<float> n01(0.f, 1.f);
    const Eigen::Matrix3f R = T_world_camera.linear();
    const Eigen::Vector3f o = T_world_camera.translation();
    for (int v = 0; v < K.height; ++v) {
      float* dr = f.depth.ptr<float>(v);
      unsigned char* gr = f.gray.ptr<unsigned char>(v);
      for (int u = 0; u < K.width; ++u) {
        const Eigen::Vector3f dc((static_cast<float>(u) - K.cx) / K.fx, (static_cast<float>(v) - K.cy) / K.fy,
                                 1.f);
        const Eigen::Vector3f dw = R * dc;
        int hit = -1;
        const float t = cast(o, dw, &hit);
        float g = 40.f;
        float z = 0.f;
        if (t > 0.f) {
          z = t;  // dc.z == 1: the ray parameter is the camera depth
          g = shade(o + t * dw, boxes[static_cast<std::size_t>(hit)].albedo);
        }
        if (opt.noise) {
          g += 2.f * n01(rng);
          if (z > 0.f) {
            // Kinect-like: disparity noise, sigma_z = 1.4e-3 z^2, quantised to 1 mm.
            z += 1.4e-3f * z * z * n01(rng);
            z = std::round(z * 1000.f) / 1000.f;
          }
        }
        if (z > 5.f || z < 0.4f) z = 0.f;
        dr[u] = opt.depth ? z : 0.f;
        gr[u] = static_cast<unsigned char>(std::clamp(std::round(g), 0.f, 255.f));
      }
    }
    return f;
  }
};

/// A chest camera at height h, tilted `tilt_deg` below horizontal, looking along +y (world),
/// at world position (x, y) on the floor, with yaw (deg, left positive) and roll.
inline Eigen::Isometry3f chest_camera(float x, float y, float h, float tilt_deg, float yaw_deg = 0.f) {
  // Camera axes in world for a level camera looking along +y: x_c = +x_w, y_c = -z_w, z_c = +y_w.
  Eigen::Matrix3f level;
  level.col(0) = Eigen::Vector3f(1, 0, 0);
  level.col(1) = Eigen::Vector3f(0, 0, -1);
  level.col(2) = Eigen::Vector3f(0, 1, 0);
  const float d2r = 3.14159265f / 180.f;
  const Eigen::Matrix3f yaw = Eigen::AngleAxisf(yaw_deg * d2r, Eigen::Vector3f::UnitZ()).toRotationMatrix();
  // Tilt down: rotate about the camera x axis (positive pitches the optical axis down).
  const Eigen::Matrix3f tilt =
      Eigen::AngleAxisf(-tilt_deg * d2r, Eigen::Vector3f::UnitX()).toRotationMatrix();
  Eigen::Isometry3f T = Eigen::Isometry3f::Identity();
  T.linear() = yaw * level * tilt;
  T.translation() = Eigen::Vector3f(x, y, h);
  return T;
}

}  // namespace sgtest
