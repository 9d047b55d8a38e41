// The daemon's feedback stage: the policy's cues come out in the decision (what the frame lines
// print), a reconfigure (SIGHUP) applies the new verbosity from the next frame, and sinks that
// cannot be had leave the decisions as they are.
#include <gtest/gtest.h>

#include "stairguide/runtime/pipeline.hpp"

using namespace stairguide;
using namespace stairguide::runtime;

namespace {

PipelineConfig no_sinks() {
  PipelineConfig c;
  c.feedback.audio_enabled = false;
  c.feedback.haptic_enabled = false;
  return c;
}

PerceptionOutput climbing(int seq, int climbed) {
  PerceptionOutput p;
  p.seq = static_cast<std::uint64_t>(seq);
  p.ran = true;
  p.floor_found = true;
  p.state = "ascending";
  p.traversal.ran = true;
  p.traversal.state = TraversalState::kOnStairs;
  p.traversal.kind = StairKind::kAscending;
  p.traversal.direction = 1;
  p.traversal.steps_climbed = p.traversal.step_index = climbed;
  return p;
}

}  // namespace

TEST(RuntimeFeedback, DecisionCarriesTheCuesAndReloadChangesVerbosity) {
  FeedbackStage stage(no_sinks());
  EXPECT_TRUE(stage.available());
  std::vector<std::string> cues;
  int frame = 0;
  auto step = [&](int climbed) {
    const Decision d = stage.decide(climbing(frame, climbed), nullptr, frame / 30.0);
    ++frame;
    if (!d.cue.empty()) cues.push_back(d.cue);
  };
  for (int climbed = 1; climbed <= 3; ++climbed)
    for (int i = 0; i < 18; ++i) step(climbed);
  // One frame's cues joined by '+', the most urgent first (the first step outranks "ready").
  EXPECT_EQ(cues, (std::vector<std::string>{"first_step+ready", "tick", "tick"}));
  PipelineConfig quiet = no_sinks();
  quiet.feedback.verbosity = "quiet";
  stage.reconfigure(quiet);
  cues.clear();
  for (int climbed = 4; climbed <= 6; ++climbed)
    for (int i = 0; i < 18; ++i) step(climbed);
  EXPECT_TRUE(cues.empty()) << ::testing::PrintToString(cues);
  const auto lat = stage.cue_latency();
  EXPECT_EQ(lat.cues, 4u);  // ready, first step, two ticks
  EXPECT_EQ(lat.sounded, 0u);
  EXPECT_EQ(lat.last, "tick");
}

TEST(RuntimeFeedback, CameraLostAndBackAreTold) {
  FeedbackStage stage(no_sinks());
  PerceptionOutput floor;
  floor.ran = floor.floor_found = true;
  floor.state = "floor";
  EXPECT_EQ(stage.decide(floor, nullptr, 0.0).cue, "ready");
  stage.camera_lost("no frame for 2 s");
  EXPECT_EQ(stage.cue_latency().last, "camera_lost");
  stage.camera_back();
  EXPECT_EQ(stage.cue_latency().last, "camera_back");
  EXPECT_EQ(stage.cue_latency().cues, 3u);
}

TEST(RuntimeFeedback, WithoutPerceptionNothingIsSaid) {
  FeedbackStage stage(no_sinks());
  PerceptionOutput p;  // ran == false: a build without perception
  p.state = "none";
  EXPECT_TRUE(stage.decide(p, nullptr, 0.0).cue.empty());
  EXPECT_EQ(stage.cue_latency().cues, 0u);
}
