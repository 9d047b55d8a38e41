// The cue policy on scripted frame sequences: what is said, in which order, and what is not
// (hysteresis, rate limits, priorities, verbosity, the blind cue, stair-free sequences). The flight
// cues (first step, ticks, counts, steps left, last step, end) are driven by scripted
// TraversalResult sequences: the traversal tracker is another room's.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "stairguide/feedback/cue_policy.hpp"
#include "stairguide/feedback/haptic.hpp"

using namespace stairguide;
using namespace stairguide::feedback;

namespace {

constexpr double kDt = 1.0 / 30.0;

struct Said {
  double t;
  CueEvent e;
};

CueInput floor_frame(double t) {
  CueInput in;
  in.t = t;
  in.floor_found = true;
  return in;
}

/// Floor-only frames (nothing else in view) from `t0` until `t1`, one per kDt.
std::vector<CueInput> floor_frames(double t0, double t1) {
  std::vector<CueInput> f;
  for (double t = t0; t < t1; t += kDt) f.push_back(floor_frame(t));
  return f;
}

/// The frames of `parts`, one part after the other.
std::vector<CueInput> joined(std::initializer_list<std::vector<CueInput>> parts) {
  std::vector<CueInput> f;
  for (const auto& p : parts) f.insert(f.end(), p.begin(), p.end());
  return f;
}

CueInput stair_frame(double t, StairKind kind, float distance, float bearing = 0.f) {
  CueInput in = floor_frame(t);
  in.stair.detected = true;
  in.stair.kind = kind;
  in.stair.direction = kind == StairKind::kDescending ? -1 : 1;
  in.stair.distance_m = distance;
  in.stair.bearing_rad = bearing;
  return in;
}

std::vector<Said> feed(CuePolicy& p, const std::vector<CueInput>& frames) {
  std::vector<Said> out;
  for (const auto& f : frames)
    for (const auto& e : p.step(f)) out.push_back({f.t, e});
  return out;
}

/// The tokens of what was said, the approach beeps left out (their rhythm is tested on its own).
std::vector<std::string> toks(const std::vector<Said>& s) {
  std::vector<std::string> t;
  for (const auto& x : s)
    if (x.e.cue != Cue::kApproach) t.push_back(token(x.e));
  return t;
}

/// The times `cue` was said.
std::vector<double> times_of(const std::vector<Said>& s, Cue cue) {
  std::vector<double> t;
  for (const auto& x : s)
    if (x.e.cue == cue) t.push_back(x.t);
  return t;
}

/// The times of the approach beeps.
std::vector<double> beeps(const std::vector<Said>& s) { return times_of(s, Cue::kApproach); }

bool about_stairs(const CueEvent& e) {
  return e.cue == Cue::kStairsAhead || e.cue == Cue::kDropWarning || e.cue == Cue::kStepAhead ||
         e.cue == Cue::kFirstStep || e.cue == Cue::kTick || e.cue == Cue::kCount ||
         e.cue == Cue::kStepsLeft || e.cue == Cue::kLastStep || e.cue == Cue::kEndOfStairs;
}

int count_of(const std::vector<Said>& s, Cue c) {
  int n = 0;
  for (const auto& x : s) n += x.e.cue == c;
  return n;
}

/// Walking toward a staircase at 1 m/s from `from` metres, one frame per kDt, for `seconds`.
std::vector<CueInput> approach(double t0, StairKind kind, float from, double seconds, float bearing = 0.f) {
  std::vector<CueInput> f;
  for (double t = 0; t < seconds; t += kDt)
    f.push_back(stair_frame(t0 + t, kind, std::max(0.3f, from - static_cast<float>(t)), bearing));
  return f;
}

}  // namespace

TEST(FeedbackPolicy, FloorOnlyIsSilentAfterReady) {
  CuePolicy p{FeedbackConfig{}};
  std::vector<CueInput> frames;
  for (int i = 0; i < 900; ++i) frames.push_back(floor_frame(i * kDt));  // 30 s
  const auto s = feed(p, frames);
  ASSERT_EQ(s.size(), 1u);
  EXPECT_EQ(s[0].e.cue, Cue::kReady);
  EXPECT_DOUBLE_EQ(s[0].t, 0.0);
}

TEST(FeedbackPolicy, AscendingAnnouncedOnceAfterConfirmation) {
  FeedbackConfig c;  // confirm 4 frames over 0.3 s
  CuePolicy p{c};
  auto frames = approach(0.0, StairKind::kAscending, 3.2f, 3.0);
  const auto s = feed(p, frames);
  ASSERT_EQ(s.size(), 2u) << ::testing::PrintToString(toks(s));
  EXPECT_EQ(s[0].e.cue, Cue::kReady);
  EXPECT_EQ(token(s[1].e), "stairs_ahead_up:3m");  // straight ahead: no clock said
  // Not before the detection has persisted confirm_time, and on the first frame after it.
  EXPECT_GE(s[1].t, c.confirm_time - 1e-6);  // (confirm_time is a float)
  EXPECT_LT(s[1].t, c.confirm_time + kDt + 1e-9);
  EXPECT_EQ(clips_for(s[1].e), (std::vector<std::string>{"stairs_up", "n3", "metres"}));
}

TEST(FeedbackPolicy, ClockPositionAndSideAreSaid) {
  EXPECT_EQ(clock_position(0.f), 12);
  EXPECT_EQ(clock_position(static_cast<float>(M_PI / 2)), 3);
  EXPECT_EQ(clock_position(static_cast<float>(-M_PI / 3)), 10);
  EXPECT_EQ(clock_position(std::nanf("")), 12);
  CuePolicy p{FeedbackConfig{}};
  const auto s = feed(p, approach(0.0, StairKind::kAscending, 2.2f, 1.0, static_cast<float>(M_PI / 6)));
  ASSERT_EQ(s.size(), 2u);
  EXPECT_EQ(token(s[1].e), "stairs_ahead_up:2m@1");
  EXPECT_EQ(clips_for(s[1].e), (std::vector<std::string>{"stairs_up", "n2", "metres", "n1", "oclock"}));
}

TEST(FeedbackPolicy, FlickerIsNeverAnnounced) {
  CuePolicy p{FeedbackConfig{}};
  std::vector<CueInput> frames;
  // 60 s of floor with a false detection: 3 frames in a row every second (< confirm_frames), and
  // single frames every 0.5 s (gaps > confirm_time): never confirmed.
  for (int i = 0; i < 1800; ++i) {
    const double t = i * kDt;
    const int in_second = i % 30;
    if (in_second < 3 || in_second == 15)
      frames.push_back(
          stair_frame(t, in_second == 15 ? StairKind::kDescending : StairKind::kAscending, 2.5f));
    else
      frames.push_back(floor_frame(t));
  }
  const auto s = feed(p, frames);
  for (const auto& x : s) EXPECT_FALSE(about_stairs(x.e)) << token(x.e) << " at " << x.t;
  EXPECT_EQ(s.size(), 1u);
}

