#include "stairguide/feedback/cue.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace stairguide::feedback {

namespace {
constexpr int kMaxNumber = 30;  // numbers n1..n30 are recorded
std::string number_clip(int n) { return "n" + std::to_string(n); }
bool sayable(int n) { return n >= 1 && n <= kMaxNumber; }
}  // namespace

const char* to_string(Cue c) {
  switch (c) {
    case Cue::kReady: return "ready";
    case Cue::kCameraLost: return "camera_lost";
    case Cue::kCameraBack: return "camera_back";
    case Cue::kBlind: return "blind";
    case Cue::kStairsAhead: return "stairs_ahead";
    case Cue::kDropWarning: return "drop_warning";
    case Cue::kStepAhead: return "step_ahead";
    case Cue::kFirstStep: return "first_step";
    case Cue::kTick: return "tick";
    case Cue::kCount: return "count";
    case Cue::kStepsLeft: return "steps_left";
    case Cue::kLastStep: return "last_step";
    case Cue::kEndOfStairs: return "end_of_stairs";
    case Cue::kApproach: return "approach";
    case Cue::kBatteryLow: return "battery_low";
    case Cue::kBatteryCritical: return "battery_critical";
    case Cue::kSlow: return "slow";
    case Cue::kWhere: return "where";
    case Cue::kMuted: return "muted";
    case Cue::kUnmuted: return "unmuted";
    case Cue::kVerbosity: return "verbosity";
    case Cue::kDropAhead: return "drop_ahead";
  }
  return "?";
}

bool marks_a_step(Cue c) {
  switch (c) {
    case Cue::kFirstStep:
    case Cue::kTick:
    case Cue::kCount:
    case Cue::kStepsLeft:
    case Cue::kLastStep:
    case Cue::kEndOfStairs: return true;
    default: return false;
  }
}

int cue_priority(Cue c) {
  // Step feedback is the lowest (a newer step makes an old tick stale); what is ahead comes next;
  // the system's own blindness and the last step are warnings; a drop ahead is the highest.
  switch (c) {
    case Cue::kTick: return 1;
    case Cue::kCount: return 2;
    case Cue::kReady: return 3;
    case Cue::kStairsAhead:
    case Cue::kStepAhead:
    case Cue::kFirstStep:
    case Cue::kStepsLeft:
    case Cue::kEndOfStairs:
    case Cue::kCameraBack: return 4;
    case Cue::kApproach:
    case Cue::kSlow:
    // The answers to a press: the wearer asked, and waits for them.
    case Cue::kWhere:
    case Cue::kMuted:
    case Cue::kUnmuted:
    case Cue::kVerbosity: return 5;
    case Cue::kBatteryLow: return 3;
    case Cue::kBatteryCritical: return 7;
    case Cue::kLastStep:
    case Cue::kBlind: return 6;
    case Cue::kCameraLost: return 7;
    case Cue::kDropWarning:
    case Cue::kDropAhead: return 8;
  }
  return 0;
}

CueSound cue_sound(Cue c) {
  if (c == Cue::kTick || c == Cue::kApproach) return CueSound::kEarcon;
  return marks_a_step(c) && c != Cue::kTick ? CueSound::kStepPhrase : CueSound::kPhrase;
}

std::uint32_t cue_supersedes(Cue c) {
  if (cue_sound(c) != CueSound::kStepPhrase) return 0;
  std::uint32_t s = cue_bit(Cue::kStairsAhead) | cue_bit(Cue::kStepAhead) | cue_bit(Cue::kDropWarning);
  for (int k = 0; k < kCueKinds; ++k)
    if (cue_sound(static_cast<Cue>(k)) == CueSound::kStepPhrase) s |= cue_bit(static_cast<Cue>(k));
  return s;
}

float cue_pan(const CueEvent& e) {
  if (!std::isfinite(e.bearing_rad)) return 0.f;
  const float p = e.bearing_rad / static_cast<float>(M_PI / 2.0);
  return std::clamp(p, -1.f, 1.f) * kMaxPan;
}

std::string token(const CueEvent& e) {
  std::string s = to_string(e.cue);
  if (e.cue == Cue::kApproach) {
    s += "_down";
    if (std::isfinite(e.distance_m)) {
      char b[32];
      std::snprintf(b, sizeof b, ":%.2fm", static_cast<double>(e.distance_m));
      s += b;
    }
    return s;
  }
  if (e.cue == Cue::kDropAhead) {
    if (e.number >= 0) s += ":" + std::to_string(e.number) + "m";
    if (e.clock > 0) s += "@" + std::to_string(e.clock);
    return s;
  }
  if (e.cue == Cue::kWhere && e.kind == StairKind::kNone && e.clock == 0) {
    if (e.number >= 0) return s + ":" + std::to_string(e.number) + "_left";  // on a flight
    return s + "_none";
  }
  if (e.cue == Cue::kVerbosity) {
    static const char* level[] = {"_quiet", "_normal", "_verbose"};
    return s + level[std::clamp(e.number, 0, 2)];
  }
  if (e.cue == Cue::kStairsAhead || e.cue == Cue::kStepAhead || e.cue == Cue::kDropWarning ||
      e.cue == Cue::kWhere) {
    if (e.cue == Cue::kStepAhead) s = e.kind == StairKind::kCurb ? "curb" : "step";
    if (e.cue == Cue::kWhere)
      s += e.kind == StairKind::kCurb ? "_curb" : e.kind == StairKind::kSingleStep ? "_step" : "";
    s += e.direction > 0 ? "_up" : "_down";
    if (e.number >= 0) s += ":" + std::to_string(e.number) + "m";
    if (e.clock > 0) s += "@" + std::to_string(e.clock);
  } else if (e.number >= 0) {
    s += ":" + std::to_string(e.number);
  }
  return s;
}

