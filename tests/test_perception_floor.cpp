// Floor detection on other seeds than the perception suite's (test_perception.cpp uses fixed
// ones): over every cold view of the staircase presets, the floor found is always the one the
// user stands on, never a tread; issue 3's "never a tread or a table taken for the floor".
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "stairguide/synth/synth.hpp"
#include "stairguide/synth/render.hpp"
#include "stairguide/perception/perception.hpp"

namespace {

using namespace stairguide;

TEST(PerceptionFloor, NeverATreadOnOtherSeeds) {
  Perception perception{PipelineConfig{}};
  RgbdFrame frame;
  FrameTruth truth;
  SceneResult scene;
  int views = 0, visible = 0, found = 0, wrong = 0;
  for (std::uint32_t seed : {6u, 7u}) {
    for (const char* preset :
         {"ascending_static", "ascending_short_static", "descending_static", "open_risers_static",
          "nosing_landing_static", "rotated_static", "people_static", "handrails_open_sides_static",
          "single_step_static", "curb_static"}) {
      for (long i = 0; i < 16; ++i) {
        synth::render_preset_frame(preset, i, seed, synth::SynthOptions{}, frame, truth);
        perception.reset();  // independent views: nothing tracked
        perception.process(frame, scene);
        ++views;
        visible += truth.floor_visible;
        if (!scene.floor_found) continue;
        ++found;
        const float err = std::fabs(scene.camera_height - truth.camera_height_m);
        if (err > 0.02f) {
          ++wrong;
          std::printf("seed %u %s %ld: floor %.3f m below the camera, truth %.3f m\n", seed, preset, i,
                      scene.camera_height, truth.camera_height_m);
        }
      }
    }
  }
  std::printf("cold views %d, floor visible %d, found %d, wrong plane %d\n", views, visible, found, wrong);
  EXPECT_EQ(wrong, 0);
  // Measured 0.97 of the views with the floor visible (seeds 6-7; the misses are views whose
  // floor strip may be a first tread, reported as no floor).
  EXPECT_GE(found, 0.95 * visible);
}

// Cold views at the top of a descent (held-out seeds), the floor under the user's feet out of view:
// the first tread fills the bottom of the view, the floor around the stairwell lies a riser above
// it and the next tread a riser below it. The first tread reaches nearer the user's feet than the
// floor beside the stairwell, and was taken for the floor (15-16 cm too low: the flight one step
// short, its first edge a tread too far). In one view the floor cannot be verified there either
// (a lower level lies nearer the user's feet), so no floor is the right answer.
TEST(PerceptionFloor, TheFirstTreadOfADescentIsNoFloor) {
  Perception perception{PipelineConfig{}};
  RgbdFrame frame;
  FrameTruth truth;
  SceneResult scene;
  struct View {
    const char* preset;
    long index;
    std::uint32_t seed;
  };
  // A person standing on the flight splits the treads in the second view.
  for (const View& v : {View{"descending_static", 8, 3u}, View{"people_static", 18, 7u}}) {
    synth::render_preset_frame(v.preset, v.index, v.seed, synth::SynthOptions{}, frame, truth);
    perception.reset();
    perception.process(frame, scene);
    ASSERT_TRUE(truth.floor_visible) << v.preset << " " << v.index << ": the world changed";
    if (scene.floor_found) {
      EXPECT_LE(std::fabs(scene.camera_height - truth.camera_height_m), 0.02f)
          << v.preset << " " << v.index << " seed " << v.seed << ": a tread taken for the floor";
    }
  }
}

// Cold views of an ascending flight from its foot (the suite's seed) where the level strip at the
// view's bottom, with a step rising right after it, cannot be a tread of that flight. Both were
// refused as a possible first tread before (no floor).
constexpr std::uint32_t kSuiteSeed = 20261123u;

// One static view perceived from nothing (as the wearer switches the aid on).
SceneResult cold_view(const char* preset, long index, std::uint32_t seed, FrameTruth& truth) {
  Perception perception{PipelineConfig{}};
  RgbdFrame frame;
  SceneResult scene;
  synth::render_preset_frame(preset, index, seed, synth::SynthOptions{}, frame, truth);
  perception.process(frame, scene);
  return scene;
}

void expect_floor_found(const char* preset, long index, const char* cue, std::uint32_t seed = kSuiteSeed) {
  FrameTruth truth;
  const SceneResult scene = cold_view(preset, index, seed, truth);
  ASSERT_TRUE(truth.floor_visible) << preset << " " << index << ": the world changed";
  ASSERT_TRUE(scene.floor_found) << preset << " " << index << " (" << cue << "): " << scene.why;
  EXPECT_LE(std::fabs(scene.camera_height - truth.camera_height_m), 0.02f) << preset << " " << index;
}

// The floor region (2.33 m wide) goes on beside the flight (treads 1.83 m wide), past the riser
// line of the first tread: a tread ends at the riser rising from its back, so this level is the
// floor around the flight.
TEST(PerceptionFloor, FloorBesideTheFlightIsNoTread) {
  expect_floor_found("handrails_open_sides_static", 20, "level beyond the riser line, beside the flight");
}

// The floor strip is 0.39 m deep from the view's bottom to the first riser, the treads ahead
// 0.35 m (two of them, agreeing): treads within a flight are uniform, so the strip is no tread.
TEST(PerceptionFloor, FloorDeeperThanTheTreadsIsNoTread) {
  expect_floor_found("nosing_landing_static", 5, "deeper than the treads ahead");
}

// The protection kept: the same two views from one riser higher and a tread and a few cm further
// along the flight, the user still on the floor (the camera a riser higher above it): the first
// tread now fills the bottom of the view with less depth than a tread and nothing of its level
// beside the flight (the floor beside it is a riser lower). It must never be taken for the floor.
TEST(PerceptionFloor, TheFirstTreadWithTheFloorOutOfViewIsRefused) {
  Perception perception{PipelineConfig{}};
  RgbdFrame frame;
  FrameTruth truth;
  SceneResult scene;
  const synth::SynthOptions opt;
  const CameraIntrinsics K = synth::synthetic_intrinsics(opt);
  int refused = 0;
  for (const auto& [preset, index] : {std::pair<const char*, long>{"handrails_open_sides_static", 20},
                                      std::pair<const char*, long>{"nosing_landing_static", 5}}) {
    synth::PresetFrame pf = synth::build_preset_frame(preset, index, kSuiteSeed, opt);
    // The flight's direction and size, from the truth of the original view.
    synth::render_preset_frame(preset, index, kSuiteSeed, opt, frame, truth);
    ASSERT_FALSE(truth.stairs.empty()) << preset;
    const StairTruth& st = truth.stairs.front();
    ASSERT_EQ(st.kind, StairKind::kAscending) << preset;
    const Eigen::Vector3f up_flight =
        (pf.walker.T_world_camera.linear() * st.T_camera_stair.linear().col(2)).normalized();
    Pose T = pf.walker.T_world_camera;
    T.translation() += (st.tread_m + 0.05f) * up_flight + Eigen::Vector3f(0.f, 0.f, st.riser_m);
    synth::RenderBuffers buf;
    synth::render(pf.scene, T, K, buf, true);
    synth::apply_depth_sensor(buf, K, opt, 7u, frame.depth);
    synth::apply_color_sensor(buf, opt, 7u, frame.color, frame.gray);
    frame.intrinsics = K;
    pf.walker.T_world_camera = T;  // support_z unchanged: the user still stands on the floor
    truth = synth::compute_truth(pf.scene, pf.walker, buf, K, opt);
    perception.reset();
    perception.process(frame, scene);
    if (!scene.floor_found) {
      ++refused;
      continue;
    }
    // Only the floor itself (beside the flight) may be found; the first tread is a riser higher.
    EXPECT_LE(std::fabs(scene.camera_height - truth.camera_height_m), 0.02f)
        << preset << " " << index << " shifted: the first tread taken for the floor (floor at "
        << scene.camera_height << " m, truth " << truth.camera_height_m << " m)";
  }
  // The floor under the nosing view is out of view: no floor there at least.
  EXPECT_GE(refused, 1);
}

// Cold view up a flight between the walls of a stairwell (held-out seed 19), the floor out of
// view: the first tread fills the bottom of the view, 0.30 m deep like the treads ahead and as
// wide as the flight. Only 85% of its pixels have the next tread above them in the image (the rest
// lie under the stairwell's side wall), so the column test let it through and it was taken for
// the floor (1.398 m for 1.567 m: the flight counted a step short). In 3D it has a tread's shape.
TEST(PerceptionFloor, TheFirstTreadInAStairwellIsNoFloor) {
  FrameTruth truth;
  const SceneResult scene = cold_view("ascending_short_static", 13, 19u, truth);
  ASSERT_FALSE(truth.stairs.empty()) << "the world changed";
  if (scene.floor_found) {
    EXPECT_LE(std::fabs(scene.camera_height - truth.camera_height_m), 0.02f)
        << "a tread taken for the floor (floor at " << scene.camera_height << " m, truth "
        << truth.camera_height_m << " m)";
  }
}

// What that protection leaves alone (held-out seeds): the floor in front of a flight that fills a
// stairwell wall to wall is as wide as the flight too, but seen deeper than its treads (0.45 to
// 0.60 m against 0.29 to 0.32 m), so it is no tread and stays the floor.
TEST(PerceptionFloor, TheFloorOfAStairwellDeeperThanATreadIsKept) {
  expect_floor_found("ascending_short_static", 3, "wall to wall, 0.60 m deep", 13u);
  expect_floor_found("ascending_short_static", 8, "wall to wall, 0.45 m deep", 5u);
  expect_floor_found("ascending_short_static", 5, "wall to wall, 0.55 m deep", 20u);
}

// Cold view of a curb from its upper level (held-out seed 2): the user's level shows only as a
// strip cut by the view's bottom-left corner (0.165 m above the road, too small for a floor), and
// the road was taken for the floor (1.44 m instead of 1.275 m: the curb ahead turned upside down).
// The strip's straight edge with the road leaves the nadir on the strip's side: no floor.
void expect_user_on_level_above(const char* preset, long index, std::uint32_t seed) {
  FrameTruth truth;
  const SceneResult scene = cold_view(preset, index, seed, truth);
  EXPECT_FALSE(scene.floor_found) << preset << " " << index << ": floor at " << scene.camera_height
                                  << " m, truth " << truth.camera_height_m << " m";
  EXPECT_NE(scene.why.find("level above"), std::string::npos) << scene.why;
}

TEST(PerceptionFloor, UserOnTheLevelAboveAtTheViewsEdgeIsNoFloor) {
  expect_user_on_level_above("curb_static", 4, 2u);
}

// The same from near the view's corner (held-out seed 20): the user's level shows as a triangle
// cut by the view's left and bottom borders, and its edge with the road runs 0.54 m between them,
// short of the 0.8 m asked of a curb's edge; the road was taken for the floor (1.499 m for
// 1.365 m). An edge cut by the view at both ends is as long as it is seen or longer: no floor.
TEST(PerceptionFloor, UserOnTheLevelAboveSeenInTheViewsCornerIsNoFloor) {
  expect_user_on_level_above("curb_static", 1, 20u);
}

// The protection does not reach a step beside the floor (held-out seed 3): a single step cut by
// the view's bottom edge, 0.166 m above the floor, with a straight 1.2 m edge, but the nadir lies
// on the floor's side of that edge (about 1 m): the user stands on the floor, which is found.
TEST(PerceptionFloor, AStepAtTheViewsEdgeAheadKeepsTheFloor) {
  expect_floor_found("single_step_static", 11, "a step at the view's edge, the nadir on the floor's side",
                     3u);
}

// Standing 0.5-2 m from a drop's edge (a platform, a dock, a hole, a sunken floor), a cold view
// often holds only a strip of the user's floor along its bottom edge, smaller than min_area in
// every window, beside a lower level (a hole's far wall under the floor beyond it looked like a
// tread's riser). The strip, cut by the view's bottom edge at the usual chest rig's height and
// tilt, is the floor. Seed 1201 was never tuned on (tuned on 801 and 1003: the floor was missed
// on 22 of 400 such views, 3 after); measured here 50 of 52 found, none on a wrong plane.
TEST(PerceptionFloor, TheStripOfFloorBeforeADropIsTheFloor) {
  Perception perception{PipelineConfig{}};
  RgbdFrame frame;
  FrameTruth truth;
  SceneResult scene;
  synth::SynthOptions o;
  ASSERT_TRUE(synth::sensor_options("real-v1", o));
  int near = 0, found = 0, wrong = 0;
  for (const char* preset :
       {"drop_platform_static", "drop_dock_static", "drop_hole_static", "drop_sunken_static"})
    for (long i = 0; i < 30; ++i) {
      synth::render_preset_frame(preset, i, 1201u, o, frame, truth);
      if (!truth.drop_in_view || truth.drop_distance_m > 2.f) continue;
      perception.reset();
      perception.process(frame, scene);
      ++near;
      if (!scene.floor_found) {
        std::printf("%s %ld: no floor (%s)\n", preset, i, scene.why.c_str());
        continue;
      }
      ++found;
      if (std::fabs(scene.camera_height - truth.camera_height_m) > 0.03f) {
        ++wrong;
        std::printf("%s %ld: floor %.3f m below the camera, truth %.3f m\n", preset, i, scene.camera_height,
                    truth.camera_height_m);
      }
    }
  std::printf("drop views within 2 m: %d, floor found %d, on a wrong plane %d\n", near, found, wrong);
  ASSERT_GE(near, 30);
  EXPECT_EQ(wrong, 0);
  EXPECT_GE(found, near - 3);
}

// A low table filling the bottom of the view, the room's floor at the bottom corners beside it:
// where its near edge is in view the floor shows right under it, and the columns where the table
// runs on to the view's bottom edge are no evidence for it (the floor beside it is at a floor's
// height). Tuning view (world2_sofa seed 801 #10): taking the table made a stair false positive.
TEST(PerceptionFloor, ALowTableAtTheViewsBottomIsNoFloor) {
  Perception perception{PipelineConfig{}};
  RgbdFrame frame;
  FrameTruth truth;
  SceneResult scene;
  synth::SynthOptions o;
  ASSERT_TRUE(synth::sensor_options("real-v1", o));
  synth::render_preset_frame("world2_sofa_static", 10, 801u, o, frame, truth);
  perception.process(frame, scene);
  ASSERT_TRUE(scene.floor_found) << scene.why;
  EXPECT_NEAR(scene.camera_height, truth.camera_height_m, 0.03f);
}

}  // namespace
