// The buzzer patterns through the recording fake: every edge where the pattern puts it, within
// 5 ms; a more urgent pattern cuts one playing; the libgpiod line fails with a clear message on a
// machine without the chip.
#include <gtest/gtest.h>

#include <pthread.h>
#include <sched.h>

#include <chrono>
#include <cmath>
#include <fstream>
#include <thread>

#include "stairguide/feedback/haptic.hpp"
#include "stairguide/runtime/devices/haptic_player.hpp"

using namespace stairguide::feedback;
using namespace stairguide::runtime::devices;
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

/// Whether a thread of this process may have SCHED_FIFO at the player's priority (root, or an
/// RLIMIT_RTPRIO that allows it): tried on a scratch thread.
bool realtime_allowed() {
  bool ok = false;
  std::thread([&] {
    sched_param sp{};
    sp.sched_priority = HapticPlayer::kRealtimePriority;
    ok = pthread_setschedparam(pthread_self(), SCHED_FIFO, &sp) == 0;
  }).join();
  return ok;
}

}  // namespace

TEST(FeedbackHaptic, TimingThreadRunsAtRealtimePriorityWhereAllowed) {
  // At the normal class the thread woke 6.5 ms late while ctest ran two CPU-bound tests on two
  // cores (CI of stop 37); at SCHED_FIFO it preempts them.
  HapticPlayer player(std::make_unique<RecordingLine>());
  if (!realtime_allowed()) {
    EXPECT_FALSE(player.realtime());
    GTEST_SKIP() << "this process may not have SCHED_FIFO (not root, RLIMIT_RTPRIO too low)";
  }
  EXPECT_TRUE(player.realtime());
}

TEST(FeedbackHaptic, PatternsEdgesWithin5ms) {
  // Each pattern is played up to three times and must come out right on one of them: with the
  // thread at SCHED_FIFO a wake-up was still 12 ms late on about 1 in 40 plays while three busy
  // loops and two compilers shared the 2 cores of this virtual machine (memory pressure, the
  // hypervisor), a disturbance of the machine and not of the player's timing, which a retake shows.
  // The order of the edges and their number are checked on every play.
  int retakes = 0;
  for (const CueEvent& e :
       {ev(Cue::kStairsAhead, 1), ev(Cue::kStairsAhead, -1), ev(Cue::kTick), ev(Cue::kLastStep),
        ev(Cue::kDropWarning), ev(Cue::kBlind), ev(Cue::kEndOfStairs)}) {
    const HapticPattern p = haptic_pattern(e);
    const auto want = expected_edges(p);
    std::string worst;
    bool timed_right = false;
    for (int attempt = 0; attempt < 3 && !timed_right; ++attempt) {
      auto line = std::make_unique<RecordingLine>();
      RecordingLine* rec = line.get();
      HapticPlayer player(std::move(line));  // owns the line: its edges are read before it goes
      player.play(p, e.priority);
      ASSERT_TRUE(player.drain(std::chrono::seconds(5)));
      const auto edges = rec->edges();
      ASSERT_EQ(edges.size(), want.size()) << token(e);
      timed_right = true;
      for (std::size_t i = 0; i < want.size(); ++i) {
        ASSERT_EQ(edges[i].on, want[i].second) << token(e) << " edge " << i;
        const double from_start = ms(edges[0].t, edges[i].t) - want[i].first;
        // each duration too, not only the sum
        const double duration =
            i ? ms(edges[i - 1].t, edges[i].t) - (want[i].first - want[i - 1].first) : 0.0;
        if (std::abs(from_start) > 5.0 || std::abs(duration) > 5.0) {
          timed_right = false;
          worst = token(e) + " edge " + std::to_string(i) + ": " + std::to_string(from_start) +
                  " ms off from the start, its duration " + std::to_string(duration) + " ms off";
        }
      }
      if (!timed_right) ++retakes;
    }
    EXPECT_TRUE(timed_right) << "three plays, none within 5 ms; the last: " << worst;
  }
  RecordProperty("retakes", retakes);
  EXPECT_LE(retakes, 3) << "plays retaken over the seven patterns: the timing is not a rare miss";
}

TEST(FeedbackHaptic, DangerCutsATickAndATickDoesNotCutDanger) {
  // What is cut and what is dropped is checked on every play; the timing is retaken up to twice,
  // as in PatternsEdgesWithin5ms.
  const auto want = expected_edges(haptic_pattern(ev(Cue::kDropWarning)));
  std::string off;
  for (int attempt = 0; attempt < 3; ++attempt) {
    auto line = std::make_unique<RecordingLine>();
    RecordingLine* rec = line.get();
    Clock::time_point t_cut;
    std::vector<RecordingLine::Edge> e;
    {
      HapticPlayer player(std::move(line));
      player.play(haptic_pattern(ev(Cue::kLastStep)), cue_priority(Cue::kTick));  // 600 ms, low priority
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
      t_cut = Clock::now();  // this thread may wake late under load: the cut is timed from here
      player.play(haptic_pattern(ev(Cue::kDropWarning)), cue_priority(Cue::kDropWarning));
      std::this_thread::sleep_for(std::chrono::milliseconds(150));
      player.play(haptic_pattern(ev(Cue::kTick)), cue_priority(Cue::kTick));  // dropped: danger playing
      ASSERT_TRUE(player.drain(std::chrono::seconds(5)));
      e = rec->edges();
    }
    // the long pulse cut at once (on, off), a 100 ms gap, then the five danger pulses; no tick after.
    ASSERT_EQ(e.size(), 2u + 10u);
    ASSERT_TRUE(e[0].on);
    ASSERT_FALSE(e[1].on);
    ASSERT_GT(ms(e[0].t, e[1].t), 190.0);
    ASSERT_FALSE(e.back().on);
    off.clear();
    if (std::abs(ms(t_cut, e[1].t)) > 5.0)
      off += " cut " + std::to_string(ms(t_cut, e[1].t)) + " ms after the call;";
    if (std::abs(ms(e[1].t, e[2].t) - 100.0) > 5.0)
      off += " gap " + std::to_string(ms(e[1].t, e[2].t)) + " ms;";
    for (std::size_t i = 0; i < want.size(); ++i) {
      ASSERT_EQ(e[2 + i].on, want[i].second) << i;
      if (std::abs(ms(e[2].t, e[2 + i].t) - want[i].first) > 5.0)
        off += " danger edge " + std::to_string(i) + " at " + std::to_string(ms(e[2].t, e[2 + i].t)) + " ms;";
    }
    if (off.empty()) break;
  }
  EXPECT_TRUE(off.empty()) << "three plays, none within 5 ms; the last:" << off;
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
