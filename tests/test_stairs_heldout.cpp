// Stair modelling on cold views from the held-out sweep (static presets, seeds 1-12, not the
// suite's 5): a shelf's bottom board seen as a strip under the image top is no single step; the
// treads of open-riser, nosed, rotated and far flights are measured as built, not short.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>

#include "stairguide/synth/synth.hpp"
#include "stairguide/perception/perception.hpp"
#include "stairguide/eval/stair_eval.hpp"
#include "stairguide/stairs/stairs.hpp"
#include "synth_stairs_test_util.hpp"

namespace {

using namespace stairguide;

using sgtest::run_view;

std::string name(const char* preset, std::uint32_t seed, long view) {
  return std::string(preset) + " seed " + std::to_string(seed) + " #" + std::to_string(view);
}

/// An ascending flight found where it is, its tread as built (within 2 cm).
void expect_ascending(const char* preset, std::uint32_t seed, long view) {
  StairResult r;
  FrameTruth truth;
  run_view(preset, view, seed, r, truth);
  const std::string what = name(preset, seed, view);
  const StairFrameEval e = evaluate_stair_frame(r, truth);
  ASSERT_TRUE(r.detected) << what << ": " << to_string(r.verdict) << ", tread " << r.tread_m << " m";
  EXPECT_EQ(e.outcome, EvalOutcome::kTP) << what;
  EXPECT_FALSE(e.wrong_direction) << what;
  EXPECT_EQ(r.kind, StairKind::kAscending) << what;
  ASSERT_TRUE(e.has_tread) << what;
  EXPECT_LT(std::fabs(e.tread_err), 0.02f) << what << ": tread " << r.tread_m << " m";
  if (e.has_riser) {
    EXPECT_LT(std::fabs(e.riser_err), 0.01f) << what;
  }
}

}  // namespace

// Far away (2.2-2.3 m), the bottom board of a shelf shows only as a strip under the image top,
// 10-18 cm high; the side panels' upper parts are out of view, so no panel was seen rising above
// the board and it was reported as a single step. The inner face of a panel at a lateral end
// (seed 2: facing the board's middle, seen below the board; seed 12: turned 37 degrees), or a
// panel's front edge rising above the board at its end (seed 11), now bounds it: furniture.
TEST(StairsHeldout, ShelfBoardUnderTheImageTopIsNoStep) {
  const struct {
    std::uint32_t seed;
    long view;
  } views[] = {{2, 20}, {11, 15}, {12, 23}};
  for (const auto& v : views) {
    StairResult r;
    FrameTruth truth;
    run_view("shelves_static", v.view, v.seed, r, truth);
    EXPECT_FALSE(r.detected) << name("shelves_static", v.seed, v.view) << ": " << to_string(r.kind) << ", "
                             << r.levels << " levels";
  }
}

// The same kind of strip that is a step platform or a curb stays one: over seeds 1-12 (even
// views, to keep the test short) every single step and curb found before the rule above is still
// found (many are far strips under the image top, 0.06-0.5 m seen, 1.9-2.9 m away), and no shelf
// board is reported as one.
TEST(StairsHeldout, StepStripsStaySteps) {
  const struct {
    const char* preset;
    int min_tp;  // found before the panel rule (and after): 118 of 144, 120 of 144
  } presets[] = {{"single_step_static", 118}, {"curb_static", 120}, {"shelves_static", 0}};
  for (const auto& p : presets) {
    int tp = 0, fp = 0, wrong_way = 0;
    for (std::uint32_t seed = 1; seed <= 12; ++seed) {
      for (long view = 0; view < 24; view += 2) {
        StairResult r;
        FrameTruth truth;
        run_view(p.preset, view, seed, r, truth);
        const StairFrameEval e = evaluate_stair_frame(r, truth);
        tp += e.outcome == EvalOutcome::kTP ? 1 : 0;
        fp += e.outcome == EvalOutcome::kFP ? 1 : 0;
        wrong_way += e.wrong_direction ? 1 : 0;
      }
    }
    std::printf("%-20s seeds 1-12, even views: TP %d FP %d wrong direction %d\n", p.preset, tp, fp,
                wrong_way);
    EXPECT_EQ(fp, 0) << p.preset;
    EXPECT_EQ(wrong_way, 0) << p.preset;
    EXPECT_GE(tp, p.min_tp) << p.preset;
  }
}

