// Tests of the synthetic stair world: renderer geometry, sensor noise statistics, ground-truth
// labels, every preset, determinism.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <set>

#include "stairguide/capture/synth_source.hpp"
#include "stairguide/synth/builders.hpp"

using namespace stairguide;
using namespace stairguide::synth;

namespace {

SynthOptions clean() {
  SynthOptions o;
  o.noise = false;
  return o;
}

Eigen::Vector3f ray_of(const CameraIntrinsics& K, int u, int v) {
  return Eigen::Vector3f((static_cast<float>(u) - K.cx) / K.fx, (static_cast<float>(v) - K.cy) / K.fy, 1.f);
}

bool preset_has_stairs(const std::string& n) {
  return n.find("ascending") != std::string::npos || n.find("descending") != std::string::npos ||
         n == "open_risers_static" || n == "nosing_landing_static" || n == "rotated_static" ||
         n == "people_static" || n == "handrails_open_sides_static" || n == "single_step_static" ||
         n == "curb_static";
}

Material plain() {
  Material m;
  m.contrast = 0.f;
  return m;
}

// Floor, a wall ahead, an ascending staircase (known geometry) and a camera looking at it.
struct TestWorld {
  Scene scene;
  Pose T_wc;
  float riser = 0.17f, tread = 0.30f, width = 1.2f;
  int steps = 6;
  TestWorld() {
    scene.add_box_world({-5.f, -5.f, -0.2f}, {10.f, 5.f, 0.f}, plain(), "floor");
    scene.add_box_world({6.f, -5.f, 0.f}, {6.2f, 5.f, 3.f}, plain(), "wall");
    StairParams p = flight_params(StairKind::kAscending, steps, riser, tread, width);
    p.side_walls = false;
    p.T_world_stair = stair_pose(2.0f, 0.1f, 0.f, riser);
    Rng rng(3);
    add_staircase(scene, p, rng);
    T_wc = camera_pose({0.1f, 0.f, 1.3f}, 0.05f, deg2rad(40.f), deg2rad(1.5f));
  }
};

}  // namespace

TEST(SyntheticRender, DepthEqualsAnalyticRayPlaneDistance) {
  TestWorld w;
  const CameraIntrinsics K = synthetic_intrinsics(clean());
  RenderBuffers buf;
  render(w.scene, w.T_wc, K, buf);
  const Eigen::Matrix3f R = w.T_wc.linear();
  const Eigen::Vector3f c = w.T_wc.translation();
  int floor_checked = 0, tread_checked = 0;
  double worst = 0.0;
  for (int v = 5; v < K.height; v += 23) {
    for (int u = 3; u < K.width; u += 29) {
      const int f = buf.face.at<int>(v, u);
      ASSERT_GE(f, 0) << "pixel " << u << "," << v << " sees nothing";
      const Face& face = w.scene.faces()[static_cast<std::size_t>(f)];
      const Eigen::Vector3f d = R * ray_of(K, u, v);  // world direction, unit camera z
      // Analytic distance along the ray to the face's plane (z-depth, since ray z = 1).
      const float t = face.normal.dot(face.vertices[0] - c) / face.normal.dot(d);
      const float z = buf.depth.at<float>(v, u);
      worst = std::max(worst, static_cast<double>(std::abs(z - t)));
      EXPECT_NEAR(z, t, 1e-3f) << "pixel " << u << "," << v;
      const std::string& label = w.scene.solids()[static_cast<std::size_t>(face.solid)].label;
      if (label == "floor" && face.normal.z() > 0.99f) {
        EXPECT_NEAR(z, -c.z() / d.z(), 1e-3f);  // floor plane z = 0
        ++floor_checked;
      }
      if (face.tread > 0) {
        EXPECT_NEAR(z, (static_cast<float>(face.tread) * w.riser - c.z()) / d.z(), 1e-3f);
        ++tread_checked;
      }
    }
  }
  EXPECT_GT(floor_checked, 20);
  EXPECT_GT(tread_checked, 10);
  std::printf("[ renderer ] worst |depth - analytic| = %.3g m\n", worst);
}

