// The drop-off stage (stairs/drop_detection.hpp, issue 42 item 4) on rendered drops and on the
// negatives it must stay silent on: stair-free rooms and furniture (both worlds), descending
// staircases (the stair stage tells those), and the real stair-free frames of ../shared/data.
// Seeds here are not the ones the stage was tuned on (1 and 2).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "stairguide/capture/frame_source.hpp"
#include "stairguide/synth/synth.hpp"
#include "stairguide/stairs/drop_detection.hpp"
#include "synth_stairs_test_util.hpp"

namespace sg = stairguide;

namespace {

struct DropRun {
  int near = 0, near_told = 0, told_elsewhere = 0, frames = 0;
  int near_no_floor = 0;  // near frames missed where perception found no floor (a strip of floor in view)
  double abs_distance_err = 0.0;
};

// Every view of `preset` cold (independent views), through perception, the stairs stage and
// the drop stage, scored against the truth.
DropRun run_preset(const std::string& preset, int frames, std::uint32_t seed, const std::string& noise) {
  sgtest::SynthStairs s;
  EXPECT_TRUE(sg::synth::sensor_options(noise, s.options)) << noise;
  DropRun r;
  for (int i = 0; i < frames; ++i) {
    const sg::StairResult& st = s.step(preset, i, seed, true);
    const sg::DropSummary d = sg::summarize_drop(sg::detect_drop(s.frame, s.scene, s.cfg.drops), st);
    ++r.frames;
    if (s.truth.drop_in_view && s.truth.drop_distance_m <= 2.f) {
      ++r.near;
      if (d.detected) {
        ++r.near_told;
        r.abs_distance_err += std::fabs(d.distance_m - s.truth.drop_distance_m);
      } else {
        r.near_no_floor += !s.scene.floor_found;
      }
    } else if (!s.truth.drop_in_view && s.truth.drop_depth_m == 0.f) {
      r.told_elsewhere += d.detected;
    }
  }
  return r;
}

}  // namespace

// The truth side: each preset labels its drop, in view on most views, within the drawn ranges.
TEST(DropPresets, TruthInRange) {
  for (const auto& p : sg::synth::drop_presets()) {
    if (p.default_frames > 1) continue;
    int in_view = 0;
    for (int i = 0; i < 20; ++i) {
      sg::RgbdFrame f;
      sg::FrameTruth t;
      sg::synth::render_preset_frame(p.name, i, 77, {}, f, t);
      EXPECT_GE(t.drop_depth_m, 0.3f) << p.name;
      EXPECT_LE(t.drop_depth_m, 1.5f) << p.name;
      if (!t.drop_in_view) continue;
      ++in_view;
      EXPECT_GT(t.drop_distance_m, 0.3f) << p.name << " " << i;
      EXPECT_LT(t.drop_distance_m, 5.f) << p.name << " " << i;
      EXPECT_LT(std::fabs(t.drop_bearing_rad), 1.2f) << p.name << " " << i;
      EXPECT_TRUE(t.stairs.empty()) << p.name;
    }
    EXPECT_GE(in_view, 14) << p.name;
  }
}

// Told on the views with the edge within 2 m, where it is (distance within 5 cm on average).
TEST(DropDetection, ToldOnTheDropPresets) {
  for (const char* preset :
       {"drop_platform_static", "drop_dock_static", "drop_hole_static", "drop_sunken_static"})
    for (const char* noise : {"real-v1", "tof-v2"}) {
      const DropRun r = run_preset(preset, 16, 31, noise);
      std::printf("%-22s %-8s near %d/%d (%d missed with no floor found), mean |distance error| %.3f m\n",
                  preset, noise, r.near_told, r.near, r.near_no_floor,
                  r.near_told ? r.abs_distance_err / r.near_told : 0.0);
      ASSERT_GE(r.near, 3) << preset;
      // Every view with its floor found is told; a view whose floor is a strip at the bottom of the
      // image (the edge 0.5-0.7 m away) may have no floor from perception, and then no drop.
      EXPECT_GE(r.near_told + r.near_no_floor, r.near) << preset << " " << noise;
      EXPECT_GE(r.near_told, r.near - 2) << preset << " " << noise;
      if (r.near_told > 0) {
        EXPECT_LT(r.abs_distance_err / r.near_told, 0.05) << preset;
      }
    }
}

// Silent on rooms, corridors and furniture of both worlds, with every sensor model's artefacts
// (dark floors that read nothing beyond 2 m included).
TEST(DropDetection, SilentOnStairFreePresets) {
  const std::vector<std::string> presets = {
      "floor_only_static",   "corridor_static",      "room_clutter_static",   "table_static",
      "low_platform_static", "rig_furniture_static", "world2_bed_static",     "world2_lowtable_static",
      "world2_boxes_static", "world2_sofa_static",   "world2_shelves_static", "world2_bench_static"};
  for (const auto& p : presets)
    for (const char* noise : {"real-v1", "real-v2", "sl-v1"}) {
      const DropRun r = run_preset(p, 6, 41, noise);
      EXPECT_EQ(r.told_elsewhere, 0) << p << " " << noise;
    }
}