TEST(FeedbackPolicy, DropoutDoesNotRetractNorRepeat) {
  FeedbackConfig c;  // forget 3 s, repeat 20 s
  CuePolicy p{c};
  const std::vector<CueInput> f =
      joined({approach(0.0, StairKind::kAscending, 3.6f, 1.0), floor_frames(1.0, 2.0),  // 1 s dropout
              approach(2.0, StairKind::kAscending, 2.6f, 1.0), floor_frames(3.0, 8.0),  // forgotten (> 3 s)
              approach(8.0, StairKind::kAscending, 3.0f, 1.0)});                        // < 20 s: not again
  auto s = feed(p, f);
  EXPECT_EQ(count_of(s, Cue::kStairsAhead), 1) << ::testing::PrintToString(toks(s));
  // Long after: a staircase found again is announced again.
  s = feed(p, joined({floor_frames(9.0, 30.0), approach(30.0, StairKind::kAscending, 3.0f, 1.0)}));
  ASSERT_EQ(count_of(s, Cue::kStairsAhead), 1);
  EXPECT_GE(s.back().t, 30.0);
}

TEST(FeedbackPolicy, FarStairsWaitForAnnounceDistance) {
  FeedbackConfig c;
  c.announce_distance = 4.0f;
  CuePolicy p{c};
  const auto s = feed(p, approach(0.0, StairKind::kAscending, 7.0f, 4.0));
  ASSERT_EQ(count_of(s, Cue::kStairsAhead), 1);
  const auto& e = s.back();
  EXPECT_EQ(e.e.number, 4);
  // 7 m at t=0, 1 m/s: within 4 m from t=3 s.
  EXPECT_NEAR(e.t, 3.0, kDt + 1e-9);
}

TEST(FeedbackPolicy, DescendingWithinDangerDistanceAlwaysWarnsEvenQuiet) {
  for (const char* v : {"quiet", "normal", "verbose"}) {
    FeedbackConfig c;
    c.verbosity = v;
    CuePolicy p{c};
    // Seen at 3.5 m (told as stairs ahead, going down), then nearer than 2 m: the warning.
    const auto s = feed(p, approach(0.0, StairKind::kDescending, 3.5f, 3.0));
    ASSERT_EQ(count_of(s, Cue::kDropWarning), 1) << v << ::testing::PrintToString(toks(s));
    // Verbose too: no distance update between 3 m and the warning (rate limit), none after it.
    ASSERT_EQ(count_of(s, Cue::kStairsAhead), 1) << v << ::testing::PrintToString(toks(s));
    for (const auto& x : s)
      if (x.e.cue == Cue::kDropWarning) {
        EXPECT_EQ(x.e.number, 2) << v;
        EXPECT_NEAR(x.t, 1.5, kDt + 1e-9) << v;  // 3.5 m - 1 m/s * 1.5 s = 2 m
        EXPECT_EQ(x.e.priority, cue_priority(Cue::kDropWarning));
        EXPECT_EQ(clips_for(x.e).front(), "warning");
      } else if (x.e.cue == Cue::kStairsAhead) {
        EXPECT_EQ(x.e.earcon_only, std::string(v) == "quiet");
        EXPECT_EQ(x.e.direction, -1);
      }
  }
  // First seen already near: only the warning; of unknown distance (no floor): the warning.
  CuePolicy p{FeedbackConfig{}};
  auto s = feed(p, approach(0.0, StairKind::kDescending, 1.5f, 1.0));
  EXPECT_EQ(toks(s), (std::vector<std::string>{"ready", "drop_warning_down:1m"}));
  CuePolicy q{FeedbackConfig{}};
  std::vector<CueInput> f;
  for (int i = 0; i < 30; ++i) {
    CueInput in = stair_frame(i * kDt, StairKind::kDescending, std::nanf(""));
    in.floor_found = false;
    in.stair.without_floor = true;
    f.push_back(in);
  }
  s = feed(q, f);
  EXPECT_EQ(toks(s), (std::vector<std::string>{"ready", "drop_warning_down"}));
}

TEST(FeedbackPolicy, DropWarnedAgainOnlyAfterItWasForgotten) {
  FeedbackConfig c;  // forget 3 s, repeat 20 s
  CuePolicy p{c};
  auto s = feed(p, joined({approach(0.0, StairKind::kDescending, 1.8f, 1.0),
                           floor_frames(1.0, 2.5),  // 1.5 s dropout: held
                           approach(2.5, StairKind::kDescending, 1.5f, 0.5)}));
  EXPECT_EQ(count_of(s, Cue::kDropWarning), 1) << ::testing::PrintToString(toks(s));
  // Out of mind for 4 s (forgotten), back within 2 m, 5 s after the warning: warned again.
  s = feed(p, joined({floor_frames(3.0, 7.0), approach(7.0, StairKind::kDescending, 1.5f, 1.0)}));
  ASSERT_EQ(count_of(s, Cue::kDropWarning), 1) << ::testing::PrintToString(toks(s));
  for (const auto& x : s)
    if (x.e.cue == Cue::kDropWarning) {
      EXPECT_NEAR(x.t, 7.0 + c.confirm_time, kDt + 1e-6);
    }
  EXPECT_EQ(count_of(s, Cue::kStairsAhead), 0);
}

TEST(FeedbackPolicy, CurbsAndSingleSteps) {
  CuePolicy p{FeedbackConfig{}};
  auto s = feed(p, approach(0.0, StairKind::kCurb, 2.0f, 1.0));
  std::vector<CueInput> in;
  for (int i = 0; i < 30; ++i) {
    CueInput x = stair_frame(5.0 + i * kDt, StairKind::kSingleStep, 1.5f);
    x.stair.direction = -1;
    in.push_back(x);
  }
  for (auto& x : feed(p, in)) s.push_back(x);
  EXPECT_EQ(toks(s), (std::vector<std::string>{"ready", "curb_up", "step_down"}));
  EXPECT_EQ(clips_for(s[1].e), (std::vector<std::string>{"curb_up"}));
  EXPECT_EQ(clips_for(s[2].e), (std::vector<std::string>{"step_down"}));
}