std::string tokens(const std::vector<CueEvent>& events) {
  std::string s;
  for (const auto& e : events) {
    if (!s.empty()) s += '+';
    s += token(e);
  }
  return s;
}

namespace {
// The distance ("3 metres") and, off straight ahead, the clock position ("2 o'clock") a cue carries,
// each when it has one that can be said.
void add_distance_and_clock(const CueEvent& e, std::vector<std::string>& c) {
  if (sayable(e.number)) {
    c.push_back(number_clip(e.number));
    c.push_back(e.number == 1 ? "metre" : "metres");
  }
  if (e.clock >= 1 && e.clock <= 12) {
    c.push_back(number_clip(e.clock));
    c.push_back("oclock");
  }
}

// The answer to "where are the stairs?": what is ahead with its distance and clock position (said
// even at 12: the wearer asked where), the steps left on a flight, or "no stairs".
std::vector<std::string> where_clips(const CueEvent& e) {
  const bool up = e.direction > 0;
  std::vector<std::string> c;
  switch (e.kind) {
    case StairKind::kAscending:
    case StairKind::kDescending: c = {up ? "stairs_up" : "stairs_down"}; break;
    case StairKind::kSingleStep: c = {up ? "step_up" : "step_down"}; break;
    case StairKind::kCurb: c = {up ? "curb_up" : "curb_down"}; break;
    default:
      if (sayable(e.number)) return {number_clip(e.number), "steps_left"};
      return {"no_stairs"};
  }
  add_distance_and_clock(e, c);
  return c;
}
}  // namespace

namespace {
// The clip of a cue said by one clip of its own whatever it carries (named as the cue, but for
// "blind", which says what it means); nullptr for the others.
const char* own_clip(Cue c) {
  switch (c) {
    case Cue::kBlind: return "cannot_see";
    case Cue::kReady:
    case Cue::kCameraLost:
    case Cue::kCameraBack:
    case Cue::kFirstStep:
    case Cue::kTick:
    case Cue::kLastStep:
    case Cue::kEndOfStairs:
    case Cue::kApproach:
    case Cue::kBatteryLow:
    case Cue::kBatteryCritical:
    case Cue::kSlow:
    case Cue::kMuted:
    case Cue::kUnmuted: return to_string(c);
    default: return nullptr;
  }
}
}  // namespace

std::vector<std::string> clips_for(const CueEvent& e) {
  if (const char* own = own_clip(e.cue)) return {own};
  std::vector<std::string> c;
  const bool up = e.direction > 0;
  auto distance = [&] { add_distance_and_clock(e, c); };
  switch (e.cue) {
    case Cue::kStairsAhead:
      if (e.earcon_only) {
        c = {up ? "up" : "down"};
      } else {
        c = {up ? "stairs_up" : "stairs_down"};
        distance();
      }
      break;
    case Cue::kDropWarning:
      c = {"warning", "stairs_down"};
      distance();
      break;
    case Cue::kStepAhead:
      if (e.earcon_only)
        c = {up ? "up" : "down"};
      else if (e.kind == StairKind::kCurb)
        c = {up ? "curb_up" : "curb_down"};
      else
        c = {up ? "step_up" : "step_down"};
      break;
    case Cue::kCount:
      if (sayable(e.number))
        c = {number_clip(e.number)};
      else
        c = {"tick"};
      break;
    case Cue::kStepsLeft:
      if (sayable(e.number)) c = {number_clip(e.number), "steps_left"};
      break;
    case Cue::kWhere: c = where_clips(e); break;
    case Cue::kVerbosity: c = {e.number <= 0 ? "quiet" : e.number == 1 ? "normal" : "verbose"}; break;
    default:  // own_clip's
      break;
    case Cue::kDropAhead:
      c = {"warning", "drop_ahead"};
      distance();
      break;
  }
  return c;
}

const std::vector<std::string>& all_clip_names() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> n = {"ready",         "camera_lost", "camera_back", "cannot_see",
                                  "stairs_up",     "stairs_down", "step_up",     "step_down",
                                  "curb_up",       "curb_down",   "first_step",  "last_step",
                                  "end_of_stairs", "steps_left",  "metre",       "metres",
                                  "oclock",        "tick",        "up",          "down",
                                  "warning",       "approach",    "battery_low", "battery_critical",
                                  "slow",          "no_stairs",   "muted",       "unmuted",
                                  "quiet",         "normal",      "verbose",     "drop_ahead"};
    for (int i = 1; i <= kMaxNumber; ++i) n.push_back(number_clip(i));
    return n;
  }();
  return names;
}

bool is_earcon_clip(const std::string& name) {
  return name == "tick" || name == "approach" || name == "up" || name == "down" || name == "warning";
}

}  // namespace stairguide::feedback