// A descending flight is the stair stage's: where it finds one, a drop found there is not told.
TEST(DropDetection, DescentSeenByTheStairStageIsNotADrop) {
  sgtest::SynthStairs s;
  int both = 0, descents = 0;
  for (int i = 0; i < 16; ++i) {
    const sg::StairResult& st = s.step("descending_static", i, 43, true);
    const sg::DropResult d = sg::detect_drop(s.frame, s.scene, s.cfg.drops);
    const sg::DropSummary told = sg::summarize_drop(d, st);
    if (st.detected && st.direction() < 0) {
      ++descents;
      EXPECT_FALSE(told.detected) << i;
      both += told.by_stairs;
    }
  }
  EXPECT_GE(descents, 8);
  std::printf("descending_static: %d descents told by the stair stage, %d of them also a drop edge\n",
              descents, both);
}

// What the stage says when it cannot look: no floor, disabled; and every length in the result
// the camera's own (the same drop at half the resolution).
TEST(DropDetection, VerdictsAndResolution) {
  sgtest::SynthStairs s;
  s.perceive("drop_dock_static", 1, 53, true);
  sg::SceneResult none = s.scene;
  none.floor_found = false;
  EXPECT_EQ(sg::detect_drop(s.frame, none, s.cfg.drops).verdict, sg::DropVerdict::kNoFloor);
  sg::DropConfig off = s.cfg.drops;
  off.enabled = false;
  EXPECT_EQ(sg::detect_drop(s.frame, s.scene, off).verdict, sg::DropVerdict::kDisabled);
  ASSERT_TRUE(s.truth.drop_in_view);
  const sg::DropResult full = sg::detect_drop(s.frame, s.scene, s.cfg.drops);
  ASSERT_TRUE(full.detected) << sg::to_string(full.verdict);
  EXPECT_NEAR(full.distance_m, s.truth.drop_distance_m, 0.08);
  EXPECT_NEAR(full.bearing_rad, s.truth.drop_bearing_rad, 0.1);
  EXPECT_NEAR(full.depth_m, s.truth.drop_depth_m, 0.15);
  sgtest::SynthStairs half;
  half.options.width = 320;
  half.options.height = 240;
  half.perceive("drop_dock_static", 1, 53, true);
  const sg::DropResult small = sg::detect_drop(half.frame, half.scene, half.cfg.drops);
  ASSERT_TRUE(small.detected) << sg::to_string(small.verdict);
  EXPECT_NEAR(small.distance_m, full.distance_m, 0.08);
  // A drop deeper than min_depth only: with the threshold above the drop, the edge is not one.
  sg::DropConfig deep = s.cfg.drops;
  deep.min_depth = s.truth.drop_depth_m + 0.2f;
  EXPECT_FALSE(sg::detect_drop(s.frame, s.scene, deep).detected);
}

// Walking towards a platform edge (perception tracking the floor frame to frame): told well
// before the edge, and on every frame from 2 m on while the edge is in view.
TEST(DropDetection, WalkTowardsAPlatformEdge) {
  sgtest::SynthStairs s;
  ASSERT_TRUE(sg::synth::sensor_options("real-v1", s.options));
  float first_told = -1.f;
  int near = 0, near_told = 0, no_floor = 0;
  for (int i = 0; i < 330; i += 2) {
    const sg::StairResult& st = s.step("drop_platform_walk", i, 61, i == 0);
    const sg::DropSummary d = sg::summarize_drop(sg::detect_drop(s.frame, s.scene, s.cfg.drops), st);
    if (d.detected && first_told < 0.f && s.truth.drop_in_view) first_told = s.truth.drop_distance_m;
    if (s.truth.drop_in_view && s.truth.drop_distance_m <= 2.f) {
      ++near;
      near_told += d.detected;
      no_floor += !d.detected && !s.scene.floor_found;
    }
  }
  // Standing 0.5-0.7 m from the edge the floor is a strip perception does not take: the runtime
  // carries the floor by the odometry there (test_runtime_pipeline); this stage alone cannot.
  std::printf("platform walk: first told at %.2f m; near %d/%d, %d missed with no floor found\n", first_told,
              near_told, near, no_floor);
  EXPECT_GT(first_told, 1.9f);
  ASSERT_GE(near, 20);
  EXPECT_GE(near_told + no_floor, near - 1);
}

// The real stair-free frames of ../shared/data (labels.csv): no drop in any of them.
TEST(DropDetection, RealStairFreeFramesSilent) {
  const std::string dir = STAIRGUIDE_SHARED_DATA;
  std::ifstream in(dir + "/labels.csv");
  if (!in) GTEST_SKIP() << "no shared data at " << dir;
  sg::PipelineConfig cfg;
  sg::Perception perception(cfg);
  sg::StairStage stage(cfg);
  std::string line;
  int none = 0, told = 0;
  std::getline(in, line);
  while (std::getline(in, line)) {
    const auto c1 = line.find(','), c2 = line.find(',', c1 + 1);
    if (c1 == std::string::npos || line.substr(c1 + 1, c2 - c1 - 1) != "none") continue;
    auto src = sg::open_frame_source(dir + "/" + line.substr(0, c1), cfg.capture);
    sg::RgbdFrame f;
    ASSERT_TRUE(src->read(f).ok()) << line;
    sg::SceneResult scene;
    sg::StairResult st;
    perception.reset();
    perception.process(f, scene);
    stage.run(scene, f.intrinsics, st);
    const sg::DropResult d = sg::detect_drop(f, scene, cfg.drops);
    ++none;
    told += d.detected;
    EXPECT_FALSE(d.detected) << line << ": " << d.distance_m << " m";
  }
  EXPECT_EQ(none, 12);
  EXPECT_EQ(told, 0);
}