TEST(FeedbackPolicy, RateLimitBetweenTwoAnnouncements) {
  FeedbackConfig c;
  c.min_cue_interval = 1.5f;
  CuePolicy p{c};
  // An ascending staircase, then 0.5 s later a different one (descending, far): the second
  // waits until 1.5 s after the first.
  std::vector<CueInput> f = approach(0.0, StairKind::kAscending, 3.0f, 0.5);
  for (double t = 0.5; t < 3.0; t += kDt) f.push_back(stair_frame(t, StairKind::kDescending, 3.5f));
  const auto s = feed(p, f);
  ASSERT_EQ(count_of(s, Cue::kStairsAhead), 2) << ::testing::PrintToString(toks(s));
  const std::vector<double> ts = times_of(s, Cue::kStairsAhead);
  EXPECT_GE(ts[1] - ts[0], 1.5 - 1e-9);
  EXPECT_LT(ts[1] - ts[0], 1.5 + kDt + 1e-9);
}

TEST(FeedbackPolicy, BlindToldOnceThenAtTheSlowInterval) {
  FeedbackConfig c;  // blind after 3 s, again every 30 s
  CuePolicy p{c};
  std::vector<CueInput> f;
  for (double t = 0; t < 70.0; t += kDt) {
    CueInput in;
    in.t = t;
    in.floor_found = std::fabs(t - 40.0) < 0.02;  // one frame with a floor at 40 s
    f.push_back(in);
  }
  const auto s = feed(p, f);
  const std::vector<double> ts = times_of(s, Cue::kBlind);
  ASSERT_EQ(ts.size(), 3u) << ::testing::PrintToString(toks(s));
  EXPECT_NEAR(ts[0], 3.0, kDt + 1e-6);
  EXPECT_NEAR(ts[1] - ts[0], 30.0, kDt + 1e-6);
  EXPECT_NEAR(ts[2] - ts[1], 30.0, kDt + 1e-6);  // the floor at 40 s did not reset the slow interval
  for (const auto& x : s) EXPECT_FALSE(about_stairs(x.e));
  // A stair in view (even without a floor) is not blind.
  CuePolicy q{c};
  std::vector<CueInput> g;
  for (double t = 0; t < 10.0; t += kDt) {
    CueInput in = stair_frame(t, StairKind::kAscending, std::nanf(""));
    in.floor_found = false;
    g.push_back(in);
  }
  EXPECT_EQ(count_of(feed(q, g), Cue::kBlind), 0);
}

TEST(FeedbackPolicy, CameraLostAndBackOnceEach) {
  CuePolicy p{FeedbackConfig{}};
  EXPECT_TRUE(p.camera_back(0.0).empty());
  auto a = p.camera_lost(1.0);
  ASSERT_EQ(a.size(), 1u);
  EXPECT_EQ(a[0].cue, Cue::kCameraLost);
  EXPECT_TRUE(p.camera_lost(2.0).empty());
  auto b = p.camera_back(3.0);
  ASSERT_EQ(b.size(), 1u);
  EXPECT_EQ(b[0].cue, Cue::kCameraBack);
}

TEST(FeedbackPolicy, PrioritiesWarningAboveTick) {
  EXPECT_GT(cue_priority(Cue::kDropWarning), cue_priority(Cue::kCameraLost));
  EXPECT_GT(cue_priority(Cue::kCameraLost), cue_priority(Cue::kLastStep));
  EXPECT_GT(cue_priority(Cue::kLastStep), cue_priority(Cue::kStairsAhead));
  EXPECT_GT(cue_priority(Cue::kBlind), cue_priority(Cue::kStairsAhead));
  EXPECT_GT(cue_priority(Cue::kStairsAhead), cue_priority(Cue::kReady));
  EXPECT_GT(cue_priority(Cue::kReady), cue_priority(Cue::kCount));
  EXPECT_GT(cue_priority(Cue::kCount), cue_priority(Cue::kTick));
}

namespace {

/// A scripted traversal: 1 s of floor, the approach in stair_ahead (3 m -> 0.5 m over 2.5 s),
/// then `steps` steps at 0.6 s each (on_stairs; last_step once climbed == steps - 1), arrived
/// for 1 s, searching again.
std::vector<CueInput> scripted_flight(int steps, int direction = 1, double step_s = 0.6) {
  std::vector<CueInput> f;
  double t = 0;
  const StairKind kind = direction > 0 ? StairKind::kAscending : StairKind::kDescending;
  auto tr_frame = [&](TraversalState st) {
    CueInput in = floor_frame(t);
    in.traversal.ran = true;
    in.traversal.state = st;
    in.traversal.kind = st == TraversalState::kSearching ? StairKind::kNone : kind;
    in.traversal.direction = st == TraversalState::kSearching ? 0 : direction;
    in.traversal.steps_known = steps;
    return in;
  };
  for (; t < 1.0; t += kDt) f.push_back(tr_frame(TraversalState::kSearching));
  for (double d = 3.0; d > 0.5; d -= kDt, t += kDt) {
    CueInput in = tr_frame(TraversalState::kStairAhead);
    in.traversal.in_view = true;
    in.traversal.distance_m = static_cast<float>(d);
    in.traversal.bearing_rad = 0.f;
    f.push_back(in);
  }
  for (int climbed = 1; climbed <= steps; ++climbed) {
    for (double s = 0; s < step_s; s += kDt, t += kDt) {
      CueInput in = tr_frame(climbed >= steps - 1 ? TraversalState::kLastStep : TraversalState::kOnStairs);
      in.traversal.step_index = climbed;
      in.traversal.steps_climbed = climbed;
      in.traversal.steps_left = steps - climbed;
      in.traversal.last_known = true;
      f.push_back(in);
    }
  }
  for (double s = 0; s < 1.0; s += kDt, t += kDt) f.push_back(tr_frame(TraversalState::kArrived));
  for (double s = 0; s < 2.0; s += kDt, t += kDt) f.push_back(tr_frame(TraversalState::kSearching));
  return f;
}

}  // namespace

TEST(FeedbackPolicy, ScriptedClimbInOrder) {
  CuePolicy p{FeedbackConfig{}};  // count every 5 steps
  const auto s = feed(p, scripted_flight(8));
  EXPECT_EQ(toks(s), (std::vector<std::string>{"ready", "stairs_ahead_up:3m", "first_step", "steps_left:7",
                                               "tick", "tick", "tick", "count:5", "tick", "last_step", "tick",
                                               "end_of_stairs"}));
  // Each step cue on the frame its step was reached (0.6 s apart).
  std::vector<double> ticks;
  for (const auto& x : s)
    if (x.e.cue == Cue::kTick || x.e.cue == Cue::kCount) ticks.push_back(x.t);
  for (std::size_t i = 1; i < 4; ++i) EXPECT_NEAR(ticks[i] - ticks[i - 1], 0.6, kDt + 1e-9);
}

