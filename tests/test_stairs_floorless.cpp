// The floorless route (stairs/floorless.hpp): staircases found when perception saw no floor, on
// hand-built perception results (test_stairs_scene.hpp) with the floor taken out of view.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "stairguide/synth/synth.hpp"
#include "stairguide/perception/perception.hpp"
#include "stairguide/eval/stair_eval.hpp"
#include "stairguide/stairs/stairs.hpp"
#include "synth_stairs_test_util.hpp"
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

/// Perception and the stair stage as in use, on one synthetic view at a time taken cold (nothing
/// remembered from a view before).
struct ColdRun {
  PipelineConfig cfg = on();
  Perception perception{cfg};
  StairStage stage{cfg};
  SceneResult scene;
  StairResult r;
  RgbdFrame frame;
  FrameTruth truth;
  void view(const char* preset, long index, unsigned seed) {
    synth::render_preset_frame(preset, index, seed, synth::SynthOptions{}, frame, truth);
    perception.reset();
    perception.process(frame, scene);
    stage.run(scene, frame.intrinsics, r);
  }
};

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
    std::printf(
        "%-34s frames %3d detected %3d wrong direction %d; riser |err| mean %.2f max %.2f cm; tread (%d) "
        "|err| mean %.2f max %.2f cm\n",
        what, frames, detected, wrong_direction, detected ? 100.0 * riser_abs / detected : 0.0,
        100.0 * riser_max, with_tread, with_tread ? 100.0 * tread_abs / with_tread : 0.0, 100.0 * tread_max);
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
            std::printf(
                "miss: dir %d tilt %.0f yaw %.0f dist %.1f: %s (levels %d, stacked %d, direction %d)\n", dir,
                tilt, yaw, dist, to_string(r.verdict), r.levels, stage.floorless_trace().stacked,
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
  const float yaw = rad2deg(std::acos(
      std::clamp(r.T_camera_stair.linear().col(2).dot(b.truth.T_camera_stair.linear().col(2)), -1.f, 1.f)));
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
    for (int k = 0; k < 4; ++k)
      b.add_box_top(0.f, 1.6f, 1.0f, 0.35f, 0.3f + 0.17f * static_cast<float>(k),
                    RegionClass::kStepCandidate);
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
          ADD_FAILURE() << "dir " << dir << " tilt " << tilt << " yaw " << yaw << ": "
                        << to_string(r.verdict);
        }
        // (b) the floor seen as a level (the floor detector refused it): it is level 0.
        SceneBuilder c(kHeight, tilt, seed++);
        c.add_stairs(s);
        c.scene.floor_found = false;
        c.scene.remembered_camera_height = kHeight;
        stage.run(c.scene, r);
        if (r.detected && r.floor_remembered && origin_error(r, c.truth) < 0.03f &&
            r.level_data[1].index == dir)
          ++floor_placed;
        if (dir < 0) continue;
        // (c) tread 1 out of view too (under the camera): placed one tread before tread 2.
        SceneBuilder d(kHeight, tilt, seed++);
        d.add_stairs(s);
        drop_floor(d.scene);
        drop_first_treads(d.scene, 1);
        d.scene.remembered_camera_height = kHeight;
        stage.run(d.scene, r);
        if (r.detected && r.floor_remembered && origin_error(r, d.truth) < 0.03f &&
            r.level_data[1].index == 2 && std::fabs(r.level_data[1].height - 2.f * s.riser) < 0.01f)
          ++hidden_placed;
      }
    }
  }
  std::printf(
      "remembered floor: first edge within 3 cm in %d of %d views (worst %.2f cm); floor seen as a level %d "
      "of "
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
  sgtest::SynthStairs p(on());
  const SceneResult& scene = p.scene;
  const FrameTruth& truth = p.truth;
  int floorless = 0, expected = 0, tp = 0, off_edge = 0, wrong_direction = 0, remembered = 0;
  for (long i = 0; i <= 212; ++i) {
    const StairResult& r = p.step("ascending_approach_climb", i, 5u);
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
                  to_string(e.outcome), to_string(r.verdict), r.levels, p.stage.floorless_trace().first_index,
                  p.stage.floorless_trace().first_offset);
  }
  std::printf(
      "arrival without floor: %d frames, %d expected, %d found (%d from the remembered floor), %d off the "
      "edge, %d wrong direction\n",
      floorless, expected, tp, remembered, off_edge, wrong_direction);
  ASSERT_GE(floorless, 60) << "the walk should lose the floor before the first step";
  EXPECT_EQ(off_edge, 0) << "a staircase placed off its first edge";
  EXPECT_EQ(wrong_direction, 0);
  EXPECT_EQ(remembered, tp) << "every detection here comes from the remembered floor";
  EXPECT_GE(tp, 0.85 * expected);
}

