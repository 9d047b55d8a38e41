// Stair detection and modelling (paper section 4) on hand-built perception results: staircases of
// known dimensions sampled with depth noise, tables, shelves, boxes, curbs.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <tuple>

#include "stairguide/capture/dataset.hpp"
#include "stairguide/capture/frame_source.hpp"
#include "stairguide/config/config_loader.hpp"
#include "stairguide/stairs/stair_checks.hpp"
#include "stairguide/eval/stair_eval.hpp"
#include "stairguide/stairs/stairs.hpp"
#include "test_stairs_scene.hpp"

namespace {

using namespace stairguide;
using sgtest::SceneBuilder;
using sgtest::StairSpec;

PipelineConfig cfg() { return PipelineConfig{}; }

float yaw_error_deg(const Pose& a, const Pose& b) {
  const float c = std::clamp(a.linear().col(2).dot(b.linear().col(2)), -1.f, 1.f);
  return rad2deg(std::acos(c));
}

struct Errors {
  float riser, tread, width, origin, yaw;
};

Errors errors(const StairResult& r, const StairTruth& t) {
  return {std::fabs(r.riser_m - t.riser_m), std::fabs(r.tread_m - t.tread_m),
          std::fabs(r.width_m - t.width_m),
          (r.T_camera_stair.translation() - t.T_camera_stair.translation()).norm(),
          yaw_error_deg(r.T_camera_stair, t.T_camera_stair)};
}

TEST(StairsUnit, AscendingStaircaseMeasured) {
  SceneBuilder b(1.3f, 45.f, 7);
  StairSpec s;
  s.direction = 1;
  s.steps = 5;
  s.yaw_deg = 12.f;
  s.lateral = 0.2f;
  b.add_stairs(s);
  StairStage stage(cfg());
  StairResult r;
  stage.run(b.scene, r);
  ASSERT_TRUE(r.detected) << to_string(r.verdict);
  EXPECT_EQ(r.kind, StairKind::kAscending);
  EXPECT_EQ(r.levels, 5);
  EXPECT_EQ(r.method, StairAxesMethod::kPca);
  const Errors e = errors(r, b.truth);
  EXPECT_LT(e.riser, 0.005f);
  EXPECT_LT(e.tread, 0.01f);
  EXPECT_LT(e.width, 0.03f);
  EXPECT_LT(e.origin, 0.02f);
  EXPECT_LT(e.yaw, 1.0f);
  // The two ends of the first edge are a width apart, along x_S, around the origin.
  EXPECT_NEAR((r.edge_left - r.edge_right).norm(), r.width_m, 1e-4f);
  EXPECT_GT((r.edge_left - r.origin()).dot(r.T_camera_stair.linear().col(0)), 0.f);
  ASSERT_EQ(r.level_data.size(), 6u);
  for (int k = 1; k <= 5; ++k) {
    EXPECT_NEAR(r.level_data[k].height, 0.17f * k, 0.01f) << k;
    EXPECT_FALSE(r.level_data[k].points.empty());
  }
}

TEST(StairsUnit, DescendingStaircaseMeasured) {
  SceneBuilder b(1.45f, 50.f, 11);
  StairSpec s;
  s.direction = -1;
  s.steps = 6;
  s.riser = 0.16f;
  s.tread = 0.31f;
  s.width = 1.0f;
  s.distance = 1.3f;
  s.yaw_deg = -15.f;
  b.add_stairs(s);
  StairStage stage(cfg());
  StairResult r;
  stage.run(b.scene, r);
  ASSERT_TRUE(r.detected) << to_string(r.verdict);
  EXPECT_EQ(r.kind, StairKind::kDescending);
  EXPECT_EQ(r.levels, 6);
  const Errors e = errors(r, b.truth);
  EXPECT_LT(e.riser, 0.005f);
  EXPECT_LT(e.tread, 0.01f);
  EXPECT_LT(e.width, 0.03f);
  EXPECT_LT(e.origin, 0.02f);
  EXPECT_LT(e.yaw, 1.0f);
  EXPECT_LT(r.level_data[3].height, -0.4f);
}

TEST(StairsUnit, TableAloneIsNoStaircase) {
  SceneBuilder b(1.4f, 40.f, 3);
  b.add_floor();
  b.add_box_top(0.2f, 2.0f, 1.2f, 0.8f, 0.75f, RegionClass::kStepCandidate);
  StairStage stage(cfg());
  StairResult r;
  stage.run(b.scene, r);
  EXPECT_FALSE(r.detected);
  EXPECT_EQ(r.verdict, StairVerdict::kNoFirstStep);
  EXPECT_EQ(r.candidates, 1);
  EXPECT_EQ(r.rejected_candidates, 1);
}

TEST(StairsUnit, TableBesideStaircaseIsLeftOut) {
  SceneBuilder b(1.3f, 45.f, 5);
  StairSpec s;
  s.steps = 5;
  s.yaw_deg = 0.f;
  b.add_stairs(s);
  // A table top at 75 cm right beside the staircase (its near corner 30 cm from the 4th tread).
  b.add_box_top(-1.2f, 2.3f, 0.8f, 0.8f, 0.75f, RegionClass::kStepCandidate);
  StairStage stage(cfg());
  StairResult r;
  stage.run(b.scene, r);
  ASSERT_TRUE(r.detected) << to_string(r.verdict);
  EXPECT_EQ(r.levels, 5);
  EXPECT_EQ(r.rejected_candidates, 1);
  EXPECT_LT(errors(r, b.truth).width, 0.03f);
}

TEST(StairsUnit, OccludedLevelIsFusedFromTwoRegions) {
  SceneBuilder b(1.3f, 45.f, 9);
  StairSpec s;
  s.steps = 5;
  b.add_stairs(s, /*split_level=*/2);
  StairStage stage(cfg());
  StairResult r;
  stage.run(b.scene, r);
  ASSERT_TRUE(r.detected) << to_string(r.verdict);
  EXPECT_EQ(r.levels, 5);
  EXPECT_EQ(r.level_data[2].regions.size(), 2u);
  EXPECT_LT(errors(r, b.truth).tread, 0.01f);
}

TEST(StairsUnit, BoardsStackedStraightUpCannotHoldAFoot) {
  SceneBuilder b(1.4f, 40.f, 4);
  b.add_floor();
  // Boards 17 cm apart stacked straight up: connected and at riser heights, but each edge right
  // above the one below: no going to put a foot on (physical evidence, not a building code).
  for (int k = 1; k <= 4; ++k)
    b.add_box_top(0.f, 1.8f, 1.0f, 0.35f, 0.17f * static_cast<float>(k), RegionClass::kStepCandidate);
  StairStage stage(cfg());
  StairResult r;
  stage.run(b.scene, r);
  EXPECT_FALSE(r.detected);
  EXPECT_EQ(r.levels, 4);
  EXPECT_EQ(r.verdict, StairVerdict::kTreadTooShort);
}

TEST(StairsUnit, BuildingCodesDescribeRisersAndNeverSilenceThem) {
  // Issue 39: a building code describes what was found; it never silences a staircase. 23.5 cm
  // risers are over the world's 22 cm, 19.5 cm over the paper's Spanish 18.5 cm
  // (config/profiles/paper.yaml): both are told, and described as steep.
  const PipelineConfig paper =
      load_config(std::string(STAIRGUIDE_SOURCE_DIR) + "/config/profiles/paper.yaml");
  for (const auto& [riser, config, over_code] : {std::tuple<float, PipelineConfig, bool>{0.235f, cfg(), true},
                                                 {0.195f, paper, true},
                                                 {0.195f, cfg(), false}}) {
    SceneBuilder b(1.4f, 45.f, 2);
    StairSpec s;
    s.riser = riser;
    s.steps = 4;
    b.add_stairs(s);
    StairStage stage(config);
    StairResult r;
    stage.run(b.scene, r);
    ASSERT_TRUE(r.detected) << riser << ": " << to_string(r.verdict) << ", " << r.levels << " levels, riser "
                            << r.riser_m;
    EXPECT_NEAR(r.riser_m, riser, 0.01f);
    EXPECT_EQ((r.code_notes & kCodeHighRisers) != 0, over_code)
        << riser << ": " << code_notes_text(r.code_notes);
  }
}

TEST(StairsUnit, WalkableLimitsArePhysical) {
  StairDimensions d;
  d.riser = 0.17f;
  d.tread = 0.28f;
  d.tread_known = true;
  d.width = 1.0f;
  d.width_complete = true;
  d.range = 2.f;
  EXPECT_EQ(check_walkable(d, 0.01f, 0.004f), StairVerdict::kDetected);
  d.riser = 0.085f;  // a low training stair, 2R+T = 45 cm: under every code, walked every day
  d.tread = 0.28f;
  EXPECT_EQ(check_walkable(d, 0.01f, 0.004f), StairVerdict::kDetected);
  StairModellingConfig code;
  EXPECT_NE(describe_against_code(d, true, code) & kCodeLowRisers, 0u);
  EXPECT_NE(describe_against_code(d, true, code) & kCodeBlondelLow, 0u);
  d.riser = 0.30f;  // a ledge, not a step
  EXPECT_EQ(check_walkable(d, 0.01f, 0.004f), StairVerdict::kRiserOutOfRange);
  d.riser = 0.17f;
  d.tread = 0.10f;  // no room for a foot
  EXPECT_EQ(check_walkable(d, 0.01f, 0.004f), StairVerdict::kTreadTooShort);
  d.tread = 0.22f;  // a steep cellar stair: under the code, still walked
  EXPECT_EQ(check_walkable(d, 0.01f, 0.004f), StairVerdict::kDetected);
  d.width = 0.3f;
  EXPECT_EQ(check_walkable(d, 0.01f, 0.004f), StairVerdict::kTooNarrow);
  d.width_complete = false;  // cut by the view: only a lower bound, 30 cm asked of it
  EXPECT_EQ(check_walkable(d, 0.01f, 0.004f), StairVerdict::kDetected);
  d.width = 0.25f;  // a shelf's strip cut by the view (held-out shelves seed 1 #0)
  EXPECT_EQ(check_walkable(d, 0.01f, 0.004f), StairVerdict::kTooNarrow);
  d.width = 0.35f;
  d.tread = 0.55f;  // a garden flight's long goings
  EXPECT_EQ(check_walkable(d, 0.01f, 0.004f), StairVerdict::kDetected);
  d.tread = 1.10f;  // two steps a platform apart: no flight
  EXPECT_EQ(check_walkable(d, 0.01f, 0.004f), StairVerdict::kTreadTooLong);
  EXPECT_EQ(code_notes_text(0), "within code");
}

TEST(StairsUnit, SingleStepCurbAndObstacle) {
  StairStage stage(cfg());
  StairResult r;
  {  // a platform 16 cm high, 1.4 m wide, 1.5 m deep: a single step
    SceneBuilder b(1.3f, 45.f, 12);
    b.add_floor(1.5f);
    b.add_box_top(0.1f, 2.25f, 1.4f, 1.5f, 0.16f, RegionClass::kStepCandidate);
    stage.run(b.scene, r);
    ASSERT_TRUE(r.detected) << to_string(r.verdict);
    EXPECT_EQ(r.kind, StairKind::kSingleStep);
    EXPECT_EQ(r.levels, 1);
    EXPECT_NEAR(r.riser_m, 0.16f, 0.005f);
    // Edge nearest the user at z = 1.5 m in the floor frame, height 16 cm.
    const Eigen::Vector3f o = b.scene.T_floor_camera * r.origin();
    EXPECT_NEAR(o.z(), 1.5f, 0.02f);
    EXPECT_NEAR(o.y(), 0.16f, 0.01f);
  }
  {  // a box top at step height, 35 x 30 cm: an obstacle
    SceneBuilder b(1.3f, 45.f, 13);
    b.add_floor();
    b.add_box_top(0.1f, 1.8f, 0.35f, 0.3f, 0.16f, RegionClass::kStepCandidate);
    stage.run(b.scene, r);
    EXPECT_FALSE(r.detected);
    EXPECT_EQ(r.verdict, StairVerdict::kObstacle);
  }
  {  // the ground steps down 14 cm to a large lower level: a curb
    SceneBuilder b(1.5f, 40.f, 14);
    StairSpec s;
    s.direction = -1;
    s.steps = 1;
    s.riser = 0.14f;
    s.tread = 3.0f;
    s.width = 4.0f;
    s.yaw_deg = 5.f;
    b.add_stairs(s);
    stage.run(b.scene, r);
    ASSERT_TRUE(r.detected) << to_string(r.verdict);
    EXPECT_EQ(r.kind, StairKind::kCurb);
    EXPECT_NEAR(r.riser_m, 0.14f, 0.005f);
    EXPECT_LT((r.origin() - b.truth.T_camera_stair.translation()).norm(), 0.03f);
  }
  {  // a raised level 12 cm up, deeper than any step platform: a curb (up); 12 cm is below H_min
    SceneBuilder b(1.3f, 45.f, 15);
    b.add_floor(1.4f);
    b.add_box_top(0.f, 1.4f + 1.6f, 4.0f, 3.2f, 0.12f, RegionClass::kObstacle);
    stage.run(b.scene, r);
    ASSERT_TRUE(r.detected) << to_string(r.verdict);
    EXPECT_EQ(r.kind, StairKind::kCurb);
  }
}

TEST(StairsUnit, FarDropSeenOnlyPastTheFloorEdge) {
  // Far away, a descending flight shows only the strip of its first tread that lies past the
  // shadow of the floor's edge (D * R / H beyond it): a drop however shallow the strip. The same
  // strip well past that shadow is no drop seen over the edge, and stays an obstacle.
  StairStage stage(cfg());
  StairResult r;
  const float H = 1.3f, R = 0.17f, D = 1.5f, shadow = D * R / H;
  {
    SceneBuilder b(H, 45.f, 21);
    b.add_floor(D);
    b.add_box_top(0.f, D + shadow + 0.015f, 1.2f, 0.03f, -R, RegionClass::kStepCandidate);
    stage.run(b.scene, r);
    ASSERT_TRUE(r.detected) << to_string(r.verdict);
    EXPECT_EQ(r.kind, StairKind::kCurb);  // one level below: a drop (curb or flight, cannot tell)
    EXPECT_NEAR(r.riser_m, R, 0.01f);
    const Eigen::Vector3f o = b.scene.T_floor_camera * r.origin();
    EXPECT_NEAR(o.z(), D, 0.03f);
  }
  {
    SceneBuilder b(H, 45.f, 22);
    b.add_floor(D);
    b.add_box_top(0.f, D + shadow + 0.17f, 1.2f, 0.03f, -R, RegionClass::kStepCandidate);
    stage.run(b.scene, r);
    EXPECT_FALSE(r.detected);
    EXPECT_EQ(r.verdict, StairVerdict::kObstacle);
  }
}

TEST(StairsUnit, NoFloorNoStairs) {
  SceneBuilder b(1.3f, 45.f, 1);
  StairSpec s;
  b.add_stairs(s);
  b.scene.floor_found = false;
  // With the floorless route off, no floor means no heights and no staircase.
  PipelineConfig c = cfg();
  c.stair_detection.floorless = false;
  StairStage stage(c);
  StairResult r;
  stage.run(b.scene, r);
  EXPECT_FALSE(r.detected);
  EXPECT_EQ(r.verdict, StairVerdict::kNoFloor);
  // With it on, the stack of treads is found without a floor and says so
  // (tests/test_stairs_floorless.cpp holds the figures).
  c.stair_detection.floorless = true;
  StairStage floorless(c);
  floorless.run(b.scene, r);
  EXPECT_TRUE(r.detected) << to_string(r.verdict);
  EXPECT_TRUE(r.without_floor);
}

TEST(StairsUnit, FirstStepMustTouchTheFloor) {
  SceneBuilder b(1.3f, 45.f, 6);
  b.add_floor(1.2f);
  // Two boards at step heights 2 m beyond the end of the floor: not connected to it.
  b.add_box_top(0.f, 3.5f, 1.0f, 0.3f, 0.17f, RegionClass::kStepCandidate);
  b.add_box_top(0.f, 3.8f, 1.0f, 0.3f, 0.34f, RegionClass::kStepCandidate);
  StairStage stage(cfg());
  StairResult r;
  stage.run(b.scene, r);
  EXPECT_FALSE(r.detected);
  EXPECT_EQ(r.verdict, StairVerdict::kNoFirstStep);
}

// ---- the top of a descent: floor only beside the stairwell, first treads under the view ----

/// Drops every point below the image row y/z = v_max (the bottom of a camera's view), refits the
/// regions' centroids and offsets, and removes regions left with too few points.
void cut_view(SceneResult& scene, float v_max) {
  std::vector<PlaneRegion> kept;
  int floor_region = -1;
  for (std::size_t i = 0; i < scene.regions.size(); ++i) {
    PlaneRegion r = scene.regions[i];
    r.points.erase(std::remove_if(r.points.begin(), r.points.end(),
                                  [&](const Eigen::Vector3f& p) { return p.y() / p.z() > v_max; }),
                   r.points.end());
    if (r.points.size() < 10) continue;
    Eigen::Vector3f c = Eigen::Vector3f::Zero();
    for (const auto& p : r.points) c += p;
    r.centroid = c / static_cast<float>(r.points.size());
    r.pixel_count = static_cast<int>(r.points.size());
    r.offset = -r.normal.dot(r.centroid);
    if (static_cast<int>(i) == scene.floor_region) floor_region = static_cast<int>(kept.size());
    kept.push_back(std::move(r));
  }
  scene.regions = std::move(kept);
  scene.floor_region = floor_region;
}

/// Moves a region down by `drop` (m) along the floor's up.
void lower_region(SceneResult& scene, PlaneRegion& r, float drop) {
  const Eigen::Vector3f up = scene.T_floor_camera.linear().row(1).transpose();
  for (auto& p : r.points) p -= up * drop;
  r.centroid -= up * drop;
  r.offset = -r.normal.dot(r.centroid);
  r.height -= drop;
}

/// An ascending flight whose only floor in view lies beside it, `gap` (m) sideways from its side
/// (a person or a wall end hides the floor in front of the first step).
SceneBuilder flight_beside_floor(float gap, unsigned seed) {
  SceneBuilder b(1.3f, 45.f, seed);
  StairSpec s;
  s.steps = 4;
  s.width = 1.0f;
  s.distance = 1.2f;
  s.yaw_deg = 0.f;
  b.add_stairs(s);
  b.scene.regions.erase(b.scene.regions.begin() + b.scene.floor_region);
  b.add_box_top(0.5f + gap + 0.5f, 1.5f, 1.0f, 2.0f, 0.f, RegionClass::kFloor);
  b.scene.floor_region = static_cast<int>(b.scene.regions.size()) - 1;
  return b;
}

TEST(StairsUnit, AFlightBesideTheFloorIsFoundByItsStack) {
  StairStage stage(cfg());
  StairResult r;
  {
    // 0.6 m sideways: beyond the connection radius, but the levels stand one and two risers above
    // the floor with one riser between them.
    SceneBuilder b = flight_beside_floor(0.6f, 21);
    stage.run(b.scene, r);
    ASSERT_TRUE(r.detected) << to_string(r.verdict);
    EXPECT_EQ(r.kind, StairKind::kAscending);
    EXPECT_EQ(r.level_data[1].index, 1);
    EXPECT_NEAR(r.level_data[1].height, 0.17f, 0.01f);
    EXPECT_LT(errors(r, b.truth).riser, 0.005f);
  }
  {
    // The same stack raised by half a riser: its first level is no step above the floor.
    SceneBuilder b = flight_beside_floor(0.6f, 22);
    for (auto& reg : b.scene.regions)
      if (reg.cls == RegionClass::kStepCandidate) lower_region(b.scene, reg, -0.085f);
    stage.run(b.scene, r);
    EXPECT_FALSE(r.detected);
  }
  {
    // 1.5 m sideways: too far from the floor to say it stands on it.
    SceneBuilder b = flight_beside_floor(1.5f, 23);
    stage.run(b.scene, r);
    EXPECT_FALSE(r.detected);
    EXPECT_EQ(r.verdict, StairVerdict::kNoFirstStep);
  }
}

/// A descending flight straight ahead whose first edge lies `distance` in front of the camera's
/// foot, the floor in front of it and the floor beside the stairwell (1.2 m on each side), seen by
/// a 1.3 m high camera tilted 45 deg with a 45 deg vertical field of view: the view starts 0.54 m
/// in front of the feet on the floor, deeper on the treads.
SceneBuilder top_of_descent(float distance, unsigned seed) {
  SceneBuilder b(1.3f, 45.f, seed);
  StairSpec s;
  s.direction = -1;
  s.steps = 6;
  s.riser = 0.17f;
  s.tread = 0.29f;
  s.width = 1.2f;
  s.distance = distance;
  s.yaw_deg = 0.f;
  b.add_stairs(s);
  const int front = b.scene.floor_region;
  b.add_box_top(1.2f, distance + 1.5f, 1.2f, 3.0f, 0.f, RegionClass::kFloor);
  b.add_box_top(-1.2f, distance + 1.5f, 1.2f, 3.0f, 0.f, RegionClass::kFloor);
  b.scene.floor_region = front;
  cut_view(b.scene, std::tan(deg2rad(22.5f)));
  // The floor in front of the edge may be out of view: the floor is then the one beside.
  if (b.scene.floor_region < 0)
    for (std::size_t i = 0; i < b.scene.regions.size(); ++i)
      if (b.scene.regions[i].cls == RegionClass::kFloor) b.scene.floor_region = static_cast<int>(i);
  return b;
}

int count_class(const SceneResult& scene, RegionClass c, float below = 0.f) {
  int n = 0;
  for (const auto& r : scene.regions) n += r.cls == c && r.height < below ? 1 : 0;
  return n;
}

TEST(StairsUnit, TrackedFloorIsNotDoubtedAtTheTopOfADescent) {
  // 0.45 m from the edge: the floor in front of it is under the view, the first tread is in view
  // and nearer the user than the floor beside the stairwell.
  SceneBuilder b = top_of_descent(0.45f, 41);
  ASSERT_EQ(count_class(b.scene, RegionClass::kFloor, 1.f), 2) << "only the floor beside is in view";
  StairStage stage(cfg());
  StairResult r;
  // Not tracked: the nearer lower level makes the floor doubtful (it may be a tread or a board),
  // so no height is measured from it; the treads' own vertical still tells the descent at the
  // user's feet (issue 39: a doubtful floor silenced staircases), going down.
  b.scene.floor_tracked = false;
  stage.run(b.scene, r);
  ASSERT_TRUE(r.detected) << to_string(r.verdict);
  EXPECT_EQ(r.direction(), -1);
  EXPECT_NEAR(r.riser_m, b.truth.riser_m, 0.01f);
  // Tracked (perception kept it from the frames before, the camera still at its height): the
  // staircase is reported, its first edge where it is.
  b.scene.floor_tracked = true;
  stage.run(b.scene, r);
  ASSERT_TRUE(r.detected) << to_string(r.verdict);
  EXPECT_EQ(r.kind, StairKind::kDescending);
  EXPECT_EQ(r.level_data[1].index, -1);
  const Errors e = errors(r, b.truth);
  EXPECT_LT(e.riser, 0.005f);
  EXPECT_LT(e.tread, 0.01f);
  EXPECT_LT(e.origin, 0.03f);
  EXPECT_LT(e.yaw, 1.0f);
}

TEST(StairsUnit, HiddenFirstStepsAtTheEdgeOfADescent) {
  // 0.2 m from the edge: the first tread lies wholly under the view, the second is cut by its
  // bottom. The stack seen starts two risers down.
  SceneBuilder b = top_of_descent(0.2f, 42);
  float top = -1e9f;
  for (const auto& r : b.scene.regions)
    if (r.cls == RegionClass::kStepCandidate) top = std::max(top, r.height);
  ASSERT_NEAR(top, -0.34f, 0.01f) << "the first tread must be out of view";
  StairStage stage(cfg());
  StairResult r;
  b.scene.floor_tracked = true;
  stage.run(b.scene, r);
  ASSERT_TRUE(r.detected) << to_string(r.verdict);
  EXPECT_EQ(r.kind, StairKind::kDescending);
  EXPECT_EQ(stage.detection().descending.hidden_steps, 1);
  EXPECT_EQ(r.level_data[1].index, -2);
  EXPECT_NEAR(r.level_data[1].height, -0.34f, 0.01f);
  const Errors e = errors(r, b.truth);
  EXPECT_LT(e.riser, 0.005f);
  EXPECT_LT(e.tread, 0.01f);
  // The first edge (the floor's, out of view) is extrapolated from the steps seen.
  EXPECT_LT(e.origin, 0.03f);
  EXPECT_LT(e.yaw, 1.0f);

  // Without tracking the floor's height is not trusted that far, but the stack of treads going
  // down is seen: a descent is told (never a climb).
  b.scene.floor_tracked = false;
  stage.run(b.scene, r);
  EXPECT_TRUE(!r.detected || r.direction() == -1) << to_string(r.kind);

  // Still deeper under the view (two treads hidden): found as well.
  SceneBuilder c = top_of_descent(-0.05f, 43);
  c.scene.floor_tracked = true;
  stage.run(c.scene, r);
  ASSERT_TRUE(r.detected) << to_string(r.verdict);
  EXPECT_EQ(r.level_data[1].index, -3);
  EXPECT_LT(errors(r, c.truth).origin, 0.03f);
}

TEST(StairsUnit, HiddenFirstStepsNeedAWholeNumberOfRisersAndTheViewBottom) {
  StairStage stage(cfg());
  StairResult r;
  {
    // The stack lowered by half a riser: its first level is 2.5 risers down, no step of it.
    SceneBuilder b = top_of_descent(0.2f, 44);
    b.scene.floor_tracked = true;
    for (auto& reg : b.scene.regions)
      if (reg.cls == RegionClass::kStepCandidate) lower_region(b.scene, reg, 0.085f);
    stage.run(b.scene, r);
    EXPECT_FALSE(r.detected);
    EXPECT_EQ(r.verdict, StairVerdict::kNoFirstStep);
  }
  {
    // The first tread missing from the middle of the view (not hidden under its bottom): the
    // level seen first does not reach the bottom of the view, so it is not taken as the second.
    SceneBuilder b = top_of_descent(0.9f, 45);
    b.scene.floor_tracked = true;
    int first = -1;
    for (std::size_t i = 0; i < b.scene.regions.size(); ++i)
      if (b.scene.regions[i].cls == RegionClass::kStepCandidate &&
          std::fabs(b.scene.regions[i].height + 0.17f) < 0.02f)
        first = static_cast<int>(i);
    ASSERT_GE(first, 0);
    b.scene.regions[static_cast<std::size_t>(first)].cls = RegionClass::kObstacle;
    b.scene.regions[static_cast<std::size_t>(first)].normal = Eigen::Vector3f::UnitZ();  // not horizontal
    stage.run(b.scene, r);
    EXPECT_FALSE(r.detected);
    EXPECT_EQ(r.verdict, StairVerdict::kNoFirstStep);
  }
}

TEST(StairsUnit, ManhattanAxesUsedOnlyWhenTheyAgree) {
  StairStage stage(cfg());
  StairResult r;
  StairSpec s;
  s.yaw_deg = 20.f;
  {
    SceneBuilder b(1.3f, 45.f, 21);
    b.add_stairs(s);
    b.set_manhattan(20.5f);  // walls along the staircase, half a degree off
    stage.run(b.scene, r);
    ASSERT_TRUE(r.detected);
    EXPECT_EQ(r.method, StairAxesMethod::kManhattan);
    EXPECT_NEAR(yaw_error_deg(r.T_camera_stair, b.truth.T_camera_stair), 0.5f, 0.2f);
  }
  {
    SceneBuilder b(1.3f, 45.f, 22);
    b.add_stairs(s);
    b.set_manhattan(-5.f);  // staircase rotated 25 degrees against the room
    stage.run(b.scene, r);
    ASSERT_TRUE(r.detected);
    EXPECT_EQ(r.method, StairAxesMethod::kPca);
    EXPECT_LT(yaw_error_deg(r.T_camera_stair, b.truth.T_camera_stair), 1.0f);
  }
  {
    SceneBuilder b(1.3f, 45.f, 23);
    b.add_stairs(s);
    b.set_manhattan(20.f, 0.02f);  // too little Manhattan evidence
    stage.run(b.scene, r);
    EXPECT_EQ(r.method, StairAxesMethod::kPca);
  }
}

TEST(StairsUnit, RepeatedRunsGiveTheSameResult) {
  SceneBuilder b(1.3f, 45.f, 31);
  StairSpec s;
  b.add_stairs(s);
  StairStage stage(cfg());
  StairResult r1, r2;
  stage.run(b.scene, r1);
  SceneBuilder other(1.5f, 35.f, 32);
  other.add_floor();
  stage.run(other.scene, r2);  // a different frame in between
  stage.run(b.scene, r2);
  EXPECT_EQ(r1.detected, r2.detected);
  EXPECT_EQ(r1.levels, r2.levels);
  EXPECT_FLOAT_EQ(r1.riser_m, r2.riser_m);
  EXPECT_FLOAT_EQ(r1.tread_m, r2.tread_m);
  EXPECT_TRUE(r1.T_camera_stair.isApprox(r2.T_camera_stair));
}

TEST(StairsUnit, AccuracyOverManyRandomStaircases) {
  // 60 random staircases, both directions: dimension errors well inside the figures.
  std::mt19937 rng(77);
  std::uniform_real_distribution<float> U(0.f, 1.f);
  StairStage stage(cfg());
  StairResult r;
  int detected = 0, total = 0;
  double riser = 0, tread = 0, origin = 0, yaw = 0;
  for (int i = 0; i < 60; ++i) {
    SceneBuilder b(1.0f + 0.6f * U(rng), 30.f + 30.f * U(rng), 100 + i);
    StairSpec s;
    s.direction = (i % 2) ? 1 : -1;
    s.steps = 4 + static_cast<int>(U(rng) * 6);
    s.riser = 0.15f + 0.03f * U(rng);
    s.tread = 0.28f + 0.04f * U(rng);
    s.width = 0.9f + 0.7f * U(rng);
    s.distance = 1.0f + 1.5f * U(rng);
    s.yaw_deg = -25.f + 50.f * U(rng);
    s.lateral = -0.3f + 0.6f * U(rng);
    b.add_stairs(s);
    // Far descending treads can hide behind their nosings entirely (fewer than 10 points).
    if (b.truth.visible_steps.size() < 2) continue;
    stage.run(b.scene, r);
    ++total;
    if (!r.detected) {
      ADD_FAILURE() << "staircase " << i << " not detected: " << to_string(r.verdict);
      continue;
    }
    ++detected;
    const Errors e = errors(r, b.truth);
    riser += e.riser;
    tread += e.tread;
    origin += e.origin;
    yaw += e.yaw;
  }
  ASSERT_EQ(detected, total);
  EXPECT_GE(total, 50);
  EXPECT_LT(riser / detected, 0.005);
  EXPECT_LT(tread / detected, 0.008);
  EXPECT_LT(origin / detected, 0.02);
  EXPECT_LT(yaw / detected, 1.0);
}

// ---- evaluation: which way a curb goes, and the kind as the user needs it ----

/// A frame whose one stair (kind, direction) has its first edge 1.5 m ahead, one tread in view.
FrameTruth one_level_truth(StairKind kind, bool down) {
  FrameTruth f;
  f.scene = "unit";
  f.camera_height_m = 1.3f;
  StairTruth s;
  s.kind = kind;
  s.down = down;
  s.steps = kind == StairKind::kAscending || kind == StairKind::kDescending ? 5 : 1;
  s.riser_m = 0.15f;
  s.tread_m = 0.3f;
  s.width_m = 1.2f;
  s.T_camera_stair = Pose::Identity();
  s.T_camera_stair.translation() = Eigen::Vector3f(0.f, 1.2f, 1.5f);
  s.visible_steps = kind == StairKind::kAscending || kind == StairKind::kDescending
                        ? std::vector<int>{1, 2, 3}
                        : std::vector<int>{1};
  s.visible_pixels.assign(s.visible_steps.size(), 1000);
  s.first_edge_visible = s.both_ends_visible = true;
  f.stairs.push_back(s);
  return f;
}

/// A detection at the truth's edge: `kind` with one level at `height` (signed) above the floor.
StairResult one_level_result(const FrameTruth& f, StairKind kind, float height) {
  StairResult r;
  r.detected = true;
  r.verdict = StairVerdict::kDetected;
  r.kind = kind;
  r.levels = 1;
  r.riser_m = std::fabs(height);
  r.width_m = 1.2f;
  r.T_camera_stair = f.stairs[0].T_camera_stair;
  r.level_data.resize(2);
  r.level_data[1].index = height > 0.f ? 1 : -1;
  r.level_data[1].height = height;
  return r;
}

TEST(StairsEval, ResultSaysWhichWayACurbGoes) {
  const FrameTruth f = one_level_truth(StairKind::kCurb, true);
  EXPECT_EQ(one_level_result(f, StairKind::kCurb, -0.15f).direction(), -1);
  EXPECT_EQ(one_level_result(f, StairKind::kCurb, 0.15f).direction(), 1);
  EXPECT_EQ(one_level_result(f, StairKind::kSingleStep, 0.15f).direction(), 1);
  EXPECT_EQ(one_level_result(f, StairKind::kDescending, -0.15f).direction(), -1);
  EXPECT_EQ(StairResult{}.direction(), 0);
}

TEST(StairsEval, CurbInTheWrongDirectionIsWrong) {
  const FrameTruth down = one_level_truth(StairKind::kCurb, true);
  // A curb down reported as a curb up at the very same edge: a miss and a false detection.
  const StairFrameEval wrong = evaluate_stair_frame(one_level_result(down, StairKind::kCurb, 0.15f), down);
  EXPECT_EQ(wrong.outcome, EvalOutcome::kFN);
  EXPECT_TRUE(wrong.false_positive);
  EXPECT_TRUE(wrong.wrong_direction);
  EXPECT_STREQ(wrong.truth_label(), "curb_down");
  EXPECT_STREQ(wrong.predicted_label(), "curb_up");
  // ... and as a single step (up): the same.
  EXPECT_TRUE(
      evaluate_stair_frame(one_level_result(down, StairKind::kSingleStep, 0.15f), down).wrong_direction);
  // The right way: a TP of exactly the right kind.
  const StairFrameEval right = evaluate_stair_frame(one_level_result(down, StairKind::kCurb, -0.15f), down);
  EXPECT_EQ(right.outcome, EvalOutcome::kTP);
  EXPECT_FALSE(right.wrong_direction);
  EXPECT_TRUE(right.kind_exact());
  EXPECT_TRUE(right.kind_ok());
  // A curb up reported going down is as wrong.
  const FrameTruth up = one_level_truth(StairKind::kCurb, false);
  const StairFrameEval e = evaluate_stair_frame(one_level_result(up, StairKind::kCurb, -0.15f), up);
  EXPECT_EQ(e.outcome, EvalOutcome::kFN);
  EXPECT_TRUE(e.wrong_direction);

  StairEvalTable table;
  table.add(wrong, "unit");
  table.add(right, "unit");
  EXPECT_EQ(table.all.wrong_direction, 1);
  EXPECT_EQ(table.all.fp, 1);
  EXPECT_EQ(table.all.tp, 1);
  EXPECT_EQ(table.all.confusion.at("curb_down").at("curb_up"), 1);
  EXPECT_EQ(table.all.confusion.at("curb_down").at("curb_down"), 1);
  EXPECT_NE(table.to_json().find("\"wrong_direction\": 1"), std::string::npos) << table.to_json();
}

TEST(StairsEval, SingleStepAsCurbUpIsRightForTheUserButNotExact) {
  const FrameTruth f = one_level_truth(StairKind::kSingleStep, false);
  const StairFrameEval e = evaluate_stair_frame(one_level_result(f, StairKind::kCurb, 0.16f), f);
  EXPECT_EQ(e.outcome, EvalOutcome::kTP);
  EXPECT_TRUE(e.kind_ok());      // one step up, at the right edge
  EXPECT_FALSE(e.kind_exact());  // but not the kind the truth has
  // A descending flight reported as a single curb down goes the right way but miscounts.
  // (`down` is a curb's label: a descending truth goes down whatever it holds.)
  const FrameTruth d = one_level_truth(StairKind::kDescending, false);
  const StairFrameEval c = evaluate_stair_frame(one_level_result(d, StairKind::kCurb, -0.15f), d);
  EXPECT_EQ(c.outcome, EvalOutcome::kTP);
  EXPECT_FALSE(c.kind_ok());

  StairEvalTable table;
  table.add(e, "unit");
  table.add(c, "unit");
  EXPECT_EQ(table.all.tp, 2);
  EXPECT_EQ(table.all.kind_correct, 0);
  EXPECT_EQ(table.all.kind_ok, 1);
  EXPECT_EQ(table.all.confusion.at("single_step").at("curb_up"), 1);
  EXPECT_EQ(table.all.confusion.at("descending").at("curb_down"), 1);
  const std::string json = table.to_json();
  EXPECT_NE(
      json.find("\"confusion\": {\"descending\": {\"curb_down\": 1}, \"single_step\": {\"curb_up\": 1}}"),
      std::string::npos)
      << json;
  EXPECT_NE(table.to_text().find("kind confusion"), std::string::npos);
}

TEST(StairsEval, LabelsCarryTheCurbDirection) {
  FrameTruth f = one_level_truth(StairKind::kCurb, true);
  const std::string dir = std::string(STAIRGUIDE_BINARY_DIR) + "/test_stairs_labels";
  std::filesystem::create_directories(dir);
  const std::string path = dir + "/labels.yaml";
  auto write = [&](const std::string& text) { std::ofstream(path) << text; };
  write(labels_to_yaml({f}));
  const auto back = read_labels_yaml(path);
  ASSERT_EQ(back.size(), 1u);
  ASSERT_EQ(back[0].stairs.size(), 1u);
  EXPECT_TRUE(back[0].stairs[0].down);
  f.stairs[0].down = false;
  write(labels_to_yaml({f}));
  EXPECT_FALSE(read_labels_yaml(path)[0].stairs[0].down);

  // A curb without a direction is refused, naming the file and the line; a descending one
  // without the key goes down; a contradiction is refused.
  std::string text = labels_to_yaml({f});
  const std::string key = "        down: false\n";
  const auto at = text.find(key);
  ASSERT_NE(at, std::string::npos);
  write(std::string(text).erase(at, key.size()));
  try {
    read_labels_yaml(path);
    ADD_FAILURE() << "a curb without 'down' was accepted";
  } catch (const SourceError& e) {
    EXPECT_NE(std::string(e.what()).find("labels.yaml:"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("down"), std::string::npos) << e.what();
  }
  f.stairs[0].kind = StairKind::kDescending;  // its `down` left false: the writer writes the kind's
  text = labels_to_yaml({f});
  const std::string key_down = "        down: true\n";
  const auto at_down = text.find(key_down);
  ASSERT_NE(at_down, std::string::npos) << text;
  write(std::string(text).erase(at_down, key_down.size()));
  EXPECT_TRUE(read_labels_yaml(path)[0].stairs[0].down);
  write(std::string(text).replace(at_down, key_down.size(), key));  // descending with down: false
  EXPECT_THROW(read_labels_yaml(path), SourceError);
  std::filesystem::remove_all(dir);
}

}  // namespace
