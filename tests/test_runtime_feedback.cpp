// The daemon's feedback stage: the policy's cues come out in the decision (what the frame lines
// print), a reconfigure (SIGHUP) applies the new verbosity from the next frame, and sinks that
// cannot be had leave the decisions as they are.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>

#include "feedback_test_util.hpp"
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
  return climbing_output(static_cast<std::uint64_t>(seq), climbed);
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

namespace {
namespace fs = std::filesystem;
const fs::path kPanDir =
    fs::path(STAIRGUIDE_BINARY_DIR) / ("runtime_feedback_files." + std::to_string(getpid()));

PipelineConfig to_file_pcm(const std::string& pcm) {
  PipelineConfig c;
  c.feedback.audio_device = pcm;
  c.feedback.sounds_dir = sgtest::sounds_dir();
  c.feedback.haptic_enabled = false;
  c.feedback.volume = 1.0f;
  return c;
}

/// An ascending staircase 3 m ahead at `bearing`, seen on `frames` frames from t0: the policy
/// confirms it and the stage says "stairs ahead".
double see_stairs(FeedbackStage& stage, double t0, float bearing, int frames) {
  double t = t0;
  for (int i = 0; i < frames; ++i, t += 1.0 / 30) {
    PerceptionOutput p;
    p.seq = static_cast<std::uint64_t>(t * 30);
    p.ran = p.floor_found = true;
    p.state = "ascending";
    p.stair.detected = true;
    p.stair.kind = StairKind::kAscending;
    p.stair.direction = 1;
    p.stair.distance_m = 3.f;
    p.stair.bearing_rad = bearing;
    stage.decide(p, nullptr, t);
  }
  return t;
}
}  // namespace

// The wiring from the policy to the ear: a staircase at 3 o'clock is said at least 6 dB louder in
// the right channel of the stereo stream, one at 9 o'clock in the left (heard through a file PCM);
// with stereo_pan off the stream is mono.
TEST(RuntimeFeedback, StairsAheadArePlacedByTheirBearing) {
  sgtest::write_alsa_config(kPanDir / "asound.conf", kPanDir, {"sg_rt_right", "sg_rt_left", "sg_rt_mono"});
  setenv("ALSA_CONFIG_PATH", (kPanDir / "asound.conf").c_str(), 1);
  const auto clip = sgtest::clip("stairs_up");
  struct Case {
    const char* pcm;
    float bearing;
  };
  for (const Case& c : {Case{"sg_rt_right", static_cast<float>(M_PI / 2)},
                        Case{"sg_rt_left", static_cast<float>(-M_PI / 2)}}) {
    {
      FeedbackStage stage(to_file_pcm(c.pcm));
      see_stairs(stage, 0.0, c.bearing, 30);
      stage.drain(std::chrono::seconds(10));
    }
    const auto st = sgtest::split(sgtest::read_raw(kPanDir / (std::string(c.pcm) + ".raw")));
    const auto h = sgtest::find_all(st.mid(), "stairs_up");
    ASSERT_EQ(h.size(), 1u) << c.pcm;
    const auto from = static_cast<std::size_t>(h[0].pos), to = from + clip.size();
    const double db =
        10.0 * std::log10(sgtest::energy(st.right, from, to) / sgtest::energy(st.left, from, to));
    std::printf("%s: stairs ahead at %+.0f deg: right - left %+.1f dB\n", c.pcm, c.bearing * 57.29578, db);
    if (c.bearing > 0)
      EXPECT_GE(db, 6.0);
    else
      EXPECT_LE(db, -6.0);
  }
  PipelineConfig mono = to_file_pcm("sg_rt_mono");
  mono.feedback.stereo_pan = false;
  {
    FeedbackStage stage(mono);
    see_stairs(stage, 0.0, static_cast<float>(M_PI / 2), 30);
    stage.drain(std::chrono::seconds(10));
  }
  const auto h = sgtest::find_all(sgtest::read_raw(kPanDir / "sg_rt_mono.raw"), "stairs_up");
  ASSERT_EQ(h.size(), 1u);
  EXPECT_GT(h[0].score, 0.999);  // the clip itself, one channel
  std::error_code ec;
  if (!::testing::Test::HasFailure()) fs::remove_all(kPanDir, ec);
}

// "slow" is decided from the frames' capture-to-decision lag: frames decided 0.8 s after their
// capture for 4 s make the stage say it, once; frames on time never.
TEST(RuntimeFeedback, SlowWhenTheFramesAreDecidedLate) {
  for (const double lag : {0.8, 0.02}) {
    FeedbackStage stage(no_sinks());
    std::vector<std::string> cues;
    for (int i = 0; i < 120; ++i) {
      PerceptionOutput p;
      p.seq = static_cast<std::uint64_t>(i);
      p.ran = p.floor_found = true;
      p.state = "floor";
      const auto captured =
          std::chrono::steady_clock::now() -
          std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(lag));
      const Decision d = stage.decide(p, nullptr, i / 30.0, captured);
      if (!d.cue.empty()) cues.push_back(d.cue);
    }
    if (lag > 0.5)
      EXPECT_EQ(cues, (std::vector<std::string>{"ready", "slow"}));
    else
      EXPECT_EQ(cues, (std::vector<std::string>{"ready"}));
  }
}