// Open risers: a handrail post or a stringer's facet at one end of the flight, upright and
// facing the user between two treads' heights, was taken for the second riser and put the
// second step's start in the middle of the first tread (treads measured 13-18 cm). A riser
// spans the staircase.
TEST(StairsHeldout, OpenRisersPostIsNoRiser) {
  expect_ascending("open_risers_static", 4, 10);
  expect_ascending("open_risers_static", 9, 18);
}

// Far flights (2.8-3.4 m): the top rows of a riser join the tread above and, moved along their
// rays onto its plane, pull its near edge 5-11 cm towards the user (nosed flight seed 6: 21.9 cm
// for 30 cm). The riser beyond that edge, where the tread below is seen to end, now places it.
TEST(StairsHeldout, FarTreadPulledByItsRiserIsPlacedByTheRiser) {
  expect_ascending("nosing_landing_static", 6, 9);
  expect_ascending("nosing_landing_static", 1, 19);
}

// A rotated flight whose last level is a piece of the landing beside it (or a big first level)
// had its axis turned round by the first-to-last centroid: treads -29 to -32 cm. Most consecutive
// levels decide the way now.
TEST(StairsHeldout, OneOddLevelDoesNotTurnTheFlightRound) {
  expect_ascending("rotated_static", 1, 16);
  expect_ascending("rotated_static", 12, 12);
}

// Walking up to a descent (held-out walk seed 2, frames 136-141, the last before the first step
// down, tracked as in use): a 180 px sliver 13 cm below the first tread lay one riser below it, as
// the whole second tread 17 cm below did; the sweep took the sliver, nearer in height, as the
// second level, and the rest of the flight, no longer a riser apart, stayed out (2 levels, a 2 m
// "tread": no stair). A much larger candidate in the same band now takes the level's place.
TEST(StairsHeldout, SliverOneRiserDownDoesNotStopTheFlight) {
  const char* walk = "descending_approach_descend";
  sgtest::SynthStairs p;
  for (long i = 120; i <= 141; ++i) {
    const StairResult& r = p.step(walk, i, 2);
    if (i < 136) continue;
    const std::string what = name(walk, 2, i);
    ASSERT_TRUE(r.detected) << what << ": " << to_string(r.verdict) << ", " << r.levels << " levels";
    const StairFrameEval e = evaluate_stair_frame(r, p.truth);
    EXPECT_EQ(e.outcome, EvalOutcome::kTP) << what;
    EXPECT_EQ(r.kind, StairKind::kDescending) << what;
    EXPECT_EQ(r.levels, 8) << what;
    ASSERT_TRUE(e.has_riser) << what;
    EXPECT_LT(std::fabs(e.riser_err), 0.01f) << what;
  }
}

