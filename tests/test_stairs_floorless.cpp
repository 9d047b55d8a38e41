// The floorless route (stairs/floorless.hpp): staircases found when perception saw no floor, on
// hand-built perception results (test_stairs_scene.hpp) with the floor taken out of view.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "stairguide/capture/synthetic.hpp"
#include "stairguide/perception/perception.hpp"
#include "stairguide/stairs/stair_eval.hpp"
#include "stairguide/stairs/stairs.hpp"
#include "test_stairs_scene.hpp"

namespace {

using namespace stairguide;
using sgtest::SceneBuilder;
using sgtest::StairSpec;

/// The pipeline's defaults with the floorless route on (the default; set here so the tests say it).
PipelineConfig on() {
  PipelineConfig c;
  c.stair_detection.floorless = true;
  return c;
}

/// Removes the floor region (the view cropped above it) and perception's floor.
void drop_floor(SceneResult& scene) {
  if (scene.floor_region >= 0) scene.regions.erase(scene.regions.begin() + scene.floor_region);
  scene.floor_region = -1;
  scene.floor_found = false;
  scene.T_floor_camera = Pose::Identity();
  scene.camera_height = 0.f;
}

/// Removes the first `k` tread regions (the lowest ones out of view: the user at the foot of the
/// staircase or on it). Treads follow the floor in SceneBuilder::add_stairs.
void drop_first_treads(SceneResult& scene, int k) {
  for (int i = 0; i < k && !scene.regions.empty(); ++i) scene.regions.erase(scene.regions.begin());
}

struct Tally {
  int frames = 0, detected = 0, wrong_direction = 0, with_tread = 0;
  double riser_abs = 0, riser_max = 0, tread_abs = 0, tread_max = 0;
  void add(const StairResult& r, const StairSpec& s) {
    ++frames;
    if (!r.detected) return;
    ++detected;
    EXPECT_TRUE(r.without_floor);
    const bool up = r.kind == StairKind::kAscending;
    if (up != (s.direction > 0)) ++wrong_direction;
    const double er = std::fabs(r.riser_m - s.riser);
    riser_abs += er;
    riser_max = std::max(riser_max, er);
    if (r.tread_m > 0.f) {
      ++with_tread;
      const double et = std::fabs(r.tread_m - s.tread);
      tread_abs += et;
      tread_max = std::max(tread_max, et);
    }
  }
  void print(const char* what) const {
    std::printf("%-34s frames %3d detected %3d wrong direction %d; riser |err| mean %.2f max %.2f cm; tread (%d) |err| mean %.2f max %.2f cm\n",
                what, frames, detected, wrong_direction, detected ? 100.0 * riser_abs / detected : 0.0, 100.0 * riser_max,
                with_tread, with_tread ? 100.0 * tread_abs / with_tread : 0.0, 100.0 * tread_max);
  }
};

// Views over camera tilt, yaw of the staircase, distance and direction, floor out of view.
TEST(StairsFloorless, StaircasesWithoutFloor) {
  const PipelineConfig cfg = on();
  StairStage stage(cfg);
  Tally asc, desc, asc_cut;
  unsigned seed = 100;
  for (int dir : {1, -1}) {
    for (float tilt : {30.f, 45.f, 60.f}) {
      for (float yaw : {-15.f, 0.f, 20.f}) {
        // Descending, the floor leaves the view only near the top edge; from farther away the
        // self-occluded treads show as strips too thin for a level (and the floor is in view).
        for (float dist : {dir > 0 ? 0.9f : 0.4f, dir > 0 ? 1.6f : 0.9f}) {
          StairSpec s;
          s.direction = dir;
          s.steps = 5;
          s.yaw_deg = yaw;
          s.distance = dist;
          s.riser = dir > 0 ? 0.17f : 0.16f;
          s.tread = dir > 0 ? 0.29f : 0.31f;
          SceneBuilder b(1.4f, tilt, seed++);
          b.add_stairs(s);
          drop_floor(b.scene);
          StairResult r;
          stage.run(b.scene, r);
          (dir > 0 ? asc : desc).add(r, s);
          if (!r.detected)
            std::printf("miss: dir %d tilt %.0f yaw %.0f dist %.1f: %s (levels %d, stacked %d, direction %d)\n", dir, tilt, yaw,
                        dist, to_string(r.verdict), r.levels, stage.floorless_trace().stacked,
                        stage.floorless_trace().direction);
          if (dir > 0) {
            // The first tread out of view too: the stack starts at tread 2.
            SceneBuilder c(1.4f, tilt, seed++);
            c.add_stairs(s);
            drop_floor(c.scene);
            drop_first_treads(c.scene, 1);
            stage.run(c.scene, r);
            asc_cut.add(r, s);
          }
        }
      }
    }
  }
  asc.print("ascending, no floor");
  asc_cut.print("ascending, no floor nor tread 1");
  desc.print("descending, no floor");
  EXPECT_EQ(asc.wrong_direction + desc.wrong_direction + asc_cut.wrong_direction, 0);
  EXPECT_GE(asc.detected, 17) << "of 18";
  EXPECT_GE(asc_cut.detected, 17) << "of 18";
  EXPECT_GE(desc.detected, 17) << "of 18";
  EXPECT_LE(asc.riser_max, 0.01);
  EXPECT_LE(desc.riser_max, 0.01);
  EXPECT_LE(asc.tread_max, 0.02);
  EXPECT_LE(desc.tread_max, 0.02);
}

TEST(StairsFloorless, OriginOnTheFirstSeenEdge) {
  // Ascending, floor out of view: the origin is the first tread's nosing, as with a floor.
  const PipelineConfig cfg = on();
  StairStage stage(cfg);
  SceneBuilder b(1.3f, 45.f, 3);
  StairSpec s;
  s.steps = 5;
  s.yaw_deg = 10.f;
  b.add_stairs(s);
  drop_floor(b.scene);
  StairResult r;
  stage.run(b.scene, r);
  ASSERT_TRUE(r.detected) << to_string(r.verdict);
  EXPECT_EQ(r.kind, StairKind::kAscending);
  const float pos = (r.T_camera_stair.translation() - b.truth.T_camera_stair.translation()).norm();
  const float yaw = rad2deg(std::acos(std::clamp(
      r.T_camera_stair.linear().col(2).dot(b.truth.T_camera_stair.linear().col(2)), -1.f, 1.f)));
  std::printf("origin error %.2f cm, yaw error %.2f deg, levels %d\n", 100.f * pos, yaw, r.levels);
  EXPECT_LT(pos, 0.03f);
  EXPECT_LT(yaw, 2.f);
  EXPECT_EQ(r.levels, 5);
  EXPECT_EQ(r.level_data[0].index, 0);
  EXPECT_TRUE(r.level_data[0].regions.empty());  // level 0 is virtual
}

TEST(StairsFloorless, FurnitureIsNoStaircase) {
  const PipelineConfig cfg = on();
  StairStage stage(cfg);
  StairResult r;
  {  // shelves: boards one riser apart straight above each other (no tread)
    SceneBuilder b(1.4f, 45.f, 11);
    for (int k = 0; k < 4; ++k) b.add_box_top(0.f, 1.6f, 1.0f, 0.35f, 0.3f + 0.17f * static_cast<float>(k), RegionClass::kStepCandidate);
    b.scene.floor_found = false;
    stage.run(b.scene, r);
    EXPECT_FALSE(r.detected) << to_string(r.verdict);
    EXPECT_EQ(stage.floorless_trace().stacked, 4);
  }
  {  // two narrow box tops one riser and one tread apart
    SceneBuilder b(1.4f, 45.f, 12);
    b.add_box_top(0.f, 1.5f, 0.35f, 0.3f, 0.4f, RegionClass::kStepCandidate);
    b.add_box_top(0.f, 1.8f, 0.35f, 0.3f, 0.57f, RegionClass::kStepCandidate);
    b.scene.floor_found = false;
    stage.run(b.scene, r);
    EXPECT_FALSE(r.detected) << to_string(r.verdict);
  }
  {  // a table top and a seat far apart: one level each, no stack
    SceneBuilder b(1.4f, 45.f, 13);
    b.add_box_top(0.5f, 1.5f, 1.2f, 0.8f, 0.75f, RegionClass::kStepCandidate);
    b.add_box_top(-1.2f, 1.5f, 0.5f, 0.5f, 0.45f, RegionClass::kStepCandidate);
    b.scene.floor_found = false;
    stage.run(b.scene, r);
    EXPECT_FALSE(r.detected);
    EXPECT_EQ(r.verdict, StairVerdict::kNoFloor);
  }
  {  // steps that do not connect (1 m apart): no stack
    SceneBuilder b(1.4f, 45.f, 14);
    b.add_box_top(0.f, 1.2f, 1.0f, 0.3f, 0.2f, RegionClass::kStepCandidate);
    b.add_box_top(0.f, 2.6f, 1.0f, 0.3f, 0.37f, RegionClass::kStepCandidate);
    b.scene.floor_found = false;
    stage.run(b.scene, r);
    EXPECT_FALSE(r.detected);
    EXPECT_LT(stage.floorless_trace().stacked, 2);
  }
}

TEST(StairsFloorless, ImplausibleVerticalIsRefused) {
  // The same staircase seen by a camera rolled 40 degrees: its treads' normal is no body camera's
  // "up" (roll limit 20 degrees), so nothing is reported.
  const PipelineConfig cfg = on();
  StairStage stage(cfg);
  SceneBuilder b(1.4f, 45.f, 21);
  StairSpec s;
  b.add_stairs(s);
  drop_floor(b.scene);
  const Eigen::Matrix3f roll = Eigen::AngleAxisf(deg2rad(40.f), Eigen::Vector3f::UnitZ()).toRotationMatrix();
  for (auto& reg : b.scene.regions) {
    for (auto& p : reg.points) p = roll * p;
    reg.normal = roll * reg.normal;
    reg.centroid = roll * reg.centroid;
  }
  StairResult r;
  stage.run(b.scene, r);
  EXPECT_FALSE(r.detected);
  EXPECT_FALSE(stage.floorless_trace().up_found);
}

/// Distance between the estimated and the true first-edge centres, m.
float origin_error(const StairResult& r, const StairTruth& t) {
  return (r.T_camera_stair.translation() - t.T_camera_stair.translation()).norm();
}

// The floor out of view but the camera's height above the feet remembered (perception's memory):
// the steps are placed from the feet, the first edge and the step indices as with a floor.
TEST(StairsFloorless, RememberedFloorPlacesTheFirstStep) {
  const PipelineConfig cfg = on();
  StairStage stage(cfg);
  constexpr float kHeight = 1.4f;
  int views = 0, placed = 0, hidden_placed = 0, floor_placed = 0;
  float worst = 0.f;
  unsigned seed = 200;
  for (int dir : {1, -1}) {
    for (float tilt : {35.f, 50.f}) {
      for (float yaw : {-10.f, 15.f}) {
        StairSpec s;
        s.direction = dir;
        s.steps = 5;
        s.yaw_deg = yaw;
        s.distance = dir > 0 ? 1.0f : 0.5f;
        s.riser = dir > 0 ? 0.17f : 0.16f;
        s.tread = dir > 0 ? 0.29f : 0.31f;
        // (a) the floor out of view: the first seen level is the first step.
        SceneBuilder b(kHeight, tilt, seed++);
        b.add_stairs(s);
        drop_floor(b.scene);
        b.scene.remembered_camera_height = kHeight;
        StairResult r;
        stage.run(b.scene, r);
        ++views;
        if (r.detected) {
          EXPECT_TRUE(r.floor_remembered);
          EXPECT_FALSE(r.without_floor);
          EXPECT_EQ(r.direction(), dir);
          EXPECT_EQ(r.level_data[1].index, dir);
          EXPECT_NEAR(r.level_data[1].height, dir * s.riser, 0.01f);
          worst = std::max(worst, origin_error(r, b.truth));
          placed += origin_error(r, b.truth) < 0.03f;
        } else {
          ADD_FAILURE() << "dir " << dir << " tilt " << tilt << " yaw " << yaw << ": " << to_string(r.verdict);
        }
        // (b) the floor seen as a level (the floor detector refused it): it is level 0.
        SceneBuilder c(kHeight, tilt, seed++);
        c.add_stairs(s);
        c.scene.floor_found = false;
        c.scene.remembered_camera_height = kHeight;
        stage.run(c.scene, r);
        if (r.detected && r.floor_remembered && origin_error(r, c.truth) < 0.03f && r.level_data[1].index == dir) ++floor_placed;
        if (dir < 0) continue;
        // (c) tread 1 out of view too (under the camera): placed one tread before tread 2.
        SceneBuilder d(kHeight, tilt, seed++);
        d.add_stairs(s);
        drop_floor(d.scene);
        drop_first_treads(d.scene, 1);
        d.scene.remembered_camera_height = kHeight;
        stage.run(d.scene, r);
        if (r.detected && r.floor_remembered && origin_error(r, d.truth) < 0.03f && r.level_data[1].index == 2 &&
            std::fabs(r.level_data[1].height - 2.f * s.riser) < 0.01f)
          ++hidden_placed;
      }
    }
  }
  std::printf("remembered floor: first edge within 3 cm in %d of %d views (worst %.2f cm); floor seen as a level %d of "
              "%d; tread 1 hidden %d of %d\n",
              placed, views, 100.f * worst, floor_placed, views, hidden_placed, views / 2);
  EXPECT_EQ(placed, views);
  EXPECT_EQ(floor_placed, views);
  EXPECT_EQ(hidden_placed, views / 2);
}

TEST(StairsFloorless, StackOffTheRememberedFeetIsNoStaircase) {
  // The same staircase with a remembered height that puts its first level half a riser from the
  // feet, or with more steps out of view than may be hidden: no staircase (an index would be a
  // guess).
  const PipelineConfig cfg = on();
  StairStage stage(cfg);
  StairSpec s;
  s.steps = 6;
  s.distance = 1.2f;
  {
    SceneBuilder b(1.4f, 45.f, 41);
    b.add_stairs(s);
    drop_floor(b.scene);
    b.scene.remembered_camera_height = 1.4f + 0.5f * s.riser;
    StairResult r;
    stage.run(b.scene, r);
    EXPECT_FALSE(r.detected);
    EXPECT_EQ(r.verdict, StairVerdict::kNoFirstStep);
    EXPECT_TRUE(stage.floorless_trace().anchored);
  }
  {
    SceneBuilder b(1.4f, 45.f, 42);
    b.add_stairs(s);
    drop_floor(b.scene);
    drop_first_treads(b.scene, 2);  // treads 1 and 2 out of view: tread 3 is the first seen
    b.scene.remembered_camera_height = 1.4f;
    StairResult r;
    stage.run(b.scene, r);
    EXPECT_FALSE(r.detected);
    EXPECT_EQ(stage.floorless_trace().first_index, -1);
  }
}

// End to end on the synthetic world: the walk up to the first step of the default climb, every
// frame through perception (it tracks and remembers the floor as in use). In the last half metre
// the floor leaves the view; perception remembers the camera height and the floorless route places
// the steps from the feet.
TEST(StairsFloorless, ArrivalAtTheFootOfAClimb) {
  const PipelineConfig cfg = on();
  Perception perception(cfg);
  StairStage stage(cfg);
  SceneResult scene;
  StairResult r;
  RgbdFrame frame;
  FrameTruth truth;
  int floorless = 0, expected = 0, tp = 0, off_edge = 0, wrong_direction = 0, remembered = 0;
  for (long i = 0; i <= 212; ++i) {
    synth::render_preset_frame("ascending_approach_climb", i, 5u, synth::SynthOptions{}, frame, truth);
    perception.process(frame, scene);
    stage.run(scene, frame.intrinsics, r);
    if (scene.floor_found) continue;
    const StairFrameEval e = evaluate_stair_frame(r, truth);
    if (e.outcome == EvalOutcome::kSkipped) continue;  // on the first step: traversal's
    ++floorless;
    remembered += r.detected && r.floor_remembered;
    expected += e.outcome == EvalOutcome::kTP || e.outcome == EvalOutcome::kFN;
    tp += e.outcome == EvalOutcome::kTP;
    off_edge += e.false_positive;
    wrong_direction += e.wrong_direction;
    if (e.outcome != EvalOutcome::kTP)
      std::printf("frame %ld: %s, %s (levels %d, first index %d, first level %.3f m from the feet)\n", i,
                  to_string(e.outcome), to_string(r.verdict), r.levels, stage.floorless_trace().first_index,
                  stage.floorless_trace().first_offset);
  }
  std::printf("arrival without floor: %d frames, %d expected, %d found (%d from the remembered floor), %d off the "
              "edge, %d wrong direction\n",
              floorless, expected, tp, remembered, off_edge, wrong_direction);
  ASSERT_GE(floorless, 60) << "the walk should lose the floor before the first step";
  EXPECT_EQ(off_edge, 0) << "a staircase placed off its first edge";
  EXPECT_EQ(wrong_direction, 0);
  EXPECT_EQ(remembered, tp) << "every detection here comes from the remembered floor";
  EXPECT_GE(tp, 0.85 * expected);
}

TEST(StairsFloorless, OffByConfig) {
  PipelineConfig cfg;
  cfg.stair_detection.floorless = false;
  StairStage stage(cfg);
  SceneBuilder b(1.4f, 45.f, 31);
  StairSpec s;
  b.add_stairs(s);
  drop_floor(b.scene);
  StairResult r;
  stage.run(b.scene, r);
  EXPECT_FALSE(r.detected);
  EXPECT_EQ(r.verdict, StairVerdict::kNoFloor);
  EXPECT_FALSE(r.without_floor);
}

}  // namespace
