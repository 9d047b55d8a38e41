// Perception (paper 3.1 and 3.3) on a scene built for the purpose, with known sizes: what each
// planar region carries (plane, centroid, points and pixels, area, rectangle in its own axes,
// concave-hull extent, curvature) and what it is classified as (floor, step candidate, obstacle;
// vertical left, right, front), and a curved pole left to the obstacle clusters.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>

#include "stairguide/capture/synth_source.hpp"
#include "stairguide/synth/builders.hpp"
#include "stairguide/synth/render.hpp"
#include "stairguide/perception/perception.hpp"

using namespace stairguide;
using namespace stairguide::synth;

namespace {

constexpr float kCamHeight = 1.40f;

// World: z up, the user at the origin looking along +y, a chest camera tilted 45 degrees down.
Pose chest_camera(float tilt_deg) {
  const float t = tilt_deg * 3.14159265f / 180.f;
  Eigen::Matrix3f R;
  R.col(0) = Eigen::Vector3f(1.f, 0.f, 0.f);                   // x right
  R.col(2) = Eigen::Vector3f(0.f, std::cos(t), -std::sin(t));  // z forward, down
  R.col(1) = R.col(2).cross(R.col(0));                         // y down
  Pose T = Pose::Identity();
  T.linear() = R;
  T.translation() = Eigen::Vector3f(0.f, 0.f, kCamHeight);
  return T;
}

struct Built {
  RgbdFrame frame;
  Pose T_world_camera;
};

// A room 3.1 m wide with a 16 cm platform (1.0 x 0.5 m) ahead, a 7 cm block to the right, and a
// pole (10 cm radius) to the left.
Built build() {
  Scene scene;
  scene.name = "regions";
  Rng rng(11);
  scene.add_box_world({-1.5f, -1.f, -0.1f}, {1.6f, 4.5f, 0.f}, floor_material(rng), "floor");
  scene.add_box_world({-1.6f, -1.f, 0.f}, {-1.5f, 4.5f, 2.5f}, wall_material(rng), "wall");  // left
  scene.add_box_world({1.6f, -1.f, 0.f}, {1.7f, 4.5f, 2.5f}, wall_material(rng), "wall");    // right
  scene.add_box_world({-1.6f, 4.0f, 0.f}, {1.7f, 4.1f, 2.5f}, wall_material(rng), "wall");   // ahead
  scene.add_box_world({-0.5f, 1.6f, 0.f}, {0.5f, 2.1f, 0.16f}, wood_material(rng), "platform");
  scene.add_box_world({0.6f, 0.9f, 0.f}, {1.0f, 1.2f, 0.07f}, wood_material(rng), "block");
  // Rendered as a prism: with 64 sides each facet is 1 cm wide, a curved surface to the sensor.
  scene.add_cylinder({-0.8f, 1.4f, 0.f}, {-0.8f, 1.4f, 1.0f}, 0.1f, 0.1f, metal_material(rng), "pole", 64);
  Built b;
  b.T_world_camera = chest_camera(45.f);
  const SynthOptions o;
  const CameraIntrinsics K = synthetic_intrinsics(o);
  RenderBuffers ideal;
  render(scene, b.T_world_camera, K, ideal, false);
  apply_depth_sensor(ideal, K, o, 7, b.frame.depth);
  b.frame.intrinsics = K;
  return b;
}

// The region whose centroid lies nearest `p_world` among those with a normal within 10 degrees
// of `n_world`; -1 when none.
int find_region(const SceneResult& sc, const Pose& T_wc, const Eigen::Vector3f& p_world,
                const Eigen::Vector3f& n_world, float max_dist) {
  int best = -1;
  float best_d = max_dist;
  for (int i = 0; i < static_cast<int>(sc.regions.size()); ++i) {
    const PlaneRegion& R = sc.regions[static_cast<std::size_t>(i)];
    if (std::fabs((T_wc.linear() * R.normal).dot(n_world)) < std::cos(0.1745f)) continue;
    const float d = (T_wc * R.centroid - p_world).norm();
    if (d < best_d) best_d = d, best = i;
  }
  return best;
}

}  // namespace