// Cold views at the top of a descent (held-out seeds): perception finds no floor (the treads
// below lie nearer the feet than the floor around the stairwell), the floor under the user is out
// of view below the first edge, and the floor around the stairwell, one riser above the first
// tread seen and joined to it at the walls' feet, topped the floorless stack: one level more than
// the treads, its near boundary farther than the first tread's, so the direction was undecided
// ("step edges not evenly spaced"). It is the user's floor level, a chest camera's height below:
// out of the stack, it places the flight from the feet. Every tread counted, the first edge where
// it is built.
TEST(StairsHeldout, FloorAroundTheStairwellIsNoStep) {
  const struct {
    const char* preset;
    std::uint32_t seed;
    long view;
    int steps;  // treads seen (the truth's visible steps): 9, 11, 6 and 7 levels were stacked
  } views[] = {{"descending_static", 9, 12, 8},
               {"descending_static", 3, 8, 10},
               {"people_static", 2, 20, 5},
               {"people_static", 7, 18, 6}};
  for (const auto& v : views) {
    sgtest::SynthStairs p;
    const StairResult& r = p.step(v.preset, v.view, v.seed, /*cold=*/true);
    const std::string what = name(v.preset, v.seed, v.view);
    ASSERT_FALSE(p.scene.floor_found) << what << ": the case is the floor refused by perception";
    ASSERT_EQ(p.truth.stairs.size(), 1u) << what;
    ASSERT_TRUE(r.detected) << what << ": " << to_string(r.verdict) << ", " << r.levels << " levels";
    const StairFrameEval e = evaluate_stair_frame(r, p.truth);
    EXPECT_EQ(e.outcome, EvalOutcome::kTP) << what;
    EXPECT_EQ(r.kind, StairKind::kDescending) << what;
    EXPECT_FALSE(e.wrong_direction) << what;
    EXPECT_EQ(r.levels, v.steps) << what;
    EXPECT_EQ(static_cast<int>(p.truth.stairs.front().visible_steps.size()), v.steps) << what;
    EXPECT_TRUE(p.stage.floorless_trace().floor_beside) << what;
    EXPECT_FALSE(r.without_floor) << what << ": placed from the floor seen";
    // The first edge (the origin), along the flight and in height: its ends may be out of view.
    const Pose& Tt = p.truth.stairs.front().T_camera_stair;
    const Eigen::Vector3f d = r.T_camera_stair.translation() - Tt.translation();
    EXPECT_LT(std::fabs(Tt.linear().col(2).dot(d)), 0.03f) << what << ": first edge off along the flight";
    EXPECT_LT(std::fabs(Tt.linear().col(1).dot(d)), 0.03f) << what << ": first edge off in height";
    ASSERT_TRUE(e.has_riser) << what;
    EXPECT_LT(std::fabs(e.riser_err), 0.01f) << what;
  }
  // One pair is no evidence: at the foot of a short climb (seed 7 #20) the floor strip, seen only
  // in a corner, lies farther than the first tread, and the landing farther again; taking the
  // landing for the floor beside a stairwell reported the climb as a descent.
  sgtest::SynthStairs p;
  const StairResult& r = p.step("ascending_short_static", 20, 7, /*cold=*/true);
  const StairFrameEval e = evaluate_stair_frame(r, p.truth);
  EXPECT_FALSE(e.wrong_direction);
  EXPECT_NE(r.kind, StairKind::kDescending) << to_string(r.verdict) << ", " << r.levels << " levels";
  EXPECT_FALSE(p.stage.floorless_trace().floor_beside);
}

// An open shelf seen cold from 1.7 m (held-out seed 18): its bottom board (1.07 m long, 13 cm up),
// a box on it and a piece of the next board, 12.6 cm apart, were reported as a flight of 3 going
// up, 33.7 cm treads. Going up, a tread is never seen beyond the far side of the tread above it;
// the board runs on 0.6 m past the box on it: the box stands on the board.
TEST(StairsHeldout, BoxOnAShelfBoardIsNoFlight) {
  StairResult r;
  FrameTruth truth;
  run_view("shelves_static", 22, 18u, r, truth);
  EXPECT_FALSE(r.detected) << to_string(r.kind) << ", " << r.levels << " levels";
  EXPECT_EQ(r.verdict, StairVerdict::kStackedLevels) << to_string(r.verdict);
}

// What that leaves alone, from the views that a first, looser form of the rule lost: a region at
// the fourth level's height in front of the third tread (seed 12 rotated #12), a landing reaching
// back beside the flight (seed 1 rotated #16), a tread seen 12 cm past the next one's near edge
// (seed 11 ascending #13, its top tread cut by the view).
TEST(StairsHeldout, TreadsBesideOrUnderNoLevelAreKept) {
  expect_ascending("rotated_static", 1, 16);
  expect_ascending("rotated_static", 12, 12);
  StairResult r;
  FrameTruth truth;
  run_view("ascending_static", 13, 11u, r, truth);
  EXPECT_TRUE(r.detected) << to_string(r.verdict);
  EXPECT_EQ(evaluate_stair_frame(r, truth).outcome, EvalOutcome::kTP);
}

// A curb seen from the street at a slant (held-out seed 18): the sidewalk fills the view, its
// near boundary is the curb's edge for 24 lateral bins and a far outline at a slant for 30. The
// median of all bins put the edge 34 cm into the sidewalk and the curb was reported there; the
// largest group of bins at one depth is the edge. It must never be reported off its edge.
TEST(StairsHeldout, CurbAtASlantIsPlacedOnItsEdgeOrNotAtAll) {
  StairResult r;
  FrameTruth truth;
  run_view("curb_static", 7, 18u, r, truth);
  if (r.detected) {
    EXPECT_EQ(evaluate_stair_frame(r, truth).outcome, EvalOutcome::kTP) << "reported off the curb's edge";
  }
}