TEST(FeedbackPolicy, ScriptedDescentWarnsAndCounts) {
  CuePolicy p{FeedbackConfig{}};
  const auto s = feed(p, scripted_flight(4, -1));
  // 3 m -> told; 2 m -> the drop warning; then the flight.
  EXPECT_EQ(toks(s),
            (std::vector<std::string>{"ready", "stairs_ahead_down:3m", "drop_warning_down:2m", "first_step",
                                      "steps_left:3", "tick", "last_step", "tick", "end_of_stairs"}));
}

TEST(FeedbackPolicy, QuietFlightOnlyTheLastStep) {
  FeedbackConfig c;
  c.verbosity = "quiet";
  CuePolicy p{c};
  const auto s = feed(p, scripted_flight(8));
  EXPECT_EQ(toks(s), (std::vector<std::string>{"ready", "stairs_ahead_up:3m", "last_step"}));
  EXPECT_TRUE(s[1].e.earcon_only);
  EXPECT_EQ(clips_for(s[1].e), (std::vector<std::string>{"up"}));
}

TEST(FeedbackPolicy, VerboseDistancesAndStepsLeft) {
  FeedbackConfig c;
  c.verbosity = "verbose";
  CuePolicy p{c};
  const auto s = feed(p, scripted_flight(12));
  EXPECT_EQ(toks(s),
            (std::vector<std::string>{"ready", "stairs_ahead_up:3m@12", "stairs_ahead_up:1m@12", "first_step",
                                      "steps_left:11", "tick", "tick", "tick", "steps_left:7", "tick", "tick",
                                      "tick", "tick", "steps_left:2", "last_step", "tick", "end_of_stairs"}));
}

TEST(FeedbackPolicy, WarningCutsTickOnTheSameFrame) {
  // The step that enters last_step would also tick: only the last step is given.
  CuePolicy p{FeedbackConfig{}};
  const auto s = feed(p, scripted_flight(3));
  EXPECT_EQ(toks(s), (std::vector<std::string>{"ready", "stairs_ahead_up:3m", "first_step", "steps_left:2",
                                               "last_step", "tick", "end_of_stairs"}));
}

TEST(FeedbackPolicy, TicksRateLimitedOnAFlickeringCount) {
  FeedbackConfig c;
  c.count_interval = 100;
  CuePolicy p{c};
  // The tracker's count rises on 20 successive frames (a fault): ticks at most every 0.25 s.
  std::vector<CueInput> f;
  for (int i = 0; i < 40; ++i) {
    CueInput in = floor_frame(i * kDt);
    in.traversal.ran = true;
    in.traversal.state = TraversalState::kOnStairs;
    in.traversal.kind = StairKind::kAscending;
    in.traversal.direction = 1;
    in.traversal.steps_climbed = in.traversal.step_index = 1 + std::min(i, 20);
    f.push_back(in);
  }
  const auto s = feed(p, f);
  const std::vector<double> ts = times_of(s, Cue::kTick);
  ASSERT_GE(ts.size(), 2u);
  EXPECT_LE(ts.size(), 3u);  // 20 frames = 0.67 s
  for (std::size_t i = 1; i < ts.size(); ++i) EXPECT_GE(ts[i] - ts[i - 1], 0.25 - 1e-9);
}

TEST(FeedbackPolicy, ReconfigureVerbosityMidFlight) {
  CuePolicy p{FeedbackConfig{}};
  const auto f = scripted_flight(8);
  std::vector<Said> s;
  for (std::size_t i = 0; i < f.size(); ++i) {
    if (i == f.size() / 2) {
      FeedbackConfig q;
      q.verbosity = "quiet";
      p.reconfigure(q);
    }
    for (const auto& e : p.step(f[i])) s.push_back({f[i].t, e});
  }
  // No tick, count or end after the switch; the last step still told.
  bool switched = false;
  for (const auto& x : s) {
    if (x.t >= f[f.size() / 2].t) switched = true;
    if (switched) {
      EXPECT_TRUE(x.e.cue == Cue::kLastStep) << token(x.e);
    }
  }
  EXPECT_EQ(count_of(s, Cue::kLastStep), 1);
}

TEST(FeedbackPolicy, ClockGoingBackStartsAfresh) {
  CuePolicy p{FeedbackConfig{}};
  auto s = feed(p, approach(100.0, StairKind::kAscending, 3.0f, 1.0));
  EXPECT_EQ(count_of(s, Cue::kStairsAhead), 1);
  s = feed(p, approach(0.0, StairKind::kAscending, 3.0f, 1.0));  // a reopened camera: t from 0
  EXPECT_EQ(count_of(s, Cue::kStairsAhead), 1);
}

TEST(FeedbackHapticPatterns, DirectionAndCountCoded) {
  CueEvent up, down;
  up.cue = down.cue = Cue::kStairsAhead;
  up.direction = 1;
  down.direction = -1;
  const auto pu = haptic_pattern(up), pd = haptic_pattern(down);
  ASSERT_EQ(pu.size(), 2u);
  ASSERT_EQ(pd.size(), 2u);
  EXPECT_LT(pu[0].on_ms, pu[1].on_ms);  // rising: short-long
  EXPECT_GT(pd[0].on_ms, pd[1].on_ms);  // falling: long-short
  CueEvent tick, last, drop, blind;
  tick.cue = Cue::kTick;
  last.cue = Cue::kLastStep;
  drop.cue = Cue::kDropWarning;
  blind.cue = Cue::kBlind;
  EXPECT_EQ(haptic_pattern(tick).size(), 1u);
  ASSERT_EQ(haptic_pattern(last).size(), 1u);
  EXPECT_GE(haptic_pattern(last)[0].on_ms, 5 * haptic_pattern(tick)[0].on_ms);
  EXPECT_EQ(haptic_pattern(drop).size(), 5u);
  EXPECT_EQ(haptic_pattern(blind).size(), 3u);
}

// ------------------------------------------------------------------ the approach beep