TEST(PerceptionRegions, GeometryAndClassesOnAKnownScene) {
  const Built b = build();
  Perception P;
  SceneResult sc;
  P.process(b.frame, sc);
  ASSERT_TRUE(sc.floor_found) << sc.why;
  EXPECT_NEAR(sc.camera_height, kCamHeight, 0.02f);
  EXPECT_NEAR(sc.camera_tilt * 180.f / 3.14159265f, 45.f, 1.f);
  ASSERT_TRUE(sc.manhattan_found) << sc.manhattan_why;
  const Pose& T = b.T_world_camera;
  const Eigen::Vector3f up(0.f, 0.f, 1.f), x(1.f, 0.f, 0.f), y(0.f, 1.f, 0.f);

  // Every region: a unit normal facing the camera, its points on its plane, pixels and count.
  for (const PlaneRegion& R : sc.regions) {
    EXPECT_NEAR(R.normal.norm(), 1.f, 1e-4f);
    EXPECT_LT(R.normal.dot(R.centroid), 0.f) << "normal facing away from the camera";
    EXPECT_EQ(R.pixel_count, static_cast<int>(R.pixels.size()));
    ASSERT_FALSE(R.points.empty());
    EXPECT_NEAR(R.normal.dot(R.centroid) + R.offset, 0.f, 0.01f);
  }

  // The floor.
  ASSERT_GE(sc.floor_region, 0);
  EXPECT_EQ(sc.regions[static_cast<std::size_t>(sc.floor_region)].cls, RegionClass::kFloor);

  // The platform's top, 1.0 x 0.5 m at 16 cm, seen whole: a step candidate with its size.
  const int top = find_region(sc, T, {0.f, 1.85f, 0.16f}, up, 0.1f);
  ASSERT_GE(top, 0) << "platform top not found";
  const PlaneRegion& P1 = sc.regions[static_cast<std::size_t>(top)];
  EXPECT_EQ(P1.cls, RegionClass::kStepCandidate);
  EXPECT_NEAR(P1.height, 0.16f, 0.01f);
  EXPECT_NEAR(P1.rect_length_major, 1.0f, 0.05f);
  EXPECT_NEAR(P1.rect_length_minor, 0.5f, 0.05f);
  EXPECT_NEAR(P1.area, 0.5f, 0.06f);
  EXPECT_GT(P1.hull_extent, 0.85f) << "a rectangle fills its bounding rectangle";
  EXPECT_LT(P1.curvature, 0.01f);
  EXPECT_LT((T * P1.centroid - Eigen::Vector3f(0.f, 1.85f, 0.16f)).norm(), 0.03f);
  EXPECT_GT((T.linear() * P1.rect_axis_major).cwiseAbs().x(), 0.98f)
      << "major axis along the platform's 1 m side";

  // Its front face, facing the user: vertical front.
  const int front = find_region(sc, T, {0.f, 1.6f, 0.08f}, y, 0.1f);
  ASSERT_GE(front, 0) << "platform front not found";
  EXPECT_EQ(sc.regions[static_cast<std::size_t>(front)].cls, RegionClass::kVerticalFront);

  // The block's top at 7 cm: horizontal, above the floor but below a step's height (H_min): an
  // obstacle to trip on.
  const int block = find_region(sc, T, {0.8f, 1.05f, 0.07f}, up, 0.1f);
  ASSERT_GE(block, 0) << "block top not found";
  EXPECT_EQ(sc.regions[static_cast<std::size_t>(block)].cls, RegionClass::kObstacle);
  EXPECT_NEAR(sc.regions[static_cast<std::size_t>(block)].height, 0.07f, 0.01f);

  // The side walls: the one on the user's left is vertical left, the other vertical right.
  int left = 0, right = 0, wrong = 0;
  for (const PlaneRegion& R : sc.regions) {
    const Eigen::Vector3f n = T.linear() * R.normal, c = T * R.centroid;
    if (std::fabs(n.dot(x)) < std::cos(0.1745f) || R.pixel_count < 500) continue;
    if (std::fabs(c.x() + 1.5f) < 0.05f) (R.cls == RegionClass::kVerticalLeft ? left : wrong)++;
    if (std::fabs(c.x() - 1.6f) < 0.05f) (R.cls == RegionClass::kVerticalRight ? right : wrong)++;
  }
  EXPECT_GE(left, 1) << "left wall";
  EXPECT_GE(right, 1) << "right wall";
  EXPECT_EQ(wrong, 0) << "a side wall classified the other way";

  // The pole is curved: no planar region stands on it, and an obstacle cluster does.
  for (const PlaneRegion& R : sc.regions) {
    const Eigen::Vector3f c = T * R.centroid;
    EXPECT_FALSE(std::hypot(c.x() + 0.8f, c.y() - 1.4f) < 0.12f && c.z() > 0.05f && R.pixel_count > 300)
        << "a plane of " << R.pixel_count << " px on the pole";
  }
  bool pole_cluster = false;
  for (const ObstacleCluster& C : sc.clusters) {
    const Eigen::Vector3f c = T * C.centroid;
    pole_cluster = pole_cluster || std::hypot(c.x() + 0.8f, c.y() - 1.4f) < 0.2f;
  }
  EXPECT_TRUE(pole_cluster) << "the pole is an obstacle cluster";
}