TEST(SyntheticRender, NoisyTreadPointsLieOnTheirPlanes) {
  TestWorld w;
  SynthOptions o;  // noise on
  const CameraIntrinsics K = synthetic_intrinsics(o);
  RenderBuffers buf;
  render(w.scene, w.T_wc, K, buf);
  cv::Mat depth;
  apply_depth_sensor(buf, K, o, 77, depth);
  std::map<int, std::pair<int, int>> per_tread;  // tread -> (points, within the noise model)
  double sum_norm2 = 0.0;
  int n = 0;
  for (int v = 0; v < K.height; ++v)
    for (int u = 0; u < K.width; ++u) {
      const int f = buf.face.at<int>(v, u);
      const float z = depth.at<float>(v, u);
      if (f < 0 || z <= 0.f) continue;
      const Face& face = w.scene.faces()[static_cast<std::size_t>(f)];
      if (face.tread <= 0) continue;
      const Eigen::Vector3f p = w.T_wc * (z * ray_of(K, u, v));
      const float dev = p.z() - static_cast<float>(face.tread) * w.riser;
      // Depth noise moves the point along the ray: its height error is dz * |d.z| per unit z.
      const float dz_per_z = std::abs((w.T_wc.linear() * ray_of(K, u, v)).z());
      const float sigma_h = depth_sigma_model(z, o) * dz_per_z + 0.0005f;
      auto& e = per_tread[face.tread];
      ++e.first;
      if (std::abs(dev) <= 4.f * sigma_h) ++e.second;
      sum_norm2 += static_cast<double>(dev / sigma_h) * (dev / sigma_h);
      ++n;
    }
  ASSERT_GE(per_tread.size(), 3u);
  for (const auto& [k, e] : per_tread) {
    EXPECT_GT(e.first, 200) << "tread " << k;
    EXPECT_GE(static_cast<double>(e.second) / e.first, 0.99) << "tread " << k;
  }
  // The spread in units of the model's sigma is about 1 (not 0.2, not 5).
  const double rms = std::sqrt(sum_norm2 / n);
  EXPECT_GT(rms, 0.6);
  EXPECT_LT(rms, 1.3);
}

TEST(SyntheticSensor, NoiseSigmaMatchesKinectModel) {
  SynthOptions o;
  o.dropout = 0.f;
  const CameraIntrinsics K = synthetic_intrinsics(o);
  for (const float dist : {1.0f, 2.0f, 3.0f, 1.37f, 2.61f}) {
    Scene s;
    s.add_box_world({dist, -20.f, -20.f}, {dist + 0.2f, 20.f, 20.f}, plain(), "wall");
    const Pose T = camera_pose({0.f, 0.f, 0.f}, 0.f, 0.f, 0.f);  // looks along +x, fronto-parallel
    RenderBuffers buf;
    render(s, T, K, buf);
    double sum = 0, sum2 = 0;
    long n = 0;
    for (std::uint64_t seed = 1; seed <= 2; ++seed) {
      cv::Mat depth;
      apply_depth_sensor(buf, K, o, seed, depth);
      for (int v = 0; v < K.height; ++v)
        for (int u = 0; u < K.width; ++u) {
          const float z = depth.at<float>(v, u);
          ASSERT_GT(z, 0.f) << "hole on a fronto-parallel wall at " << dist << " m";
          const double e = static_cast<double>(z) - dist;
          sum += e;
          sum2 += e * e;
          ++n;
        }
    }
    const double mean = sum / n, sigma = std::sqrt(sum2 / n - mean * mean);
    const double model = 1.425e-3 * dist * dist;
    std::printf("[ noise ] z = %.2f m: measured sigma %.2f mm, model %.2f mm (ratio %.3f), bias %.2f mm\n",
                dist, sigma * 1e3, model * 1e3, sigma / model, mean * 1e3);
    EXPECT_NEAR(sigma / model, 1.0, 0.2) << "at " << dist << " m";
    EXPECT_LT(std::abs(mean), 0.25 * model + 0.0005) << "bias at " << dist << " m";
  }
}