namespace {
/// Walking at `speed` m/s toward a descending first edge from `from` m down to `to` m (straight
/// ahead unless `bearing`), one frame per kDt from t0; distances with +-`noise` m of alternating
/// noise (a depth camera's distance is never smooth).
std::vector<CueInput> walk_to_edge(double t0, float from, float to, float speed, float noise = 0.f,
                                   float bearing = 0.f) {
  std::vector<CueInput> f;
  int i = 0;
  for (double t = 0; from - speed * t > to; t += kDt, ++i) {
    const float d = from - speed * static_cast<float>(t) + (i % 2 ? noise : -noise);
    f.push_back(stair_frame(t0 + t, StairKind::kDescending, d, bearing));
  }
  return f;
}
}  // namespace

// Parking-sensor style: from the range (2 m) in, one beep, then again and again, the interval
// shrinking from 1.5 s at 2 m to 0.25 s at 0.5 m and never growing while the wearer walks on,
// even on noisy distances; the first when the edge comes within range; none before.
TEST(FeedbackPolicy, ApproachBeepQuickensAsTheEdgeNears) {
  for (const float noise : {0.f, 0.04f}) {
    FeedbackConfig c;  // range 2 m, 1.5 s .. 0.25 s at 0.5 m
    CuePolicy p{c};
    const auto s = feed(p, walk_to_edge(0.0, 3.5f, 0.2f, 0.6f, noise));
    auto b = beeps(s);
    ASSERT_GE(b.size(), 5u) << noise;
    // The first beat when the edge came within 2 m (3.5 m at 0.6 m/s: at 2.5 s), give or take the
    // noise: the drop warning, which stands for the first beep (no beep over its alarm).
    double warned = -1;
    for (const auto& x : s)
      if (x.e.cue == Cue::kDropWarning) warned = x.t;
    EXPECT_NEAR(warned, 2.5, 0.15) << noise;
    EXPECT_GT(b[0], warned);
    b.insert(b.begin(), warned);
    std::vector<double> gaps;
    for (std::size_t i = 1; i < b.size(); ++i) gaps.push_back(b[i] - b[i - 1]);
    for (std::size_t i = 1; i < gaps.size(); ++i)
      EXPECT_LE(gaps[i], gaps[i - 1] + 1e-9) << noise << " beep " << i;
    EXPECT_GT(gaps.front(), 0.9) << noise;                // far: slow (1.5 s at 2 m, less as it nears)
    EXPECT_NEAR(gaps.back(), 0.25, kDt + 1e-9) << noise;  // at and nearer than 0.5 m: 0.25 s
    // The distance it beeps for goes down with the beeps.
    float last = 1e9f;
    for (const auto& x : s)
      if (x.e.cue == Cue::kApproach) {
        EXPECT_LE(x.e.distance_m, last);
        EXPECT_LE(x.e.distance_m, c.approach_range + noise);
        last = x.e.distance_m;
        EXPECT_EQ(haptic_pattern(x.e).size(), 1u);  // one pulse per beep
        EXPECT_EQ(clips_for(x.e), (std::vector<std::string>{"approach"}));
      }
    // The interval between beeps follows the distance (linear between the two ends).
    EXPECT_EQ(count_of(s, Cue::kDropWarning), 1);
  }
}

TEST(FeedbackPolicy, ApproachBeepStopsOnTheFirstStep) {
  CuePolicy p{FeedbackConfig{}};
  const auto s = feed(p, scripted_flight(4, -1));
  double first_step_t = -1;
  for (const auto& x : s)
    if (x.e.cue == Cue::kFirstStep) first_step_t = x.t;
  ASSERT_GT(first_step_t, 0);
  const auto b = beeps(s);
  ASSERT_GE(b.size(), 2u);
  for (double t : b) EXPECT_LT(t, first_step_t);
  // Ascending flights never beep.
  CuePolicy q{FeedbackConfig{}};
  EXPECT_TRUE(beeps(feed(q, scripted_flight(4, 1))).empty());
}

TEST(FeedbackPolicy, ApproachBeepStopsWhenTurnedAwayOrStopped) {
  FeedbackConfig c;  // cone 35 deg, stall 2 s
  CuePolicy p{c};
  // Walking in to 1.2 m: beeping.
  auto f = walk_to_edge(0.0, 2.5f, 1.2f, 0.5f);
  double t = f.back().t + kDt;
  const std::size_t walked = f.size();
  // Turned 60 deg away for 2 s (the edge still seen, at the side): silent.
  for (double u = 0; u < 2.0; u += kDt) f.push_back(stair_frame(t + u, StairKind::kDescending, 1.2f, 1.05f));
  t += 2.0;
  const std::size_t turned = f.size();
  // Back facing it and standing still for 4 s: beeps for the stall time, then silent.
  for (double u = 0; u < 4.0; u += kDt) f.push_back(stair_frame(t + u, StairKind::kDescending, 1.2f, 0.f));
  const double still_from = t;
  t += 4.0;
  // Walking on: beeping again.
  for (auto& x : walk_to_edge(t, 1.2f, 0.5f, 0.5f)) f.push_back(x);
  std::vector<Said> s;
  std::vector<double> during_walk, during_turn, during_still, after;
  for (std::size_t i = 0; i < f.size(); ++i)
    for (const auto& e : p.step(f[i]))
      if (e.cue == Cue::kApproach) {
        if (i < walked)
          during_walk.push_back(f[i].t);
        else if (i < turned)
          during_turn.push_back(f[i].t);
        else if (f[i].t < still_from + 4.0)
          during_still.push_back(f[i].t);
        else
          after.push_back(f[i].t);
      }
  EXPECT_GE(during_walk.size(), 1u);
  EXPECT_TRUE(during_turn.empty()) << ::testing::PrintToString(during_turn);
  ASSERT_FALSE(during_still.empty());
  EXPECT_LE(during_still.back(), still_from + c.approach_stall + kDt);
  EXPECT_GE(after.size(), 2u);
}

TEST(FeedbackPolicy, ApproachBeepSilentWithoutADescent) {
  CuePolicy p{FeedbackConfig{}};
  EXPECT_TRUE(beeps(feed(p, floor_frames(0, 10))).empty());
  CuePolicy q{FeedbackConfig{}};
  EXPECT_TRUE(beeps(feed(q, approach(0.0, StairKind::kAscending, 3.f, 3.0))).empty());
  CuePolicy r{FeedbackConfig{}};  // a flicker of a descent (never confirmed)
  std::vector<CueInput> g;
  for (int i = 0; i < 300; ++i)
    g.push_back(i % 10 == 0 ? stair_frame(i * kDt, StairKind::kDescending, 1.0f) : floor_frame(i * kDt));
  EXPECT_TRUE(beeps(feed(r, g)).empty());
  FeedbackConfig off;
  off.approach_range = 0.f;  // turned off
  CuePolicy o{off};
  EXPECT_TRUE(beeps(feed(o, walk_to_edge(0.0, 3.f, 0.3f, 0.6f))).empty());
  // Quiet verbosity keeps it: a safety cue.
  FeedbackConfig quiet;
  quiet.verbosity = "quiet";
  CuePolicy qq{quiet};
  EXPECT_GE(beeps(feed(qq, walk_to_edge(0.0, 3.f, 0.3f, 0.6f))).size(), 5u);
}