// With the real-like noise (correlated over 2 and 10 px), a staircase's first riser at the image's
// top edge, 3000 to 6000 px, met a patch of about 130 px bent 14 deg at its edge: the curved
// surfaces' test took it for a facet of one and gave it to the obstacles, and these views had no
// vertical plane at all. Facets of one curve are of a size (SegmentationConfig::
// curved_facet_size_ratio): the riser is a region again. (People still come out as obstacles:
// PerceptionRealData.BigPlanesWholeCurvedSurfacesObstacles.)
TEST(PerceptionRegions, FlatRiserWithANoisyPatchAtItsEdgeIsNoCurvedFacet) {
  const struct {
    const char* preset;
    long index;
    std::uint32_t seed;
  } views[] = {{"single_step_static", 9, 20261123u},
               {"single_step_static", 12, 20261123u},
               {"rotated_static", 6, 12},
               {"handrails_open_sides_static", 6, 5}};
  SegmentationConfig old_rule;
  old_rule.curved_facet_size_ratio = 0.f;
  // The biggest region upright in the world (within 10 deg), in pixels.
  auto biggest_upright = [](const SceneResult& sc, const FrameTruth& t) {
    int best = 0;
    for (const PlaneRegion& r : sc.regions)
      if (std::fabs((t.T_world_camera.linear() * r.normal).z()) < std::sin(0.1745f))
        best = std::max(best, r.pixel_count);
    return best;
  };
  for (const auto& v : views) {
    const std::string name =
        std::string(v.preset) + " #" + std::to_string(v.index) + " seed " + std::to_string(v.seed);
    RgbdFrame frame;
    FrameTruth truth;
    render_preset_frame(v.preset, v.index, v.seed, with_real_kinect_noise(), frame, truth);
    ASSERT_GE(truth.wall_or_riser_pixels, 3000) << name;
    SceneResult sc;
    Perception P;
    P.process(frame, sc);
    EXPECT_GE(biggest_upright(sc, truth), truth.wall_or_riser_pixels / 2) << name;
    Perception P_old(old_rule);
    P_old.process(frame, sc);
    EXPECT_LT(biggest_upright(sc, truth), truth.wall_or_riser_pixels / 2)
        << name << ": the riser was a region before too, the test does not test";
  }
}

