// End to end, drop-offs (issue 42 item 4): stairguided replaying a walk towards a platform edge
// says "drop ahead" before the edge, heard through an ALSA file PCM (found in the captured
// samples by correlation with the WAV) and felt on the buzzer (gpio_chip "file:PATH"); a
// stair-free walk says nothing of drops.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "feedback_test_util.hpp"
#include "stairguide/synth/synth.hpp"

namespace fs = std::filesystem;

namespace {

const fs::path kDir = fs::path(STAIRGUIDE_BINARY_DIR) / "e2e_feedback_drops_files";

sgtest::DaemonRun run_daemon(const std::string& name, const std::string& replay) {
  return sgtest::run_daemon(kDir, name, replay, "--fast --sync");
}

}  // namespace

TEST(E2eFeedbackDrops, WalkTowardsAPlatformEdgeSaysDropAheadBeforeTheEdge) {
  const std::string preset = "drop_platform_walk";
  const std::uint32_t seed = 7;
  const sgtest::DaemonRun r =
      run_daemon("e2e_drop_walk", "synth:" + preset + ":460:" + std::to_string(seed) + ":real-v1");
  ASSERT_EQ(r.code, 0) << r.log;
  std::vector<std::pair<double, std::string>> drops;
  int beeps = 0;
  for (const auto& [t, tok] : r.told) {
    if (tok.rfind("drop_ahead", 0) == 0) drops.push_back({t, tok});
    if (tok.rfind("approach", 0) == 0) ++beeps;
    EXPECT_EQ(tok.find("stairs_ahead"), std::string::npos) << tok;  // a platform edge is no staircase
  }
  // Told once on the way; again only after it was forgotten (unseen forget_time: standing at the
  // edge with only a strip of floor in view, then turning along it, it may come back).
  ASSERT_GE(drops.size(), 1u) << r.log;
  if (drops.size() > 1) {
    EXPECT_GT(drops[1].first - drops[0].first, 3.0);
  }
  // Told with its distance, before the wearer reaches the edge: the truth of that frame says how
  // far the edge still was.
  stairguide::RgbdFrame f;
  stairguide::FrameTruth truth;
  stairguide::synth::SynthOptions o;
  ASSERT_TRUE(stairguide::synth::sensor_options("real-v1", o));
  stairguide::synth::render_preset_frame(preset, std::lround(drops[0].first * 30.0), seed, o, f, truth);
  std::printf("told %s at %.2f s, the edge %.2f m away (truth); %d approach beeps after it\n",
              drops[0].second.c_str(), drops[0].first, truth.drop_distance_m, beeps);
  EXPECT_TRUE(truth.drop_in_view);
  EXPECT_GT(truth.drop_distance_m, 1.0f);
  EXPECT_LE(truth.drop_distance_m, 2.2f);
  EXPECT_GE(std::atoi(drops[0].second.c_str() + std::strlen("drop_ahead:")), 1) << drops[0].second;
  EXPECT_GE(beeps, 3);
  // Heard: the alarm and the words, in that order.
  const auto names =
      sgtest::names_of(sgtest::heard(r.audio, {"drop_ahead", "warning", "stairs_down", "stairs_up"}));
  std::printf("heard %s\n", ::testing::PrintToString(names).c_str());
  ASSERT_EQ(std::count(names.begin(), names.end(), "drop_ahead"), static_cast<long>(drops.size()))
      << ::testing::PrintToString(names);
  EXPECT_EQ(std::count(names.begin(), names.end(), "stairs_down"), 0);
  const auto warn = std::find(names.begin(), names.end(), "warning");
  EXPECT_LT(warn - names.begin(), std::find(names.begin(), names.end(), "drop_ahead") - names.begin());
  // Felt: four strong pulses of 150 ms per drop told (and the 150 ms pulse of "ready").
  int strong = 0;
  for (std::size_t i = 1; i < r.edges.size(); ++i)
    if (r.edges[i - 1].second == 1 && r.edges[i].second == 0 &&
        std::fabs(r.edges[i].first - r.edges[i - 1].first - 150.0) < 20.0)
      ++strong;
  EXPECT_EQ(strong, 4 * static_cast<int>(drops.size()) + 1);
}

TEST(E2eFeedbackDrops, StairFreeWalksSayNoDrop) {
  std::vector<std::pair<std::string, std::string>> runs = {
      {"e2e_drop_room", "synth:room_clutter_static:60:5:real-v1"},
      {"e2e_drop_corridor", "synth:corridor_static:60:5:real-v2"}};
  sgtest::add_real_kitchen(runs, "e2e_drop_kitchen");
  for (const auto& [name, replay] : runs) {
    const sgtest::DaemonRun r = run_daemon(name, replay);
    ASSERT_EQ(r.code, 0) << name << r.log;
    for (const auto& [t, tok] : r.told) {
      EXPECT_EQ(tok.rfind("drop_ahead", 0), std::string::npos) << name << " at " << t;
      EXPECT_EQ(tok.rfind("approach", 0), std::string::npos) << name << " at " << t;
    }
    EXPECT_TRUE(sgtest::heard(r.audio, {"drop_ahead", "approach"}).empty()) << name;
  }
}
