// Stair detection and modelling (paper section 4) on hand-built perception results: staircases of
// known dimensions sampled with depth noise, tables, shelves, boxes, curbs.
#include <gtest/gtest.h>

#include <cmath>

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
  return {std::fabs(r.riser_m - t.riser_m), std::fabs(r.tread_m - t.tread_m), std::fabs(r.width_m - t.width_m),
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

TEST(StairsUnit, ShelvesAreRejectedByTheBuildingCode) {
  SceneBuilder b(1.4f, 40.f, 4);
  b.add_floor();
  // Boards 17 cm apart stacked straight up: connected and at riser heights, but no tread.
  for (int k = 1; k <= 4; ++k)
    b.add_box_top(0.f, 1.8f, 1.0f, 0.35f, 0.17f * static_cast<float>(k), RegionClass::kStepCandidate);
  StairStage stage(cfg());
  StairResult r;
  stage.run(b.scene, r);
  EXPECT_FALSE(r.detected);
  EXPECT_EQ(r.levels, 4);
  EXPECT_EQ(r.verdict, StairVerdict::kTreadTooShort);
}

TEST(StairsUnit, RisersTooHighAreRejected) {
  SceneBuilder b(1.4f, 45.f, 2);
  StairSpec s;
  s.riser = 0.195f;  // within H_max + slack for detection, above the code for modelling
  s.steps = 4;
  b.add_stairs(s);
  StairStage stage(cfg());
  StairResult r;
  stage.run(b.scene, r);
  EXPECT_FALSE(r.detected);
  EXPECT_EQ(r.verdict, StairVerdict::kRiserOutOfRange);
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
  StairStage stage(cfg());
  StairResult r;
  stage.run(b.scene, r);
  EXPECT_FALSE(r.detected);
  EXPECT_EQ(r.verdict, StairVerdict::kNoFloor);
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

}  // namespace