// How each cue meets what sounds: earcons mix, the step's phrases cut and make the older step and
// "ahead" phrases stale, the rest wait their turn; the staircase's side places the cue.
TEST(FeedbackPolicy, CueSoundsAndWhatTheyMakeStale) {
  EXPECT_EQ(cue_sound(Cue::kTick), CueSound::kEarcon);
  EXPECT_EQ(cue_sound(Cue::kApproach), CueSound::kEarcon);
  for (Cue c : {Cue::kFirstStep, Cue::kCount, Cue::kStepsLeft, Cue::kLastStep, Cue::kEndOfStairs}) {
    EXPECT_EQ(cue_sound(c), CueSound::kStepPhrase) << to_string(c);
    EXPECT_TRUE(cue_supersedes(c) & cue_bit(Cue::kStairsAhead)) << to_string(c);
    EXPECT_TRUE(cue_supersedes(c) & cue_bit(Cue::kCount)) << to_string(c);
    EXPECT_FALSE(cue_supersedes(c) & cue_bit(Cue::kCameraLost)) << to_string(c);
  }
  for (Cue c : {Cue::kReady, Cue::kStairsAhead, Cue::kDropWarning, Cue::kBlind, Cue::kCameraLost}) {
    EXPECT_EQ(cue_sound(c), CueSound::kPhrase) << to_string(c);
    EXPECT_EQ(cue_supersedes(c), 0u) << to_string(c);
  }
  // What is ahead is placed by its bearing (2 o'clock: to the right); the flight's cues centred.
  CuePolicy p{FeedbackConfig{}};
  const auto s = feed(p, approach(0.0, StairKind::kAscending, 3.f, 1.0, 1.0f));
  ASSERT_EQ(count_of(s, Cue::kStairsAhead), 1);
  for (const auto& x : s)
    if (x.e.cue == Cue::kStairsAhead) {
      EXPECT_GT(cue_pan(x.e), 0.4f);
    }
  CuePolicy q{FeedbackConfig{}};
  for (const auto& x : feed(q, scripted_flight(4)))
    if (x.e.cue != Cue::kStairsAhead) {
      EXPECT_EQ(cue_pan(x.e), 0.f) << token(x.e);
    }
}

// ------------------------------------------------------------------ the system's state

TEST(FeedbackPolicy, BatteryLowThenCriticalOnceEachWithRepeats) {
  FeedbackConfig c;  // low 15 %, critical 5 %, repeats 300 s / 60 s
  CuePolicy p{c};
  std::vector<std::string> said;
  auto poll = [&](double t, float charge, bool charging = false) {
    for (const auto& e : p.battery(t, true, charge, charging)) said.push_back(token(e));
  };
  for (int i = 0; i < 10; ++i) poll(i * 10.0, 0.40f - 0.02f * i);  // 40 % .. 22 %: nothing
  EXPECT_TRUE(said.empty());
  poll(100, 0.15f);  // at the mark: told
  poll(110, 0.14f);  // once
  poll(120, 0.17f);  // a reading back up within 3 points: as it was (not told again at 15)
  poll(130, 0.15f);
  EXPECT_EQ(said, (std::vector<std::string>{"battery_low:15"}));
  poll(420, 0.10f);  // 300 s later, still low: again
  poll(430, 0.05f);  // critical: at once
  poll(440, 0.04f);
  poll(500, 0.03f);  // 70 s after: again
  EXPECT_EQ(said, (std::vector<std::string>{"battery_low:15", "battery_low:10", "battery_critical:5",
                                            "battery_critical:3"}));
  said.clear();
  poll(510, 0.03f, true);  // charging: silent, and over
  poll(520, 0.20f);
  poll(530, 0.14f);  // a new fall: told again at once
  EXPECT_EQ(said, (std::vector<std::string>{"battery_low:14"}));
  CuePolicy q{c};
  EXPECT_TRUE(q.battery(0, false, 0.0f, false).empty());  // no battery (a desktop): nothing
  for (Cue k : {Cue::kBatteryLow, Cue::kBatteryCritical}) {
    CueEvent e;
    e.cue = k;
    EXPECT_FALSE(haptic_pattern(e).empty());
    EXPECT_EQ(cue_sound(k), CueSound::kPhrase);
  }
  EXPECT_GT(cue_priority(Cue::kBatteryCritical), cue_priority(Cue::kStairsAhead));
}

TEST(FeedbackPolicy, SlowWhenPerceptionIsBehindLongEnough) {
  FeedbackConfig c;  // behind: lag > 0.5 s for 3 s; again every 60 s
  CuePolicy p{c};
  std::vector<CueInput> f;
  for (double t = 0; t < 10; t += kDt) {
    CueInput in = floor_frame(t);
    in.lag_s = t < 2 ? 0.05 : t < 3 ? 0.8 : t < 3.3 ? 0.1 : 0.9;  // a short spell, then a long one
    f.push_back(in);
  }
  const auto s = feed(p, f);
  const std::vector<double> slow = times_of(s, Cue::kSlow);
  ASSERT_EQ(slow.size(), 1u) << ::testing::PrintToString(toks(s));
  EXPECT_NEAR(slow[0], 3.3 + c.slow_after, 2 * kDt + 1e-9);  // 3 s into the long spell, not the short one
  // Quiet verbosity too; back on time and behind again: told again at once after slow_after.
  FeedbackConfig q = c;
  q.verbosity = "quiet";
  CuePolicy r{q};
  std::vector<CueInput> g;
  for (double t = 0; t < 20; t += kDt) {
    CueInput in = floor_frame(t);
    in.lag_s = (t > 1 && t < 6) || t > 10 ? 1.0 : 0.02;
    g.push_back(in);
  }
  int n = 0;
  for (const auto& x : feed(r, g)) n += x.e.cue == Cue::kSlow;
  EXPECT_EQ(n, 2);
}

// ---------------------------------------------------------------- the wearer's button