// with_real_kinect_noise(): the same sigma, shared between neighbouring pixels (the white default
// shares nothing). Its match to the real clouds is PerceptionRealData.
// SyntheticNoiseCorrelatedAsTheRealClouds (test_perception).
TEST(SyntheticSensor, CorrelatedNoiseKeepsTheKinectSigma) {
  SynthOptions white;
  white.dropout = 0.f;
  const SynthOptions correlated = with_real_kinect_noise(white);
  const CameraIntrinsics K = synthetic_intrinsics(white);
  for (const float dist : {1.5f, 3.0f}) {
    Scene s;
    s.add_box_world({dist, -20.f, -20.f}, {dist + 0.2f, 20.f, 20.f}, plain(), "wall");
    RenderBuffers buf;
    render(s, camera_pose({0.f, 0.f, 0.f}, 0.f, 0.f, 0.f), K, buf);
    double lag1[2] = {0, 0}, sigma[2] = {0, 0};
    for (int k = 0; k < 2; ++k) {
      double s2 = 0, sxy = 0;
      long n = 0, m = 0;
      for (std::uint64_t seed = 1; seed <= 2; ++seed) {
        cv::Mat depth;
        apply_depth_sensor(buf, K, k == 0 ? white : correlated, seed, depth);
        for (int v = 0; v < K.height; ++v)
          for (int u = 0; u < K.width; ++u) {
            const double e = depth.at<float>(v, u) - dist;
            s2 += e * e, ++n;
            if (u + 1 < K.width) sxy += e * (depth.at<float>(v, u + 1) - dist), ++m;
          }
      }
      sigma[k] = std::sqrt(s2 / n);
      lag1[k] = (sxy / m) / (s2 / n);
    }
    const double model = 1.425e-3 * dist * dist;
    std::printf(
        "[ noise ] z = %.2f m: sigma white %.2f mm, correlated %.2f mm, model %.2f mm; neighbours' "
        "correlation white %.2f, correlated %.2f\n",
        dist, sigma[0] * 1e3, sigma[1] * 1e3, model * 1e3, lag1[0], lag1[1]);
    EXPECT_NEAR(sigma[1] / model, 1.0, 0.2) << "at " << dist << " m";
    EXPECT_LT(lag1[0], 0.1) << "white noise at " << dist << " m";
    EXPECT_GT(lag1[1], 0.5) << "correlated noise at " << dist << " m";
  }
}

TEST(SyntheticSensor, RangeGrazingAndShadowHoles) {
  SynthOptions o;
  o.dropout = 0.f;
  const CameraIntrinsics K = synthetic_intrinsics(o);
  // Too near: a wall at 0.4 m gives nothing.
  {
    Scene s;
    s.add_box_world({0.4f, -5.f, -5.f}, {0.5f, 5.f, 5.f}, plain(), "wall");
    RenderBuffers buf;
    render(s, camera_pose({0.f, 0.f, 0.f}, 0.f, 0.f, 0.f), K, buf);
    cv::Mat d;
    apply_depth_sensor(buf, K, o, 1, d);
    EXPECT_EQ(cv::countNonZero(d), 0);
    EXPECT_GT(cv::countNonZero(buf.depth), K.width * K.height / 2);
  }
  // A near post in front of a far wall: the projector's shadow falls left of the post and is
  // as wide as f*b*(1/z_near - 1/z_far) pixels; the far side of each depth jump is lost too.
  {
    Scene s;
    s.add_box_world({3.f, -5.f, -5.f}, {3.2f, 5.f, 5.f}, plain(), "wall");
    s.add_box_world({1.f, -0.1f, -5.f}, {1.1f, 0.1f, 5.f}, plain(), "post");
    RenderBuffers buf;
    render(s, camera_pose({0.f, 0.f, 0.f}, 0.f, 0.f, 0.f), K, buf);
    cv::Mat d;
    apply_depth_sensor(buf, K, o, 1, d);
    const int v = K.height / 2;
    int post_left = -1, post_right = -1;
    for (int u = 0; u < K.width; ++u)
      if (std::abs(buf.depth.at<float>(v, u) - 1.f) < 1e-3f) {
        if (post_left < 0) post_left = u;
        post_right = u;
      }
    ASSERT_GT(post_left, 0);
    int shadow = 0;
    for (int u = post_left - 1; u >= 0 && d.at<float>(v, u) == 0.f; --u) ++shadow;
    const float expected = K.fx * o.baseline_m * (1.f / 1.f - 1.f / 3.f);
    EXPECT_NEAR(shadow, expected, 2.0);
    EXPECT_EQ(d.at<float>(v, post_right + 1), 0.f);   // mixed pixel right of the post
    EXPECT_GT(d.at<float>(v, post_right + 3), 2.5f);  // then the wall again
  }
  // Grazing: a floor seen nearly edge-on is lost beyond the incidence limit.
  {
    Scene s;
    s.add_box_world({-5.f, -20.f, -0.2f}, {40.f, 20.f, 0.f}, plain(), "floor");
    const Pose T = camera_pose({0.f, 0.f, 0.6f}, 0.f, deg2rad(10.f), 0.f);
    RenderBuffers buf;
    render(s, T, K, buf);
    cv::Mat d;
    o.max_range_m = 20.f;  // isolate the grazing rule
    apply_depth_sensor(buf, K, o, 1, d);
    int lost = 0, kept = 0;
    for (int v = 0; v < K.height; ++v) {
      const int u = K.width / 2;
      const float ci = buf.cos_incidence.at<float>(v, u);
      if (buf.depth.at<float>(v, u) <= 0.f) continue;
      if (ci < std::cos(deg2rad(79.f))) lost += d.at<float>(v, u) == 0.f;
      if (ci > std::cos(deg2rad(77.f))) kept += d.at<float>(v, u) > 0.f;
      if (ci < std::cos(deg2rad(79.f))) {
        EXPECT_EQ(d.at<float>(v, u), 0.f) << "row " << v;
      }
    }
    EXPECT_GT(lost, 10);
    EXPECT_GT(kept, 100);
  }
}

