// People on and around a staircase (synthetic world, seeds other than the suite's 5): a person in
// the stairwell or a sliver at its rim must not take the first step's place, and the lower floor
// cut by the top of the view must not spoil the step edges. Regression frames from the held-out
// sweep (seed 2's walk, people_static seeds 3 and 12).
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "stairguide/synth/synth.hpp"
#include "stairguide/perception/perception.hpp"
#include "stairguide/eval/stair_eval.hpp"
#include "stairguide/stairs/stairs.hpp"
#include "synth_stairs_test_util.hpp"

namespace {

using namespace stairguide;

/// A descending flight found where it is: the right kind and direction, its first edge on the
/// true one, riser and tread as built.
void expect_descending(const StairResult& r, const FrameTruth& truth, const std::string& what) {
  const StairFrameEval e = evaluate_stair_frame(r, truth);
  EXPECT_TRUE(r.detected) << what << ": " << to_string(r.verdict) << ", " << r.levels << " levels";
  EXPECT_EQ(e.outcome, EvalOutcome::kTP) << what;
  EXPECT_FALSE(e.wrong_direction) << what;
  if (!r.detected || e.outcome != EvalOutcome::kTP) return;
  EXPECT_EQ(r.kind, StairKind::kDescending) << what;
  if (e.has_edge_line) {
    EXPECT_LT(std::fabs(e.edge_line_err), 0.05f) << what;
  }
  if (e.has_riser) {
    EXPECT_LT(std::fabs(e.riser_err), 0.01f) << what;
  }
  if (e.has_tread) {
    EXPECT_LT(std::fabs(e.tread_err), 0.02f) << what;
  }
}

using sgtest::run_view;

// Seed 2's walk stops at the top edge of a descending flight with a person standing on it; the
// first two treads are under the view. A ~200 px sliver at the stairwell's left rim, 1.27 risers
// below the floor and within the connection radius of it, was taken as the first step: the
// treads seen, three risers down, could not follow it, the hidden-first-steps route was not
// tried, and a third of the frames said "single level too small for a step" (30 of 90).
TEST(StairsPeople, DescendingWalkWithPersonOnTheFlight) {
  constexpr std::uint32_t kSeed = 2;
  constexpr long kFirstScored = 204, kLast = 239, kStride = 5;  // 14 of this stretch's 36 frames failed
  sgtest::SynthStairs p;
  const FrameTruth& truth = p.truth;
  int scored = 0, tp = 0;
  // Every frame from the start goes through perception: the floor is tracked as in use.
  for (long i = 0; i <= kLast; ++i) {
    p.perceive("descending_people_approach", i, kSeed);
    if (i < kFirstScored) continue;
    const StairResult& r = p.stairs();
    // Scored frames: a stride, plus the frames that failed before the fix.
    if ((i - kFirstScored) % kStride != 0 && i != 207 && i != 213 && i != 223 && i != 238) continue;
    ++scored;
    expect_descending(r, truth, "frame " + std::to_string(i));
    tp += r.detected && r.kind == StairKind::kDescending ? 1 : 0;
    if (r.detected) {
      // Treads 1-2 are under the view: the first seen level is step 3 and the edge is extrapolated.
      EXPECT_GE(r.levels, 5) << "frame " << i;
    }
  }
  std::printf("descending_people_approach seed 2, frames %ld-%ld: %d of %d scored frames detected\n",
              kFirstScored, kLast, tp, scored);
  EXPECT_EQ(tp, scored);
}

// A person far down a stairwell: the top of the head, 11 cm below the floor and within the
// connection radius of its rim, was taken as a curb-high first step, and the real first tread
// (17.5 cm down, 7 cm below the head) could neither join it nor start the flight.
TEST(StairsPeople, HeadInTheStairwellIsNoFirstStep) {
  StairResult r;
  FrameTruth truth;
  run_view("people_static", 3, 12, r, truth);
  expect_descending(r, truth, "people_static seed 12 view 3");
  EXPECT_GE(r.levels, 6);
}

// Seen from afar, the lower floor at the foot of a descending flight is cut by the top of the
// image to less than a landing's depth; its far boundary (the view's end) was taken for a step
// edge a tread beyond the staircase's line, and 3 edges of 5 on the line were too few.
TEST(StairsPeople, LowerFloorCutByTheViewIsNoStepEdge) {
  StairResult r;
  FrameTruth truth;
  run_view("people_static", 22, 3, r, truth);
  expect_descending(r, truth, "people_static seed 3 view 22");
  EXPECT_EQ(r.levels, 4);
}

}  // namespace
