// The buzzer patterns through the recording fake: every edge where the pattern puts it, within
// 5 ms; a more urgent pattern cuts one playing; the libgpiod line fails with a clear message on a
// machine without the chip.
#include <gtest/gtest.h>

#include <chrono>
#include <fstream>
#include <thread>

#include "stairguide/feedback/haptic.hpp"

using namespace stairguide::feedback;
using Clock = std::chrono::steady_clock;

namespace {

double ms(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

/// The edges a pattern should make, as (ms from the first edge, on), on then off per pulse.
std::vector<std::pair<double, bool>> expected_edges(const HapticPattern& p) {
  std::vector<std::pair<double, bool>> e;
  double t = 0;
  for (const auto& q : p) {
    e.push_back({t, true});
    t += q.on_ms;
    e.push_back({t, false});
    t += q.off_ms;
  }
  return e;
}

CueEvent ev(Cue c, int dir = 0) {
  CueEvent e;
  e.cue = c;
  e.direction = dir;
  e.priority = cue_priority(c);
  return e;
}

}  // namespace

TEST(FeedbackHaptic, PatternsEdgesWithin5ms) {
  for (const CueEvent& e :
       {ev(Cue::kStairsAhead, 1), ev(Cue::kStairsAhead, -1), ev(Cue::kTick), ev(Cue::kLastStep),
        ev(Cue::kDropWarning), ev(Cue::kBlind), ev(Cue::kEndOfStairs)}) {
    auto line = std::make_unique<RecordingLine>();
    RecordingLine* rec = line.get();
    const HapticPattern p = haptic_pattern(e);
    HapticPlayer player(std::move(line));  // owns the line: its edges are read before it goes
    player.play(p, e.priority);
    ASSERT_TRUE(player.drain(std::chrono::seconds(5)));
    const auto edges = rec->edges();
    const auto want = expected_edges(p);
    ASSERT_EQ(edges.size(), want.size()) << token(e);
    for (std::size_t i = 0; i < want.size(); ++i) {
      EXPECT_EQ(edges[i].on, want[i].second) << token(e) << " edge " << i;
      EXPECT_NEAR(ms(edges[0].t, edges[i].t), want[i].first, 5.0) << token(e) << " edge " << i;
      if (i > 0) {  // each duration too, not only the sum
        EXPECT_NEAR(ms(edges[i - 1].t, edges[i].t), want[i].first - want[i - 1].first, 5.0)
            << token(e) << " edge " << i;
      }
    }
  }
}

TEST(FeedbackHaptic, DangerCutsATickAndATickDoesNotCutDanger) {
  auto line = std::make_unique<RecordingLine>();
  RecordingLine* rec = line.get();
  const auto t0 = Clock::now();
  std::vector<RecordingLine::Edge> e;
  {
    HapticPlayer player(std::move(line));
    player.play(haptic_pattern(ev(Cue::kLastStep)), cue_priority(Cue::kTick));  // 600 ms, low priority
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    player.play(haptic_pattern(ev(Cue::kDropWarning)), cue_priority(Cue::kDropWarning));
    std::this_thread::sleep_for(std::chrono::milliseconds(150));
    player.play(haptic_pattern(ev(Cue::kTick)), cue_priority(Cue::kTick));  // dropped: danger playing
    ASSERT_TRUE(player.drain(std::chrono::seconds(5)));
    e = rec->edges();
  }
  // long pulse cut at ~200 ms (on, off), a 100 ms gap, then the five danger pulses; no tick after.
  ASSERT_EQ(e.size(), 2u + 10u);
  EXPECT_NEAR(ms(t0, e[1].t), 200.0, 10.0);
  EXPECT_FALSE(e[1].on);
  EXPECT_NEAR(ms(e[1].t, e[2].t), 100.0, 5.0);
  const auto want = expected_edges(haptic_pattern(ev(Cue::kDropWarning)));
  for (std::size_t i = 0; i < want.size(); ++i) EXPECT_NEAR(ms(e[2].t, e[2 + i].t), want[i].first, 5.0) << i;
  EXPECT_FALSE(e.back().on);
}

TEST(FeedbackHaptic, MissingGpioChipFailsWithAClearMessage) {
  try {
    GpiodLine line("gpiochip_sg_absent", 17);
    FAIL() << "a GPIO chip that does not exist was opened";
  } catch (const std::runtime_error& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("GPIO chip 'gpiochip_sg_absent' line 17"), std::string::npos) << m;
    EXPECT_NE(m.find("cannot open the chip"), std::string::npos) << m;
  }
}

TEST(FeedbackHaptic, FileLineWritesEveryEdge) {
  const std::string path = std::string(STAIRGUIDE_BINARY_DIR) + "/feedback_haptic_edges.txt";
  {
    HapticPlayer player(make_haptic_line("file:" + path, 0));
    player.play(haptic_pattern(ev(Cue::kStairsAhead, 1)), 4);
    ASSERT_TRUE(player.drain(std::chrono::seconds(5)));
  }
  std::ifstream f(path);
  std::vector<std::pair<double, int>> edges;
  double t;
  int v;
  while (f >> t >> v) edges.push_back({t, v});
  ASSERT_EQ(edges.size(), 4u);
  EXPECT_EQ(edges[0].second, 1);
  EXPECT_EQ(edges[3].second, 0);
  EXPECT_NEAR(edges[1].first - edges[0].first, 80.0, 5.0);   // short
  EXPECT_NEAR(edges[3].first - edges[2].first, 250.0, 5.0);  // then long: rising
  EXPECT_THROW(make_haptic_line("file:/nonexistent_dir_sg/edges.txt", 0), std::runtime_error);
}