TEST(SyntheticTruth, StairFrameAndVisibleStepsMatchTheRender) {
  const SynthOptions o = clean();
  const CameraIntrinsics K = synthetic_intrinsics(o);
  int frames_with_edge = 0, frames_with_ends = 0, treads_checked = 0;
  for (const char* preset : {"ascending_static", "descending_static", "nosing_landing_static",
                             "single_step_static", "open_risers_static", "people_static"}) {
    for (long i = 0; i < 6; ++i) {
      const PresetFrame pf = build_preset_frame(preset, i, 11, o);
      RenderBuffers buf;
      render(pf.scene, pf.walker.T_world_camera, K, buf, false);
      const FrameTruth t = compute_truth(pf.scene, pf.walker, buf, K, o);
      ASSERT_EQ(t.stairs.size(), pf.scene.stairs.size());
      for (std::size_t si = 0; si < t.stairs.size(); ++si) {
        const StairTruth& st = t.stairs[si];
        const StairSpec& sp = pf.scene.stairs[si];
        const Pose T_sc = st.T_camera_stair.inverse();
        // Every tread pixel, taken into the stair frame, lies on its tread: height +-(k-1) r
        // (ascending origin one riser up) or -k r (descending), within the tread's extent.
        std::map<int, int> count;
        for (int v = 0; v < K.height; ++v)
          for (int u = 0; u < K.width; ++u) {
            const int f = buf.face.at<int>(v, u);
            const float z = buf.depth.at<float>(v, u);
            if (f < 0 || z < o.min_range_m || z > o.max_range_m) continue;
            const Face& face = pf.scene.faces()[static_cast<std::size_t>(f)];
            if (face.stair != static_cast<int>(si) || face.tread <= 0) continue;
            ++count[face.tread];
            const Eigen::Vector3f p = T_sc * (z * ray_of(K, u, v));
            const float k = static_cast<float>(face.tread);
            const float y_expected = sp.down ? -k * sp.riser_m : (k - 1.f) * sp.riser_m;
            ASSERT_NEAR(p.y(), y_expected, 2e-3f) << preset << " frame " << i << " tread " << face.tread;
            // Tread `steps` of a flight is the landing / floor after it (wider and deeper).
            if (face.tread < sp.steps || sp.kind == StairKind::kSingleStep) {
              ASSERT_LE(std::abs(p.x()), 0.5f * sp.width_m + 1e-3f) << preset << " frame " << i;
              ASSERT_GE(p.z(), (k - 1.f) * sp.tread_m - sp.nosing_m - 0.031f) << preset;
              ASSERT_LE(p.z(), k * sp.tread_m + sp.nosing_m + 0.031f) << preset;
            }
            ++treads_checked;
          }
        // visible_steps = exactly the treads with >= 200 such pixels, with their counts.
        std::vector<int> steps, pixels;
        for (const auto& [k, c] : count)
          if (c >= 200) {
            steps.push_back(k);
            pixels.push_back(c);
          }
        EXPECT_EQ(st.visible_steps, steps) << preset << " frame " << i;
        EXPECT_EQ(st.visible_pixels, pixels) << preset << " frame " << i;
        // The first edge's centre and ends, projected with T_camera_stair, land on pixels whose
        // depth matches.
        auto depth_matches = [&](const Eigen::Vector3f& p_s) {
          const Eigen::Vector3f p = st.T_camera_stair * p_s;
          if (p.z() <= 0.f) return false;
          const int u = static_cast<int>(std::lround(K.fx * p.x() / p.z() + K.cx));
          const int v = static_cast<int>(std::lround(K.fy * p.y() / p.z() + K.cy));
          for (int dv = -1; dv <= 1; ++dv)
            for (int du = -1; du <= 1; ++du) {
              const int uu = u + du, vv = v + dv;
              if (uu < 0 || vv < 0 || uu >= K.width || vv >= K.height) continue;
              const float z = buf.depth.at<float>(vv, uu);
              // Back-projected pixel within 2 cm of the edge point in 3D.
              if (z > 0.f && (z * ray_of(K, uu, vv) - p).norm() < 0.02f) return true;
            }
          return false;
        };
        const float inset = 0.5f * sp.width_m - std::min(0.03f, 0.1f * sp.width_m);
        if (st.both_ends_visible) {
          ++frames_with_ends;
          EXPECT_TRUE(depth_matches({inset, 0.f, 0.f})) << preset << " frame " << i;
          EXPECT_TRUE(depth_matches({-inset, 0.f, 0.f})) << preset << " frame " << i;
        }
        if (st.first_edge_visible && st.both_ends_visible) {
          ++frames_with_edge;
          EXPECT_TRUE(depth_matches({0.f, 0.f, 0.f})) << preset << " frame " << i;
        }
        EXPECT_EQ(st.user_step, 0) << "static views stand before the staircase";
      }
    }
  }
  EXPECT_GT(frames_with_edge, 5);
  EXPECT_GT(frames_with_ends, 5);
  EXPECT_GT(treads_checked, 100000);
}

