#pragma once
/// \file frame_clock.hpp
/// Frame timestamps the pipeline can trust. A source's clock is taken as long as it behaves: a
/// finite time that increases by at most `max_gap_s` from one frame to the next. A frame whose
/// timestamp is not a finite time (NaN, 1e300), does not increase (equal, reversed, a clock that
/// jumps back) or leaps forward more than the bound is given the previous frame's time plus one
/// step instead: the time that passed on the wall clock for a live camera, one nominal frame period
/// (1 / capture.fps) for a replay. The frames after it keep their own spacing from there, so the
/// output is strictly increasing and a single bad frame (or one jump) shifts nothing else.
///
/// The odometry's motion prior, the traversal tracker and the cue policy all work on differences
/// of these times: an equal pair made the odometry fail, a jump back counted steps wrongly and
/// 1e300 silenced the cues (issue 41). Pure: the runtime logs what `next()` reports.

#include <cstdint>
#include <string>

namespace stairguide::runtime {

/// What became of one frame's timestamp.
struct FrameTime {
  double t = 0.0;         ///< the time to use (s), strictly above the previous frame's
  bool replaced = false;  ///< `t` is not the source's timestamp plus the running offset
  std::string why;        ///< when replaced: what was wrong ("goes back 5 s", "is not finite")
};

class FrameClock {
 public:
  /// `nominal_period_s`: one frame at the source's nominal rate; `max_gap_s`: the largest forward
  /// step taken as real (a recording with a longer pause, or a stalled camera, restarts the count
  /// from one step after the previous frame).
  explicit FrameClock(double nominal_period_s, double max_gap_s = 2.0);

  /// `raw`: the source's timestamp (s); `wall_step_s`: for a live camera, the wall-clock time since
  /// the previous frame was read (<= 0: unknown, as in a replay as fast as possible).
  FrameTime next(double raw, double wall_step_s = -1.0);

  /// Frames whose timestamp was replaced so far.
  std::uint64_t replaced() const { return replaced_; }

  /// Timestamps of larger magnitude are not a time (about 3000 years in seconds; a Unix time or a
  /// device's microseconds since power-on, in seconds, are far below it).
  static constexpr double kMaxAbs = 1e11;

 private:
  double period_, max_gap_;
  bool have_ = false;      // a frame was given out
  bool have_raw_ = false;  // last_raw_ holds a finite, plausible source time
  double last_out_ = 0.0, last_raw_ = 0.0, offset_ = 0.0;
  std::uint64_t replaced_ = 0;
};

}  // namespace stairguide::runtime
