// Floor detection on other seeds than the perception suite's (test_perception.cpp uses fixed
// ones): over every cold view of the staircase presets, the floor found is always the one the
// user stands on, never a tread; issue 3's "never a tread or a table taken for the floor".
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "stairguide/capture/synthetic.hpp"
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
    for (const char* preset : {"ascending_static", "ascending_short_static", "descending_static", "open_risers_static",
                               "nosing_landing_static", "rotated_static", "people_static",
                               "handrails_open_sides_static", "single_step_static", "curb_static"}) {
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

}  // namespace