TEST(SyntheticTruth, ClimbSequenceIsConsistent) {
  SynthOptions o = clean();
  o.width = 160;  // the truth's geometry does not depend on the image size; keep it quick
  o.height = 120;
  auto src = make_source("ascending_approach_climb", 0, 5, o);
  ASSERT_EQ(src->frame_count(), 600);
  RgbdFrame f;
  Pose T_ws0 = Pose::Identity();
  int max_step = 0, prev_step = 0;
  float z0 = 0.f, z_end = 0.f, riser = 0.f;
  int steps = 0;
  for (long i = 0; i < 600; i += 1) {
    ASSERT_TRUE(src->read(f).ok());
    const FrameTruth t = *src->truth();
    if (i % 10 != 0 && i != 599) continue;  // ground truth every 10th frame is plenty
    ASSERT_EQ(t.index, static_cast<std::uint64_t>(i));
    EXPECT_NEAR(t.timestamp, i / 30.0, 1e-9);
    ASSERT_EQ(t.stairs.size(), 1u);
    const StairTruth& st = t.stairs[0];
    // T_world_camera * T_camera_stair is the fixed staircase.
    const Pose T_ws = t.T_world_camera * st.T_camera_stair;
    if (i == 0) {
      T_ws0 = T_ws;
      z0 = t.T_world_camera.translation().z();
      riser = st.riser_m;
      steps = st.steps;
    }
    EXPECT_LT((T_ws.matrix() - T_ws0.matrix()).cwiseAbs().maxCoeff(), 1e-4f) << "frame " << i;
    EXPECT_GE(st.user_step, prev_step) << "the user only climbs";
    prev_step = st.user_step;
    max_step = std::max(max_step, st.user_step);
    EXPECT_GT(t.camera_height_m, 0.95f);
    EXPECT_LT(t.camera_height_m, 1.75f);
    z_end = t.T_world_camera.translation().z();
  }
  EXPECT_EQ(steps, 8);
  EXPECT_EQ(max_step, 8);
  EXPECT_NEAR(z_end - z0, 8.f * riser, 0.03f);
  EXPECT_EQ(src->read(f).status, ReadStatus::kEnd);
}