// Cold views (nothing remembered: the wearer just switched the aid on) where the floor detector
// refused the floor strip at the foot of the steps because it might be a first tread. A strip
// seen deeper than the flight's own tread (plus the measuring slack) is no tread of that flight:
// it is the floor, and the staircase is placed from it. Over every view of the two approach walks
// taken cold, nothing may be placed off its true first edge or the wrong way (a first tread cut
// by the border is no deeper than a tread, so it is never taken for the floor).
bool result_direction_ok(const StairResult& r, const StairTruth& t) {
  return (r.direction() < 0) == t.goes_down();
}

/// Distance, m, from a result's origin to the nearest true step edge line of `t` (edge 1 is the
/// truth's origin; edge k lies k - 1 treads on and k - 1 risers up, or down descending), and that
/// edge's number in `k`.
float nearest_edge(const StairResult& r, const StairTruth& t, int& k) {
  const Eigen::Vector3f o = r.T_camera_stair.translation(), x = t.T_camera_stair.linear().col(0);
  const float up = t.goes_down() ? -1.f : 1.f;
  float best = 1e9f;
  k = 0;
  for (int e = 1; e <= std::max(1, t.steps); ++e) {
    const Eigen::Vector3f edge =
        t.T_camera_stair * Eigen::Vector3f(0.f, up * static_cast<float>(e - 1) * t.riser_m,
                                           static_cast<float>(e - 1) * t.tread_m);
    const Eigen::Vector3f d = o - edge;
    const float dist = (d - x * x.dot(d)).norm();
    if (dist < best) {
      best = dist;
      k = e;
    }
  }
  return best;
}

// Cold views (nothing remembered: the wearer just switched the aid on) near the first edge, where
// perception refused the floor: the floor strip at the foot of a climb may be a first tread, and
// at the top of a descent the treads below look nearer the user's feet than the floor.
//  - A floor strip seen deeper than the flight's own tread (plus the measuring slack) is no tread
//    of that flight: it is the floor, and the staircase is placed from it (the two seed-5 static
//    views of the suite where this was the miss).
//  - A floor level in view outside the stack, a chest camera's height below and a whole number of
//    risers from the first seen level, places the steps from the feet (the top of a descent whose
//    first treads are self-occluded), and so does the floor around a stairwell that topped the
//    stack (its near boundary farther than the first tread's below it): 4 placed views before
//    that rule, 8 with it.
//  - Anything else is reported `without_floor` (first step and distance unknown): its origin must
//    still lie on one of the flight's true edges, going the right way.
// Every view of the two approach walks is taken cold; a detection with the distance known must be
// on the true first edge.
TEST(StairsFloorless, ColdViewsNearTheFirstEdge) {
  ColdRun c;
  const SceneResult& scene = c.scene;
  const StairResult& r = c.r;
  const FrameTruth& truth = c.truth;
  const StairStage& stage = c.stage;
  const std::pair<const char*, long> views[] = {{"nosing_landing_static", 9}, {"ascending_short_static", 4}};
  for (const auto& [preset, index] : views) {
    c.view(preset, index, 5u);
    const StairFrameEval e = evaluate_stair_frame(r, truth);
    EXPECT_EQ(e.outcome, EvalOutcome::kTP) << preset << " " << index << ": " << to_string(r.verdict);
    // Perception now tells nosing #9's strip from a tread itself (deeper than the treads ahead,
    // FloorConfig::floor_deeper_than_tread): the floor it finds must be the real one. The short
    // flight's strip (no two treads ahead to compare) is still refused there and placed here.
    if (scene.floor_found) {
      EXPECT_STREQ(preset, "nosing_landing_static") << "the case is the floor refused by perception";
      EXPECT_NEAR(scene.camera_height, truth.camera_height_m, 0.02f) << preset;
    } else {
      EXPECT_TRUE(stage.floorless_trace().floor_level) << preset;
    }
  }
  int cold = 0, placed = 0, placed_from_floor = 0, unplaced = 0, off_edge = 0, wrong_direction = 0;
  for (const char* walk : {"ascending_approach_climb", "descending_approach_descend"}) {
    for (long i = 0; i <= 240; i += 3) {
      c.view(walk, i, 5u);
      if (scene.floor_found) continue;
      const StairFrameEval e = evaluate_stair_frame(r, truth);
      if (e.outcome == EvalOutcome::kSkipped) continue;  // on the stairs: traversal's
      ++cold;
      wrong_direction += e.wrong_direction;
      if (!r.detected || truth.stairs.empty()) continue;
      int k = 0;
      const float d = nearest_edge(r, truth.stairs.front(), k);
      bool ok = true;
      if (r.without_floor) {
        ++unplaced;
        ok = d < 0.1f && result_direction_ok(r, truth.stairs.front());
      } else {
        ++placed;
        placed_from_floor += stage.floorless_trace().floor_seen || stage.floorless_trace().floor_level;
        ok = e.outcome == EvalOutcome::kTP && !e.false_positive;
      }
      if (!ok) {
        ++off_edge;
        std::printf("%s %ld: %s, nearest true edge %d at %.2f m (levels %d, distance %s)\n", walk, i,
                    to_string(e.outcome), k, d, r.levels, r.without_floor ? "unknown" : "known");
      }
    }
  }
  std::printf(
      "cold views without floor: %d; placed from the feet %d (%d from a floor level seen), first step "
      "unknown %d; "
      "off every true edge %d, wrong direction %d\n",
      cold, placed, placed_from_floor, unplaced, off_edge, wrong_direction);
  ASSERT_GE(cold, 10) << "the walks should lose the floor near the first edge";
  EXPECT_EQ(off_edge, 0) << "a staircase placed off its edges";
  EXPECT_EQ(wrong_direction, 0);
  EXPECT_GE(placed_from_floor, 7);
}

