// The first edge of a staircase reached in a walk (stairs/floorless.hpp, "lean"): the frames
// where the user stands at the top of a descent or at the foot of a climb, feet still on the
// floor, as the chest starts moving towards the first step. Each walk runs through perception
// frame after frame as in use (it tracks the floor and remembers the camera height); only the
// frames around the edge are scored.
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

/// A hand-built view (test_stairs_scene.hpp) without the floor and with the first `hidden` treads
/// out of view, from a camera `lean` m nearer the flight's levels than the remembered height
/// says (up a climb, down a descent), the first edge `distance` m ahead of the camera's vertical.
StairResult lean_view(StairStage& stage, int direction, float distance, float lean, int hidden, unsigned seed,
                      StairTruth& truth) {
  constexpr float kRemembered = 1.30f;
  StairSpec s;
  s.direction = direction;
  s.distance = distance;
  SceneBuilder b(kRemembered + static_cast<float>(direction) * lean, 45.f, seed);
  b.add_stairs(s);
  SceneResult& scene = b.scene;
  if (scene.floor_region >= 0) scene.regions.erase(scene.regions.begin() + scene.floor_region);
  scene.floor_region = -1;
  scene.floor_found = false;
  scene.T_floor_camera = Pose::Identity();
  scene.camera_height = 0.f;
  for (int i = 0; i < hidden && !scene.regions.empty(); ++i) scene.regions.erase(scene.regions.begin());
  scene.remembered_camera_height = kRemembered;
  StairResult r;
  stage.run(scene, r);
  truth = b.truth;
  return r;
}

// The lean on its own: a camera 6 cm nearer the flight than remembered (more than the 4 cm anchor
// tolerance) with the first edge at its vertical is a user at the edge: placed from the feet, the
// first edge where it is. The same climb 1.2 m away is not (refused, as before the lean).
TEST(StairsEdge, LeanOnlyAtTheEdge) {
  const PipelineConfig cfg;
  StairStage stage(cfg);
  StairTruth t;
  for (int dir : {1, -1}) {
    // Ascending: tread 1 under the camera, tread 2 seen first. Descending: the floor's edge and
    // tread 1 under the camera's vertical.
    const int hidden = dir > 0 ? 1 : 0;
    const StairResult r =
        lean_view(stage, dir, -0.05f, 0.06f, hidden, 71u + static_cast<unsigned>(dir + 1), t);
    ASSERT_TRUE(r.detected) << "dir " << dir << ": " << to_string(r.verdict);
    EXPECT_TRUE(r.floor_remembered);
    EXPECT_EQ(r.direction(), dir);
    EXPECT_NEAR(stage.floorless_trace().lean, 0.06f, 0.015f) << "dir " << dir;
    EXPECT_LT((r.T_camera_stair.translation() - t.T_camera_stair.translation()).norm(), 0.03f)
        << "dir " << dir;
    ASSERT_GT(r.level_data.size(), 1u);
    EXPECT_NEAR(std::fabs(r.level_data[1].height),
                static_cast<float>(std::abs(r.level_data[1].index)) * 0.17f, 0.02f);
    EXPECT_EQ(std::abs(r.level_data[1].index), 1 + hidden);
    std::printf("dir %+d: lean %.3f m, first edge %.3f m ahead, origin error %.2f cm\n", dir,
                stage.floorless_trace().lean, stage.floorless_trace().lean_edge_ahead,
                100.f * (r.T_camera_stair.translation() - t.T_camera_stair.translation()).norm());

    if (dir < 0) continue;  // the hand-built descent farther out shows too little for a stack
    const StairResult far = lean_view(stage, dir, 1.2f, 0.06f, hidden, 81u, t);
    const FloorlessTrace& ft = stage.floorless_trace();
    std::printf("lean 6 cm with the first edge 1.2 m ahead: %s (stacked %d, lean %.3f m, first index %d)\n",
                to_string(far.verdict), ft.stacked, ft.lean, ft.first_index);
    EXPECT_FALSE(far.detected) << "a lean a metre before the edge";
    EXPECT_EQ(far.verdict, StairVerdict::kNoFirstStep);
    EXPECT_GT(ft.lean, 0.f) << "refused by the edge check, not before it";
    EXPECT_EQ(ft.first_index, -1);
  }
}

struct EdgeFigures {
  int scored = 0, tp = 0, lean = 0, wrong_direction = 0, false_positive = 0, wrong_index = 0;
  float worst_origin = 0.f, worst_riser = 0.f, worst_tread = 0.f;
};