TEST(SyntheticPresets, EveryPresetRendersWithSaneTruth) {
  const auto& list = presets();
  ASSERT_GE(list.size(), 20u);
  const std::set<std::string> required = {"ascending_approach_climb",
                                          "descending_approach_descend",
                                          "ascending_static",
                                          "descending_static",
                                          "open_risers_static",
                                          "nosing_landing_static",
                                          "rotated_static",
                                          "people_static",
                                          "handrails_open_sides_static",
                                          "single_step_static",
                                          "curb_static",
                                          "table_static",
                                          "bench_static",
                                          "shelves_static",
                                          "low_platform_static",
                                          "sofa_static",
                                          "corridor_static",
                                          "room_clutter_static",
                                          "ascending_turn_fast",
                                          "descending_people_approach"};
  std::set<std::string> names;
  for (const auto& p : list) names.insert(p.name);
  for (const auto& r : required) EXPECT_TRUE(names.count(r)) << r;

  const SynthOptions o;
  for (const auto& p : list) {
    SCOPED_TRACE(p.name);
    const bool sequence = p.default_frames > 1;
    auto src = make_source(p.name, 8, 21, o);
    RgbdFrame f;
    FrameTruth truth;
    int stair_seen = 0;
    const long n = 8;
    for (long i = 0; i < n; ++i) {
      if (sequence) {  // 8 evenly spaced frames of the sequence, rendered by random access
        render_preset_frame(p.name, i * (p.default_frames - 1) / (n - 1), 21, o, f, truth);
      } else {
        ASSERT_TRUE(src->read(f).ok());
        truth = *src->truth();
      }
      const FrameTruth& t = truth;
      ASSERT_EQ(f.depth.type(), CV_32FC1);
      ASSERT_EQ(f.color.type(), CV_8UC3);
      ASSERT_EQ(f.gray.type(), CV_8UC1);
      ASSERT_EQ(f.depth.cols, 640);
      ASSERT_EQ(f.depth.rows, 480);
      const int valid = cv::countNonZero(f.depth);
      EXPECT_GT(valid, 640 * 480 / 4);
      double mn = 0, mx = 0;
      cv::minMaxLoc(f.depth, &mn, &mx, nullptr, nullptr, f.depth > 0);
      EXPECT_GE(mn, 0.5 - 1e-6);
      EXPECT_LE(mx, 5.0 + 1e-6);
      cv::Scalar mean, sd;
      cv::meanStdDev(f.gray, mean, sd);
      EXPECT_GT(sd[0], 8.0) << "texture and shading give contrast";
      EXPECT_EQ(t.scene, p.name);
      EXPECT_GT(t.camera_height_m, 0.95f);
      EXPECT_LT(t.camera_height_m, 1.7f);
      EXPECT_GT(rad2deg(t.camera_tilt_rad), 20.f);
      EXPECT_LT(rad2deg(t.camera_tilt_rad), 70.f);
      EXPECT_LT(std::abs(rad2deg(t.camera_roll_rad)), 5.f);
      const bool stairs_expected = preset_has_stairs(p.name);
      EXPECT_EQ(!t.stairs.empty(), stairs_expected);
      for (const auto& st : t.stairs) {
        if (p.name.find("descending") != std::string::npos) {
          EXPECT_EQ(st.kind, StairKind::kDescending);
        }
        if (p.name.find("ascending") != std::string::npos) {
          EXPECT_EQ(st.kind, StairKind::kAscending);
        }
        if (p.name == "single_step_static") {
          EXPECT_EQ(st.kind, StairKind::kSingleStep);
        }
        if (p.name == "curb_static") {
          EXPECT_EQ(st.kind, StairKind::kCurb);
        }
        EXPECT_GE(st.riser_m, 0.12f);
        EXPECT_LE(st.riser_m, 0.18f);
        EXPECT_GE(st.steps, 1);
        EXPECT_LE(st.steps, 12);
        EXPECT_GT(st.width_m, 0.85f);
        const Eigen::Matrix3f R = st.T_camera_stair.linear();
        EXPECT_LT((R * R.transpose() - Eigen::Matrix3f::Identity()).cwiseAbs().maxCoeff(), 1e-4f);
        // y_S is up: in the camera it points against gravity (negative camera y when tilted down).
        const Eigen::Vector3f up_c = t.T_world_camera.linear().transpose() * Eigen::Vector3f::UnitZ();
        EXPECT_GT(R.col(1).dot(up_c), 0.9999f);
        EXPECT_EQ(st.visible_steps.size(), st.visible_pixels.size());
      }
      if (t.any_stair_visible()) ++stair_seen;
    }
    if (preset_has_stairs(p.name)) {
      // A preset about stairs shows them in a good share of its frames.
      EXPECT_GE(stair_seen, 3) << "frames with a visible staircase out of " << n;
    }
  }
}

