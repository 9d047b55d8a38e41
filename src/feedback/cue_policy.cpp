#include "stairguide/feedback/cue_policy.hpp"

#include <algorithm>
#include <cmath>

namespace stairguide::feedback {

namespace {
constexpr double kNever = -1e9;
bool is_stairs(StairKind k) { return k == StairKind::kAscending || k == StairKind::kDescending; }
bool on_flight(TraversalState s) { return s == TraversalState::kOnStairs || s == TraversalState::kLastStep; }
int metres_of(float d) { return std::isfinite(d) ? std::max(1, static_cast<int>(std::lround(d))) : -1; }
}  // namespace

Verbosity parse_verbosity(const std::string& s) {
  if (s == "quiet") return Verbosity::kQuiet;
  if (s == "verbose") return Verbosity::kVerbose;
  return Verbosity::kNormal;
}

int clock_position(float bearing_rad) {
  if (!std::isfinite(bearing_rad)) return 12;
  const int h = static_cast<int>(std::lround(bearing_rad / (M_PI / 6.0)));
  const int c = ((h % 12) + 12) % 12;
  return c == 0 ? 12 : c;
}

CuePolicy::CuePolicy(const FeedbackConfig& config)
    : cfg_(config), verbosity_(parse_verbosity(config.verbosity)) {
  std::fill(std::begin(last_t_), std::end(last_t_), kNever);
}

void CuePolicy::reconfigure(const FeedbackConfig& config) {
  // The verbosity the button chose is kept unless the reload changes the key itself.
  if (config.verbosity != cfg_.verbosity) verbosity_ = parse_verbosity(config.verbosity);
  cfg_ = config;
}

int CuePolicy::key_of(StairKind kind, int direction) {
  if (direction == 0) direction = kind == StairKind::kDescending ? -1 : 1;
  return (is_stairs(kind) ? 1 : 2) * (direction > 0 ? 1 : -1);
}

bool CuePolicy::allowed(Cue c) const {
  if (verbosity_ != Verbosity::kQuiet) return true;
  switch (c) {
    case Cue::kReady:
    case Cue::kCameraLost:
    case Cue::kCameraBack:
    case Cue::kBlind:
    case Cue::kDropWarning:
    case Cue::kDropAhead:
    case Cue::kApproach:
    case Cue::kBatteryLow:
    case Cue::kBatteryCritical:
    case Cue::kSlow:
    case Cue::kLastStep:
    case Cue::kStairsAhead:  // as an earcon
    case Cue::kStepAhead:
    case Cue::kWhere:  // the answers to the button
    case Cue::kMuted:
    case Cue::kUnmuted:
    case Cue::kVerbosity: return true;
    default: return false;
  }
}

bool CuePolicy::rate_ok(Cue c, double t) const {
  const double last = last_t_[static_cast<int>(c)];
  switch (c) {
    case Cue::kDropWarning:  // always warns (told once per staircase by the caller)
    case Cue::kDropAhead:    // ... once per drop held
    case Cue::kCameraLost:
    case Cue::kCameraBack:
    case Cue::kReady:
    case Cue::kCount:
    case Cue::kApproach:    // its own rhythm (approach_cues)
    case Cue::kBatteryLow:  // their own repeats (battery(), step())
    case Cue::kBatteryCritical:
    case Cue::kSlow:
    case Cue::kWhere:  // asked for
    case Cue::kMuted:
    case Cue::kUnmuted:
    case Cue::kVerbosity: return true;
    case Cue::kTick: return t - last >= cfg_.min_tick_interval;
    case Cue::kBlind: return t - last >= cfg_.blind_repeat;
    default: return t - last >= cfg_.min_cue_interval;
  }
}

void CuePolicy::emit(std::vector<CueEvent>& out, CueEvent e, double t) {
  e.priority = cue_priority(e.cue);
  last_t_[static_cast<int>(e.cue)] = t;
  out.push_back(e);
}

CueEvent CuePolicy::ahead_event(const Sighting& s, bool drop) const {
  CueEvent e;
  const bool stairs = is_stairs(s.kind);
  e.cue = drop ? Cue::kDropWarning : stairs ? Cue::kStairsAhead : Cue::kStepAhead;
  e.kind = s.kind;
  e.direction = key_of(s.kind, s.direction) > 0 ? 1 : -1;
  if (stairs) {
    e.number = metres_of(s.distance_m);
    const int c = clock_position(s.bearing_rad);
    e.clock = c == 12 && verbosity_ != Verbosity::kVerbose ? 0 : c;
  }
  e.earcon_only = verbosity_ == Verbosity::kQuiet && !drop;
  e.bearing_rad = s.bearing_rad;
  return e;
}

float CuePolicy::approach_interval(float d) const {
  const float far = cfg_.approach_interval_far, near = cfg_.approach_interval_near;
  if (d >= cfg_.approach_range) return far;
  if (d <= cfg_.approach_near) return near;
  return near + (far - near) * (d - cfg_.approach_near) / (cfg_.approach_range - cfg_.approach_near);
}

void CuePolicy::approach_cues(const Sighting& s, const DropSummary& drop, const TraversalResult& tr, double t,
                              std::vector<CueEvent>& out) {
  const bool stepped_on = tr.ran && (on_flight(tr.state) || tr.state == TraversalState::kArrived);
  const bool descent_held = told_.active && told_.key == -1;
  const bool drop_held = drop_.active && !descent_held;
  if (cfg_.approach_range <= 0.f || stepped_on || !(descent_held || drop_held)) {
    approach_ = Approach{};
    return;
  }
  // A frame without a sighting of it (a dropout) neither beeps nor ends the approach: it ends
  // when the staircase (or the drop) is forgotten (above).
  if (descent_held) {
    if (!s.present || key_of(s.kind, s.direction) != -1 || !std::isfinite(s.distance_m)) return;
    approach_beat(s.distance_m, s.bearing_rad, t, out);
  } else if (drop.detected && std::isfinite(drop.distance_m)) {
    approach_beat(drop.distance_m, drop.bearing_rad, t, out);
  }
}

void CuePolicy::approach_beat(float d, float bearing, double t, std::vector<CueEvent>& out) {
  constexpr float kNearer = 0.15f;       // m the wearer must come nearer to count as walking on
  constexpr float kRangeMargin = 0.25f;  // m beyond the range before a beeping approach stops
  Approach& a = approach_;
  const bool ahead = !std::isfinite(bearing) || std::fabs(bearing) <= cfg_.approach_cone;
  if (!ahead) {
    a = Approach{};  // turned away: facing it again starts a new approach
    return;
  }
  // The median of the last 5 distances (a reading or two off by noise is not a step).
  a.recent[a.n_recent % 5] = d;
  ++a.n_recent;
  float m[5];
  const int n = std::min(a.n_recent, 5);
  std::copy(a.recent, a.recent + n, m);
  std::nth_element(m, m + n / 2, m + n);
  const float filtered = m[n / 2];
  // In range from approach_range in, out again beyond it by a margin (no on-off at the border).
  if (filtered > cfg_.approach_range + (a.on ? kRangeMargin : 0.f)) {
    a.on = false;
    return;
  }
  if (!a.on) {
    a.on = true;
    a.nearest = filtered;
    a.ref_d = d;
    a.ref_t = t;
  }
  if (d < a.ref_d - kNearer) {
    a.ref_d = d;
    a.ref_t = t;
  }
  a.nearest = std::min(a.nearest, filtered);
  if (t - a.ref_t > cfg_.approach_stall) return;  // stopped: silent until walking on
  // The drop warnings are beats of their own (a beep over their alarm would blur both): the next
  // beep keeps the interval from them.
  a.last_beep_t = std::max({a.last_beep_t, last_t_[static_cast<int>(Cue::kDropWarning)],
                            last_t_[static_cast<int>(Cue::kDropAhead)]});
  if (t - a.last_beep_t + 1e-6 < approach_interval(a.nearest)) return;
  a.last_beep_t = t;
  CueEvent e;
  e.cue = Cue::kApproach;
  e.direction = -1;
  e.kind = StairKind::kDescending;
  e.bearing_rad = bearing;
  e.distance_m = a.nearest;
  emit(out, e, t);
}

// A drop-off is confirmed as a staircase is, held until unseen for forget_time, and told once while
// held when within danger_distance; never while a descent is held or seen (the stair cue wins).
void CuePolicy::drop_cues(const DropSummary& drop, bool descent, double t, std::vector<CueEvent>& out) {
  DropHold& h = drop_;
  if (h.active && t - h.last_seen_t > cfg_.forget_time) h = DropHold{};
  if (!drop.detected) {
    if (!h.active && t - h.last_t > cfg_.confirm_time) h.frames = 0;
    return;
  }
  if (!h.active) {
    if (h.frames > 0 && t - h.last_t > cfg_.confirm_time) h.frames = 0;  // a gap: start again
    if (h.frames == 0) h.first_t = t;
    ++h.frames;
    h.last_t = t;
    if (h.frames < cfg_.confirm_frames || t - h.first_t < cfg_.confirm_time - 1e-6) return;
    h.active = true;
  }
  h.last_seen_t = t;
  const bool near = !std::isfinite(drop.distance_m) || drop.distance_m <= cfg_.danger_distance;
  if (h.warned || !near || descent) return;
  CueEvent e;
  e.cue = Cue::kDropAhead;
  e.direction = -1;
  e.number = metres_of(drop.distance_m);
  const int c = clock_position(drop.bearing_rad);
  e.clock = c == 12 && verbosity_ != Verbosity::kVerbose ? 0 : c;
  e.bearing_rad = drop.bearing_rad;
  emit(out, e, t);
  h.warned = true;
}

void CuePolicy::detection_cues(const Sighting& s, double t, std::vector<CueEvent>& out) {
  if (told_.active && t - told_.last_seen_t > cfg_.forget_time) told_.active = false;
  if (cand_.active && t - cand_.last_t > cfg_.confirm_time) cand_.active = false;
  if (!s.present) return;
  const int key = key_of(s.kind, s.direction);
  if (told_.active && key == told_.key) {
    told_.last_seen_t = t;
  } else {
    if (cand_.active && cand_.key == key) {
      ++cand_.frames;
      cand_.last_t = t;
    } else {
      cand_ = Candidate{true, key, 1, t, t};
    }
    if (cand_.frames < cfg_.confirm_frames || t - cand_.first_t < cfg_.confirm_time - 1e-6) return;
    // Confirmed. The same staircase re-found soon after it was forgotten is not told again.
    const bool told_recently = key == told_.key && t - told_.told_t < cfg_.repeat_time;
    if (!told_recently) {
      told_ = Told{};
      told_.key = key;
    }
    // A drop ahead is warned of again once it has been out of mind (forgotten) and comes back.
    told_.warned = false;
    told_.active = true;
    told_.last_seen_t = t;
    cand_.active = false;
  }
  const int metres = metres_of(s.distance_m);
  const bool drop = key == -1 && (!std::isfinite(s.distance_m) || s.distance_m <= cfg_.danger_distance);
  if (drop) {
    if (!told_.warned) {
      emit(out, ahead_event(s, true), t);
      told_.warned = told_.announced = true;
      told_.told_t = t;
      told_.last_metres = metres;
    }
    return;
  }
  const bool near = !std::isfinite(s.distance_m) || s.distance_m <= cfg_.announce_distance;
  if (!near) return;
  const CueEvent e = ahead_event(s, false);
  if (!told_.announced) {
    if (!allowed(e.cue) || !rate_ok(e.cue, t)) return;
    emit(out, e, t);
    told_.announced = true;
    told_.told_t = t;
    told_.last_metres = metres;
  } else if (verbosity_ == Verbosity::kVerbose && e.cue == Cue::kStairsAhead && metres >= 1 &&
             told_.last_metres > metres && rate_ok(e.cue, t)) {
    emit(out, e, t);  // the distance as it shrinks, a metre at a time
    told_.last_metres = metres;
  }
}

void CuePolicy::flight_cues(const TraversalResult& tr, double t, std::vector<CueEvent>& out) {
  const TraversalState st = tr.state;
  auto give = [&](Cue c, int number, bool rate_limited) {
    if (!allowed(c) || (rate_limited && !rate_ok(c, t))) return false;
    CueEvent e;
    e.cue = c;
    e.number = number;
    e.direction = tr.direction;
    emit(out, e, t);
    return true;
  };
  const bool now_on = on_flight(st), was_on = on_flight(prev_state_);
  if (now_on && !was_on) {
    // On the flight: what was told of the approach is done with (and not told again soon).
    told_.active = false;
    told_.told_t = t;
    cand_.active = false;
    steps_left_told_ = false;
    prev_climbed_ = tr.steps_climbed;
    if (st == TraversalState::kLastStep)
      give(Cue::kLastStep, -1, false);
    else
      give(Cue::kFirstStep, -1, true);
    if (tr.steps_left >= 2 && give(Cue::kStepsLeft, tr.steps_left, false)) steps_left_told_ = true;
  } else if (now_on) {
    if (st == TraversalState::kLastStep && prev_state_ != TraversalState::kLastStep) {
      give(Cue::kLastStep, -1, true);  // a warning: no tick on this frame
    } else if (tr.steps_climbed > prev_climbed_) {
      const int n = tr.steps_climbed;
      if (n % cfg_.count_interval == 0) {
        if (verbosity_ == Verbosity::kVerbose && tr.steps_left >= 1)
          give(Cue::kStepsLeft, tr.steps_left, false);
        else
          give(Cue::kCount, n, false);
      } else if (t - last_tick_t_ >= cfg_.min_tick_interval && give(Cue::kTick, -1, false)) {
        last_tick_t_ = t;
      }
    }
    if (!steps_left_told_ && tr.steps_left >= 2 && give(Cue::kStepsLeft, tr.steps_left, true))
      steps_left_told_ = true;
  }
  if (now_on) prev_climbed_ = std::max(prev_climbed_, tr.steps_climbed);
  if (st == TraversalState::kArrived && prev_state_ != TraversalState::kArrived)
    give(Cue::kEndOfStairs, -1, true);
  prev_state_ = st;
}

void CuePolicy::blind_cues(const CueInput& in, double t, std::vector<CueEvent>& out) {
  const bool tracking = in.traversal.ran && in.traversal.state != TraversalState::kSearching;
  if (in.floor_found || in.stair.detected || in.drop.detected || tracking) {
    blind_since_ = -1.0;
    return;
  }
  if (blind_since_ < 0) blind_since_ = t;
  if (t - blind_since_ >= cfg_.blind_after && t - last_blind_t_ >= cfg_.blind_repeat) {
    CueEvent e;
    e.cue = Cue::kBlind;
    emit(out, e, t);
    last_blind_t_ = t;
  }
}

std::vector<CueEvent> CuePolicy::step(const CueInput& in) {
  std::vector<CueEvent> out;
  const double t = in.t;
  if (t + 1.0 < last_frame_t_) {
    // The clock went back (a reopened camera restarts its timestamps): start afresh.
    cand_ = Candidate{};
    told_ = Told{};
    std::fill(std::begin(last_t_), std::end(last_t_), kNever);
    last_tick_t_ = last_blind_t_ = kNever;
    blind_since_ = -1.0;
    slow_since_ = -1.0;
    approach_ = Approach{};
    if (mute_until_ >= 0.0)
      mute_until_ = t + std::max(0.0, mute_until_ - last_frame_t_);  // what was left of it
    drop_ = DropHold{};
  }
  last_frame_t_ = t;
  if (!ready_told_) {
    ready_told_ = true;
    CueEvent e;
    e.cue = Cue::kReady;
    emit(out, e, t);
  }
  const TraversalResult& tr = in.traversal;
  Sighting s;
  if (tr.ran && tr.state == TraversalState::kStairAhead && tr.kind != StairKind::kNone) {
    s = Sighting{true, tr.kind, tr.direction, tr.distance_m, tr.bearing_rad};
  } else if (in.stair.detected &&
             !(tr.ran && (on_flight(tr.state) || tr.state == TraversalState::kArrived))) {
    s = Sighting{true, in.stair.kind, in.stair.direction, in.stair.distance_m, in.stair.bearing_rad};
  }
  if (s.present && s.kind == StairKind::kNone) s.present = false;
  detection_cues(s, t, out);
  if (s.present && told_.active && key_of(s.kind, s.direction) == told_.key) held_ = s;
  if (tr.ran) {
    flight_left_ = tr.steps_left;
    flight_dir_ = tr.direction;
  }
  const bool descent = (told_.active && told_.key < 0) || (s.present && key_of(s.kind, s.direction) < 0);
  drop_cues(in.drop, descent, t, out);
  approach_cues(s, in.drop, tr, t, out);
  if (tr.ran) flight_cues(tr, t, out);
  blind_cues(in, t, out);
  // Perception behind the camera for long enough that what is told comes late.
  if (in.lag_s > cfg_.slow_lag) {
    if (slow_since_ < 0) slow_since_ = t;
    if (t - slow_since_ >= cfg_.slow_after && t - last_t_[static_cast<int>(Cue::kSlow)] >= cfg_.slow_repeat) {
      CueEvent e;
      e.cue = Cue::kSlow;
      emit(out, e, t);
    }
  } else if (in.lag_s < 0.5 * cfg_.slow_lag) {
    slow_since_ = -1.0;
    last_t_[static_cast<int>(Cue::kSlow)] = kNever;  // over: the next fall behind is told at once
  }
  button_cues(in.presses, t, out);
  mute_filter(out, t);
  by_priority(out);
  return out;
}

void CuePolicy::by_priority(std::vector<CueEvent>& out) {
  std::stable_sort(out.begin(), out.end(),
                   [](const CueEvent& a, const CueEvent& b) { return a.priority > b.priority; });
}

// ---------------------------------------------------------------- the button

void CuePolicy::mute_filter(std::vector<CueEvent>& out, double t) {
  if (mute_until_ < 0.0) return;
  if (t >= mute_until_) {  // its time is up: told, and nothing of this moment is held back
    mute_until_ = -1.0;
    CueEvent e;
    e.cue = Cue::kUnmuted;
    emit(out, e, t);
    return;
  }
  // A descent's or a drop's warnings are never muted (the wearer may be walking towards the edge),
  // nor the answers to the button (asked for).
  out.erase(std::remove_if(out.begin(), out.end(),
                           [](const CueEvent& e) {
                             switch (e.cue) {
                               case Cue::kDropWarning:
                               case Cue::kDropAhead:
                               case Cue::kApproach:
                               case Cue::kWhere:
                               case Cue::kMuted:
                               case Cue::kUnmuted:
                               case Cue::kVerbosity: return false;
                               default: return true;
                             }
                           }),
            out.end());
}

CueEvent CuePolicy::where_event(double t) const {
  CueEvent e;
  e.cue = Cue::kWhere;
  if (on_flight(prev_state_)) {  // the staircase is under the feet: how much of it is left
    e.direction = flight_dir_ < 0 ? -1 : 1;
    if (flight_left_ >= 1)
      e.number = flight_left_;
    else  // not known yet: which way the stairs go on
      e.kind = e.direction > 0 ? StairKind::kAscending : StairKind::kDescending;
    return e;
  }
  const bool held = told_.active && t - told_.last_seen_t <= cfg_.forget_time && held_.present;
  if (!held) return e;  // "no stairs"
  e.kind = held_.kind;
  e.direction = key_of(held_.kind, held_.direction) > 0 ? 1 : -1;
  e.number = metres_of(held_.distance_m);
  e.clock = clock_position(held_.bearing_rad);
  e.bearing_rad = held_.bearing_rad;
  return e;
}

void CuePolicy::button_cues(const std::vector<Press>& presses, double t, std::vector<CueEvent>& out) {
  for (const Press p : presses) {
    CueEvent e;
    switch (p) {
      case Press::kShort: e = where_event(t); break;
      case Press::kLong:
        if (mute_until_ >= 0.0) {
          mute_until_ = -1.0;
          e.cue = Cue::kUnmuted;
        } else {
          mute_until_ = t + cfg_.mute;
          e.cue = Cue::kMuted;
          e.number = static_cast<int>(std::lround(cfg_.mute));
        }
        break;
      case Press::kDouble:
        verbosity_ = verbosity_ == Verbosity::kQuiet    ? Verbosity::kNormal
                     : verbosity_ == Verbosity::kNormal ? Verbosity::kVerbose
                                                        : Verbosity::kQuiet;
        e.cue = Cue::kVerbosity;
        e.number = static_cast<int>(verbosity_);
        break;
    }
    emit(out, e, t);
  }
}

std::vector<CueEvent> CuePolicy::between_frames(double t, const std::vector<Press>& presses) {
  std::vector<CueEvent> out;
  button_cues(presses, t, out);
  mute_filter(out, t);
  by_priority(out);
  return out;
}

std::vector<CueEvent> CuePolicy::battery(double t, bool present, float charge, bool charging) {
  std::vector<CueEvent> out;
  if (!present || charging || charge > cfg_.battery_low + 0.03f) {
    battery_told_ = 0;
    return out;
  }
  const int level = charge <= cfg_.battery_critical ? 2 : charge <= cfg_.battery_low ? 1 : 0;
  if (level == 0) return out;  // within the 3 points above the mark: as it was
  const Cue c = level == 2 ? Cue::kBatteryCritical : Cue::kBatteryLow;
  const double repeat = level == 2 ? cfg_.battery_critical_repeat : cfg_.battery_repeat;
  if (level > battery_told_ || t - last_t_[static_cast<int>(c)] >= repeat) {
    CueEvent e;
    e.cue = c;
    e.number = static_cast<int>(std::lround(charge * 100.f));
    emit(out, e, t);
    battery_told_ = std::max(battery_told_, level);
  }
  mute_filter(out, t);
  return out;
}

std::vector<CueEvent> CuePolicy::camera_lost(double t) {
  std::vector<CueEvent> out;
  if (camera_down_) return out;
  camera_down_ = true;
  blind_since_ = -1.0;
  CueEvent e;
  e.cue = Cue::kCameraLost;
  emit(out, e, t);
  mute_filter(out, t);
  return out;
}

std::vector<CueEvent> CuePolicy::camera_back(double t) {
  std::vector<CueEvent> out;
  if (!camera_down_) return out;
  camera_down_ = false;
  CueEvent e;
  e.cue = Cue::kCameraBack;
  emit(out, e, t);
  mute_filter(out, t);
  return out;
}

}  // namespace stairguide::feedback