namespace {
CueInput pressed(CueInput in, Press p) {
  in.presses.push_back(p);
  return in;
}
/// The last cue of kind `c` said (a default CueEvent of kReady when none).
CueEvent last_of(const std::vector<Said>& s, Cue c) {
  CueEvent e;
  for (const auto& x : s)
    if (x.e.cue == c) e = x.e;
  return e;
}
}  // namespace

// A short press says where the staircase held in mind is: up or down, its metres and its clock
// position (said even straight ahead: the wearer asked where); "no stairs" when none is held (never
// seen, or forgotten).
TEST(FeedbackButton, ShortPressSaysWhereTheStairsAre) {
  CuePolicy p{FeedbackConfig{}};
  auto s = feed(p, {pressed(floor_frame(0.0), Press::kShort)});
  ASSERT_EQ(toks(s), (std::vector<std::string>{"where_none", "ready"}));  // the answer is the more urgent
  EXPECT_EQ(clips_for(s[0].e), (std::vector<std::string>{"no_stairs"}));
  // An ascending staircase at 2 o'clock, told; then asked at 2.9 m.
  auto f = approach(1.0, StairKind::kAscending, 3.9f, 1.0, static_cast<float>(M_PI / 3));
  f.back() = pressed(f.back(), Press::kShort);
  s = feed(p, f);
  const CueEvent w = last_of(s, Cue::kWhere);
  ASSERT_EQ(token(w), "where_up:3m@2") << ::testing::PrintToString(toks(s));
  EXPECT_EQ(clips_for(w), (std::vector<std::string>{"stairs_up", "n3", "metres", "n2", "oclock"}));
  EXPECT_NEAR(cue_pan(w), kMaxPan * 2.f / 3.f, 1e-5);  // heard from its side
  // Straight ahead: "12 o'clock" is said.
  CuePolicy q{FeedbackConfig{}};
  f = approach(0.0, StairKind::kDescending, 3.6f, 1.0);
  f.back() = pressed(f.back(), Press::kShort);
  s = feed(q, f);
  EXPECT_EQ(token(last_of(s, Cue::kWhere)), "where_down:3m@12");
  // Forgotten (unseen 3 s): no stairs, between frames too.
  const auto later = q.between_frames(5.0, {Press::kShort});
  ASSERT_EQ(later.size(), 1u);
  EXPECT_EQ(token(later[0]), "where_none");
}

TEST(FeedbackButton, ShortPressOnAFlightSaysTheStepsLeft) {
  CuePolicy p{FeedbackConfig{}};
  CueInput in = floor_frame(0.0);
  in.traversal.ran = true;
  in.traversal.state = TraversalState::kOnStairs;
  in.traversal.direction = 1;
  in.traversal.steps_left = 4;
  feed(p, {in});
  in.t = kDt;
  const CueEvent w = last_of(feed(p, {pressed(in, Press::kShort)}), Cue::kWhere);
  EXPECT_EQ(token(w), "where:4_left");
  EXPECT_EQ(clips_for(w), (std::vector<std::string>{"n4", "steps_left"}));
  // Steps left not known yet: the way the flight goes, never "no stairs".
  in.t = 2 * kDt;
  in.traversal.steps_left = -1;
  in.traversal.direction = -1;
  const CueEvent u = last_of(feed(p, {pressed(in, Press::kShort)}), Cue::kWhere);
  EXPECT_EQ(token(u), "where_down");
  EXPECT_EQ(clips_for(u), (std::vector<std::string>{"stairs_down"}));
}

// A long press mutes (said and felt) for mute_s: the ascending staircase is not told, the drop
// warning of a descent is; the mute ends on its time with "unmuted" (said and felt), or at once on
// another long press.
TEST(FeedbackButton, LongPressMutesAllButTheDescentsWarnings) {
  FeedbackConfig c;
  c.mute = 20.f;
  CuePolicy p{c};
  auto s = feed(p, {pressed(floor_frame(0.0), Press::kLong)});
  ASSERT_EQ(toks(s), (std::vector<std::string>{"muted:20"})) << "ready is muted too";
  EXPECT_FALSE(haptic_pattern(s[0].e).empty());
  EXPECT_EQ(clips_for(s[0].e), (std::vector<std::string>{"muted"}));
  EXPECT_TRUE(p.muted());
  s = feed(p, approach(1.0, StairKind::kAscending, 3.5f, 2.0));
  EXPECT_EQ(count_of(s, Cue::kStairsAhead), 0) << ::testing::PrintToString(toks(s));
  EXPECT_TRUE(p.camera_lost(3.0).empty());
  EXPECT_TRUE(p.camera_back(3.1).empty());
  s = feed(p, approach(8.0, StairKind::kDescending, 2.0f, 1.8));
  EXPECT_EQ(count_of(s, Cue::kDropWarning), 1) << ::testing::PrintToString(toks(s));
  EXPECT_GE(count_of(s, Cue::kApproach), 1) << "the approach beep sounds through the mute";
  // Between frames: nothing before the time, "unmuted" at it.
  EXPECT_TRUE(p.between_frames(19.9, {}).empty());
  const auto end = p.between_frames(20.0, {});
  ASSERT_EQ(end.size(), 1u);
  EXPECT_EQ(token(end[0]), "unmuted");
  EXPECT_FALSE(haptic_pattern(end[0]).empty());
  EXPECT_FALSE(p.muted());
  // A long press while muted unmutes.
  feed(p, {pressed(floor_frame(21.0), Press::kLong)});
  EXPECT_TRUE(p.muted());
  s = feed(p, {pressed(floor_frame(22.0), Press::kLong)});
  EXPECT_EQ(toks(s), (std::vector<std::string>{"unmuted"}));
  EXPECT_FALSE(p.muted());
}

// The mute ends on its time on a frame too, and a battery cue during it is held back.
TEST(FeedbackButton, MuteEndsOnItsTimeOnAFrame) {
  FeedbackConfig c;
  c.mute = 10.f;
  CuePolicy p{c};
  feed(p, {pressed(floor_frame(0.0), Press::kLong)});
  EXPECT_TRUE(p.battery(5.0, true, 0.10f, false).empty());
  EXPECT_TRUE(feed(p, {floor_frame(9.9)}).empty());
  EXPECT_EQ(toks(feed(p, {floor_frame(10.0)})), (std::vector<std::string>{"unmuted"}));
}