TEST(SyntheticSource, DeterministicPerPresetSeedAndIndex) {
  const SynthOptions o;
  for (const char* preset : {"people_static", "descending_approach_descend"}) {
    auto a = make_source(preset, 3, 9, o);
    auto b = make_source(preset, 3, 9, o);
    auto c = make_source(preset, 3, 10, o);
    RgbdFrame fa, fb, fc;
    for (int i = 0; i < 3; ++i) {
      ASSERT_TRUE(a->read(fa).ok());
      ASSERT_TRUE(b->read(fb).ok());
      ASSERT_TRUE(c->read(fc).ok());
    }
    EXPECT_EQ(cv::norm(fa.depth, fb.depth, cv::NORM_INF), 0.0) << preset;
    EXPECT_EQ(cv::norm(fa.color, fb.color, cv::NORM_INF), 0.0) << preset;
    EXPECT_GT(cv::norm(fa.depth, fc.depth, cv::NORM_L1), 1.0) << preset << ": another seed, another frame";
    // The same frame rendered directly (random access) is identical to the streamed one.
    RgbdFrame fd;
    FrameTruth td;
    render_preset_frame(preset, 2, 9, o, fd, td);
    EXPECT_EQ(cv::norm(fa.depth, fd.depth, cv::NORM_INF), 0.0) << preset;
    EXPECT_EQ(cv::norm(fa.gray, fd.gray, cv::NORM_INF), 0.0) << preset;
    EXPECT_EQ(fd.index, 2u);
    EXPECT_TRUE(td.T_world_camera.isApprox(a->truth()->T_world_camera));
  }
}

TEST(SyntheticSource, UnknownPresetAndOptionsAreRejected) {
  try {
    make_source("no_such_scene", 1, 0);
    FAIL() << "expected SourceError";
  } catch (const SourceError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("no_such_scene"), std::string::npos);
    EXPECT_NE(m.find("ascending_approach_climb"), std::string::npos) << "lists the known scenes";
  }
  SynthOptions bad;
  bad.width = 0;
  EXPECT_THROW(make_source("ascending_static", 1, 0, bad), SourceError);
}

TEST(SyntheticSource, IntrinsicsScaleWithImageSize) {
  SynthOptions o;
  o.width = 320;
  o.height = 240;
  o.camera_height_m = 1.2f;
  o.camera_tilt_deg = 45.f;
  auto src = make_source("ascending_static", 2, 4, o);
  const CameraIntrinsics K = src->intrinsics();
  EXPECT_FLOAT_EQ(K.fx, 262.5f);
  EXPECT_FLOAT_EQ(K.fy, 262.5f);
  EXPECT_FLOAT_EQ(K.cx, 159.5f);
  EXPECT_FLOAT_EQ(K.cy, 119.5f);
  RgbdFrame f;
  ASSERT_TRUE(src->read(f).ok());
  EXPECT_EQ(f.depth.cols, 320);
  EXPECT_EQ(f.color.rows, 240);
  const FrameTruth t = *src->truth();
  EXPECT_NEAR(t.camera_height_m, 1.2f, 1e-4f);  // the overrides hold
  EXPECT_NEAR(rad2deg(t.camera_tilt_rad), 45.f, 1e-3f);
  EXPECT_EQ(src->frame_count(), 2);
}

// Beside an open-sided descent the lower floor lies under the upper floor's edge, as in a building:
// the view shows it there, not a bottomless void with the lower floor's slab edge standing in it
// (that edge, 0.2 m tall, counted as a wall in view for the Manhattan figure, 2772 px on this view
// noise-free, and gave frames of its own).
TEST(SyntheticPresets, LowerFloorRunsUnderAnOpenSidedDescent) {
  RgbdFrame f;
  FrameTruth t;
  render_preset_frame("descending_static", 23, 20261123u, clean(), f, t);
  ASSERT_EQ(t.stairs.size(), 1u);
  EXPECT_LT(t.wall_or_riser_pixels, 200) << "a wall or riser face in view (the slab edge was 2772 px)";
}
