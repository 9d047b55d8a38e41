#include "stairguide/runtime/frame_clock.hpp"

#include <cmath>
#include <cstdio>

namespace stairguide::runtime {

namespace {
std::string seconds(double s) {
  char b[48];
  std::snprintf(b, sizeof b, "%.3f s", s);
  return b;
}
}  // namespace

FrameClock::FrameClock(double nominal_period_s, double max_gap_s)
    : period_(std::isfinite(nominal_period_s) && nominal_period_s > 0 ? nominal_period_s : 1.0 / 30.0),
      max_gap_(std::isfinite(max_gap_s) && max_gap_s > 0 ? max_gap_s : 2.0) {}

FrameTime FrameClock::next(double raw, double wall_step_s) {
  const bool plausible = std::isfinite(raw) && std::abs(raw) <= kMaxAbs;
  FrameTime out;
  if (!plausible) {
    out.why = std::isfinite(raw) ? "is not a time (beyond 1e11 s)" : "is not a finite number";
  } else if (have_raw_) {
    const double d = raw - last_raw_;
    const bool wall_known = wall_step_s > 0 && std::isfinite(wall_step_s);
    if (d == 0.0) {
      out.why = "equals the previous frame's";
    } else if (d < 0.0) {
      out.why = "goes back " + seconds(-d);
    } else if (d > max_gap_ && !(wall_known && std::abs(d - wall_step_s) <= 0.5)) {
      // A live camera that really stalled for that long is believed: the wall clock agrees.
      out.why = "jumps " + seconds(d) + " forward (more than " + seconds(max_gap_) + ")";
    }
  } else if (have_) {
    out.why = "follows frames without a usable time";
  }
  if (!have_) {
    // The first frame sets the clock (0 when it has no usable time of its own).
    out.t = plausible ? raw : 0.0;
    out.replaced = !plausible;
  } else if (out.why.empty()) {
    out.t = raw + offset_;
  } else {
    const double step = wall_step_s > 0 && std::isfinite(wall_step_s) ? wall_step_s : period_;
    out.t = last_out_ + step;
    out.replaced = true;
  }
  if (have_ && !(out.t > last_out_)) {
    // raw + offset may round onto the previous time when two frames are a few ns apart.
    out.t = std::nextafter(last_out_, INFINITY);
  }
  if (plausible) {
    offset_ = out.t - raw;  // the frames after this one keep their spacing from here
    last_raw_ = raw;
    have_raw_ = true;
  }
  have_ = true;
  last_out_ = out.t;
  if (out.replaced) ++replaced_;
  return out;
}

}  // namespace stairguide::runtime