// A double press cycles quiet -> normal -> verbose -> quiet, said at every verbosity, and the new
// verbosity holds (quiet: stairs ahead as an earcon); a reload that leaves the key as it was keeps it.
TEST(FeedbackButton, DoublePressCyclesTheVerbosity) {
  CuePolicy p{FeedbackConfig{}};
  std::vector<std::string> said;
  for (int i = 0; i < 3; ++i)
    for (const auto& x : feed(p, {pressed(floor_frame(i * 1.0), Press::kDouble)}))
      if (x.e.cue == Cue::kVerbosity) said.push_back(token(x.e) + "=" + clips_for(x.e).front());
  EXPECT_EQ(said, (std::vector<std::string>{"verbosity_verbose=verbose", "verbosity_quiet=quiet",
                                            "verbosity_normal=normal"}));
  feed(p, {pressed(floor_frame(4.0), Press::kDouble), pressed(floor_frame(4.5), Press::kDouble)});
  EXPECT_EQ(p.verbosity(), Verbosity::kQuiet);
  p.reconfigure(FeedbackConfig{});  // verbosity "normal" as before: the button's choice stays
  EXPECT_EQ(p.verbosity(), Verbosity::kQuiet);
  const auto s = feed(p, approach(5.0, StairKind::kAscending, 3.5f, 1.0));
  ASSERT_EQ(count_of(s, Cue::kStairsAhead), 1);
  for (const auto& x : s)
    if (x.e.cue == Cue::kStairsAhead) {
      EXPECT_TRUE(x.e.earcon_only);
    }
  FeedbackConfig v;
  v.verbosity = "verbose";
  p.reconfigure(v);
  EXPECT_EQ(p.verbosity(), Verbosity::kVerbose);
}

// Every clip a cue can name is in the list the sink loads (and tools/make-sounds makes).
TEST(FeedbackButton, AnswersUseKnownClips) {
  const auto& all = all_clip_names();
  auto known = [&](const std::string& n) { return std::find(all.begin(), all.end(), n) != all.end(); };
  for (Cue c : {Cue::kWhere, Cue::kMuted, Cue::kUnmuted, Cue::kVerbosity})
    for (int number : {-1, 0, 1, 2, 4})
      for (StairKind k :
           {StairKind::kNone, StairKind::kAscending, StairKind::kCurb, StairKind::kSingleStep}) {
        CueEvent e;
        e.cue = c;
        e.number = number;
        e.kind = k;
        e.clock = 3;
        for (const auto& clip : clips_for(e)) EXPECT_TRUE(known(clip)) << token(e) << ": " << clip;
        EXPECT_FALSE(clips_for(e).empty()) << token(e);
      }
}

// ---- drop-offs (issue 42 item 4) ----

namespace {

// Walking toward a drop's edge at 1 m/s from `from` metres (bearing `bearing`), for `seconds`.
std::vector<CueInput> drop_walk(double t0, float from, double seconds, float bearing = 0.f) {
  std::vector<CueInput> f;
  for (double t = 0.0; t < seconds; t += kDt) {
    CueInput in = floor_frame(t0 + t);
    in.drop.detected = true;
    in.drop.distance_m = std::max(0.3f, from - static_cast<float>(t));
    in.drop.bearing_rad = bearing;
    f.push_back(in);
  }
  return f;
}

}  // namespace

// "drop ahead", its distance and clock, once, within danger distance: at every verbosity; with
// the approach beep after it, quickening; nothing before the drop is confirmed.
TEST(FeedbackPolicy, DropAheadToldOnceThenBeeps) {
  for (const char* verbosity : {"quiet", "normal"}) {
    FeedbackConfig c;
    c.verbosity = verbosity;
    CuePolicy p(c);
    const auto s = feed(p, drop_walk(0.0, 3.5, 3.2, deg2rad(60.f)));
    std::vector<std::string> said;
    for (const auto& x : s)
      if (x.e.cue == Cue::kDropAhead) said.push_back(token(x.e));
    EXPECT_EQ(said, (std::vector<std::string>{"drop_ahead:2m@2"})) << verbosity;
    for (const auto& x : s)
      if (x.e.cue == Cue::kDropAhead) {
        EXPECT_NEAR(x.t, 1.5, 0.1) << verbosity;  // at 2 m, as the walk crosses danger_distance
        EXPECT_GT(cue_pan(x.e), 0.5f);            // from the right
        EXPECT_EQ(clips_for(x.e),
                  (std::vector<std::string>{"warning", "drop_ahead", "n2", "metres", "n2", "oclock"}));
      }
  }
  // Straight ahead: the beeps quicken as the edge nears (the cone is 35 deg).
  CuePolicy p{FeedbackConfig{}};
  const auto s = feed(p, drop_walk(0.0, 3.0, 2.8));
  const auto b = beeps(s);
  ASSERT_GE(b.size(), 3u);
  for (std::size_t i = 2; i < b.size(); ++i) EXPECT_LE(b[i] - b[i - 1], b[i - 1] - b[i - 2] + kDt + 1e-6);
  EXPECT_EQ(count_of(s, Cue::kDropAhead), 1);
}

// A flicker of the drop stage is never told; a drop forgotten and seen again is told again.
TEST(FeedbackPolicy, DropFlickerSilentAndForgottenToldAgain) {
  FeedbackConfig c;
  CuePolicy p(c);
  std::vector<CueInput> f;
  for (int i = 0; i < 60; ++i) {
    CueInput in = floor_frame(i * kDt);
    in.drop.detected = i % 10 == 0;  // one frame in ten
    in.drop.distance_m = 1.5f;
    f.push_back(in);
  }
  EXPECT_EQ(count_of(feed(p, f), Cue::kDropAhead), 0);
  auto a = drop_walk(2.0, 1.5, 1.0);
  EXPECT_EQ(count_of(feed(p, a), Cue::kDropAhead), 1);
  const std::vector<CueInput> gap = floor_frames(3.0, 3.0 + c.forget_time + 1.0);
  feed(p, gap);
  EXPECT_EQ(count_of(feed(p, drop_walk(gap.back().t + kDt, 1.5, 1.0)), Cue::kDropAhead), 1);
}

// A descending staircase is the stair cue's: a drop the stage reports beside a held descent (or
// in the same frames) is not told as a drop.
TEST(FeedbackPolicy, DescentWinsOverADrop) {
  CuePolicy p{FeedbackConfig{}};
  auto f = approach(0.0, StairKind::kDescending, 2.5, 2.0);
  for (auto& in : f) {
    in.drop.detected = true;
    in.drop.distance_m = in.stair.distance_m;
  }
  const auto s = feed(p, f);
  EXPECT_EQ(count_of(s, Cue::kDropAhead), 0);
  EXPECT_EQ(count_of(s, Cue::kDropWarning), 1);
}