// Two levels seen cold (nothing remembered, no floor level in view) going down, with an upright
// face between their heights: the riser faces the user, the step rises away from them, and the
// one pair's direction (where the levels come nearest the user) followed where the view's border
// cuts an oblique edge. Held-out seed 1 curb #4, a curb going up seen at 21 deg with the sidewalk
// filling the view and the street in a corner, was reported as stairs going down. A two-step
// flight going up, floor out of view, is still reported (the real stair frames are such views).
TEST(StairsFloorless, TwoLevelsGoingDownWithARiserFacingTheUserAreRefused) {
  ColdRun c;
  const StairResult& r = c.r;
  const FloorlessTrace& trace = c.stage.floorless_trace();
  // A curb going up seen as two levels whose near distances read down, the floor refused
  // (curb_static seed 1 #4: perception refused its strip of floor until the floor detector learned
  // to keep a strip at the rig's height; the refusal is now made here, the planes left as seen).
  c.view("curb_static", 4, 1u);
  c.scene.floor_found = false;
  c.scene.floor_region = -1;
  c.scene.T_floor_camera = Pose::Identity();
  c.scene.camera_height = 0.f;
  c.stage.run(c.scene, c.frame.intrinsics, c.r);
  ASSERT_FALSE(c.truth.stairs.empty());
  ASSERT_FALSE(c.truth.stairs.front().goes_down()) << "a curb going up";
  EXPECT_EQ(trace.stacked, 2);
  EXPECT_EQ(trace.direction, -1) << "the pair's near distances say down: the test does not test";
  // What matters to the wearer: the curb going up is not told as a descent. (With the planes of the
  // merged floor detector this view is refused before the riser test: riser_against no longer
  // fires on it, and the synthetic pairs below test the positive side only.)
  EXPECT_FALSE(r.detected) << to_string(r.kind) << ", " << r.levels << " levels";
  std::printf("curb seed 1 #4, floor refused: %s (riser against: %d)\n", to_string(r.verdict),
              trace.riser_against);

  for (int dir : {1, -1}) {
    SceneBuilder b(1.4f, 45.f, 41);
    StairSpec s;
    s.steps = 2;
    s.direction = dir;
    s.distance = dir > 0 ? 0.9f : 0.4f;
    b.add_stairs(s);
    drop_floor(b.scene);
    c.stage.run(b.scene, c.r);
    EXPECT_FALSE(trace.riser_against) << dir;
    EXPECT_TRUE(r.detected) << dir << ": " << to_string(r.verdict) << ", stacked " << trace.stacked;
    EXPECT_EQ(r.kind, dir > 0 ? StairKind::kAscending : StairKind::kDescending) << to_string(r.kind);
  }
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

// Going up with the tread unknown (one step edge seen), a level below the top one, seen whole,
// whose mean depth is less than a foot's holds no foot: a bed frame's rim 3-5 cm wide round the
// mattress, 22 cm up, and the mattress 43 cm up were a two-level flight placed from the remembered
// camera height once perception doubted its floor (world2_bed seed 1003 #8). The flights of the
// tests above (first levels cut by the view or whole treads) are still told.
TEST(StairsFloorless, ARimRoundAMattressHoldsNoFoot) {
  sgtest::SynthStairs p;
  ASSERT_TRUE(stairguide::synth::sensor_options("real-v1", p.options));
  int told = 0;
  for (long i = 0; i < 24; ++i) {
    const StairResult& r = p.step("world2_bed_static", i, 1003, /*cold=*/true);
    if (i == 8) {
      EXPECT_FALSE(r.detected) << to_string(r.verdict);
      EXPECT_GE(r.levels, 2);  // the stack was seen and modelled, and refused
    }
    told += r.detected;
  }
  EXPECT_EQ(told, 0);
}