// Paper 3.2.2: "throughout iterations F_T_M is recalculated but maintaining the orientation
// convention": walking and turning, k_M stays the direction nearest the user's forward and never
// jumps to the other Manhattan axis before the user has turned past 45 degrees, and it holds
// still in the world.
TEST(PerceptionManhattan, KeepsItsBranchWhileTheUserTurns) {
  const auto source = make_source("ascending_turn_fast", 0, 5);
  Perception P;
  RgbdFrame frame;
  SceneResult sc;
  int frames = 0, found = 0, jumps = 0, switches = 0;
  float prev_yaw = 0.f, prev_world = 0.f, worst_step = 0.f, worst_world = 0.f;
  bool have_prev = false;
  while (source->read(frame).ok()) {
    ++frames;
    P.process(frame, sc);
    if (!sc.floor_found || !sc.manhattan_found) {
      have_prev = false;
      continue;
    }
    ++found;
    // The nearest of the two axes to the user's forward, with the tracker's 10 degree hysteresis.
    EXPECT_LE(std::fabs(sc.manhattan_yaw), (45.f + 10.f) * 3.14159265f / 180.f);
    // k_M in the world (z up): the truth's camera pose carries it out of the floor frame.
    const std::optional<FrameTruth> t = source->truth();
    ASSERT_TRUE(t.has_value());
    const Eigen::Vector3f kF(std::sin(sc.manhattan_yaw), 0.f, std::cos(sc.manhattan_yaw));
    const Eigen::Vector3f kW = t->T_world_camera.linear() * (sc.T_floor_camera.linear().transpose() * kF);
    const float world = std::atan2(kW.y(), kW.x());
    if (have_prev) {
      // From one frame to the next the camera turns a few degrees. k_M moves to the other axis
      // only once the user's forward has turned past it (beyond 45 degrees, with hysteresis),
      // never back and forth near the middle.
      const float step = std::fabs(std::remainder(sc.manhattan_yaw - prev_yaw, 2.f * 3.14159265f));
      if (step > 30.f * 3.14159265f / 180.f) {
        ++switches;
        std::printf("frame %d: k_M from %.1f to %.1f deg (floor frame)\n", frames - 1,
                    prev_yaw * 180.f / 3.14159265f, sc.manhattan_yaw * 180.f / 3.14159265f);
        // (The fast turn moves the camera up to 10 degrees a frame: from 45 to past 55.)
        jumps += std::fabs(prev_yaw) < 30.f * 3.14159265f / 180.f;
      } else {
        worst_step = std::max(worst_step, step);
      }
      // In the world k_M stands still, or moves by 90 degrees when the user's forward crosses 45.
      float d = std::fabs(std::remainder(world - prev_world, 0.5f * 3.14159265f));
      worst_world = std::max(worst_world, d);
    }
    prev_yaw = sc.manhattan_yaw;
    prev_world = world;
    have_prev = true;
  }
  std::printf(
      "turning walk: %d frames, Manhattan frame on %d; %d switches of axis; largest step otherwise %.1f deg, "
      "world drift %.2f deg\n",
      frames, found, switches, worst_step * 180.f / 3.14159265f, worst_world * 180.f / 3.14159265f);
  EXPECT_GT(found, frames / 2);
  EXPECT_EQ(jumps, 0) << "k_M jumped to the other axis while the user still faced its own";
  // The walk turns across 45 degrees once (measured: one switch); without the hysteresis the
  // frames near 45 degrees would flip back and forth.
  EXPECT_LE(switches, 1) << "k_M switched axes back and forth";
  EXPECT_LT(worst_step * 180.f / 3.14159265f, 10.f) << "k_M moved more than the camera turns in a frame";
  EXPECT_LT(worst_world * 180.f / 3.14159265f, 2.f) << "k_M moved in the world between frames";
}