/// Runs `walk` (seed `seed`) through perception from its first frame to `end`, every `stride`-th
/// frame before `from` (perception tracks the floor and verifies the camera height on those) and
/// every frame after, and scores the frames from `from` on with the user still on the floor before
/// the flight (truth user_step 0) and the flight expected. Every frame from `from` on, on the flight or not,
/// must not go the wrong way or off the flight.
EdgeFigures run_edge(const char* walk, unsigned seed, long stride, long from, long end) {
  sgtest::SynthStairs p;
  const SceneResult& scene = p.scene;
  const FrameTruth& truth = p.truth;
  EdgeFigures f;
  for (long i = 0; i <= end; i += i < from ? stride : 1) {
    const StairResult& r = p.step(walk, i, seed);
    if (i < from) continue;
    const StairFrameEval e = evaluate_stair_frame(r, truth);
    f.wrong_direction += e.wrong_direction;
    f.false_positive += e.false_positive;
    if (truth.stairs.empty() || truth.stairs[0].user_step != 0) continue;
    if (e.outcome != EvalOutcome::kTP && e.outcome != EvalOutcome::kFN) continue;
    ++f.scored;
    if (e.outcome != EvalOutcome::kTP) {
      std::printf("%s seed %u frame %ld: %s (%s, floor %s, remembered %.3f m)\n", walk, seed, i,
                  to_string(e.outcome), to_string(r.verdict), scene.floor_found ? "found" : "not found",
                  scene.remembered_camera_height);
      continue;
    }
    ++f.tp;
    f.lean += p.stage.floorless_trace().lean > 0.f && !scene.floor_found;
    const StairTruth& t = truth.stairs[0];
    // The first edge (origin of S: the floor's edge descending, the first nosing ascending), where
    // it lies even out of view; riser, tread, and the first seen level's step number.
    f.worst_origin =
        std::max(f.worst_origin, (r.T_camera_stair.translation() - t.T_camera_stair.translation()).norm());
    f.worst_riser = std::max(f.worst_riser, std::fabs(r.riser_m - t.riser_m));
    f.worst_tread = std::max(f.worst_tread, std::fabs(r.tread_m - t.tread_m));
    // The nearest seen level's step number (steps before it out of view) must agree with its
    // height: k risers from the floor the user stands on.
    if (r.level_data.size() > 1) {
      const StairLevel& l = r.level_data[1];
      if (std::fabs(std::fabs(l.height) - static_cast<float>(std::abs(l.index)) * t.riser_m) > 0.03f)
        ++f.wrong_index;
    }
  }
  std::printf(
      "%s seed %u frames %ld-%ld: %d on the floor at the edge, %d found (%d by the lean), first edge "
      "within %.2f cm, riser %.2f cm, tread %.2f cm; %d wrong step number, %d wrong way, %d off the flight\n",
      walk, seed, from, end, f.scored, f.tp, f.lean, 100.f * f.worst_origin, 100.f * f.worst_riser,
      100.f * f.worst_tread, f.wrong_index, f.wrong_direction, f.false_positive);
  return f;
}

/// The staircase found at the edge is where it is (first edge within 3 cm, riser 1 cm, tread 2 cm,
/// the first seen level's step number right) and nothing goes the wrong way or off the flight.
void expect_placed_right(const EdgeFigures& f) {
  EXPECT_LE(f.worst_origin, 0.03f);
  EXPECT_LE(f.worst_riser, 0.01f);
  EXPECT_LE(f.worst_tread, 0.02f);
  EXPECT_EQ(f.wrong_index, 0);
  EXPECT_EQ(f.wrong_direction, 0);
  EXPECT_EQ(f.false_positive, 0);
}

// Before the lean, every approach walk lost the staircase for 5-8 frames here: the camera had
// moved 4-9 cm towards the first step (half a riser by the time the feet reach the edge), more
// than the 4 cm perception keeps a tracked floor by and the floorless route places a first level
// from the remembered camera height by. Seed 3 of both walks: 8 and 6 frames lost.
TEST(StairsEdge, TopOfADescent) {
  const EdgeFigures f = run_edge("descending_approach_descend", 3u, 4, 196, 222);
  ASSERT_GE(f.scored, 8) << "the walk should reach the edge with the feet on the floor";
  EXPECT_EQ(f.tp, f.scored) << "a descending staircase lost at its top edge";
  EXPECT_GE(f.lean, 5) << "the frames at the edge go through the lean";
  expect_placed_right(f);
}

TEST(StairsEdge, FootOfAClimb) {
  const EdgeFigures f = run_edge("ascending_approach_climb", 3u, 4, 196, 222);
  ASSERT_GE(f.scored, 8) << "the walk should reach the edge with the feet on the floor";
  // One miss is older and not the edge's: frame 202, where the last sliver of tread 1 at the
  // bottom of the view lies farther out than tread 2's near boundary and the floorless direction
  // vote refuses the stack (in the held-out sweep's baseline too).
  EXPECT_GE(f.tp, f.scored - 1) << "an ascending staircase lost at its foot";
  EXPECT_GE(f.lean, 4) << "the frames at the edge go through the lean";
  expect_placed_right(f);
}

}  // namespace
