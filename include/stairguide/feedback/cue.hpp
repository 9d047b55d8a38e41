#pragma once
/// \file cue.hpp
/// What the user is told: one `CueEvent` per thing said (and felt), with its priority, and how
/// each is spoken (the WAV clips, in order) and buzzed (the haptic pattern, haptic.hpp).

#include <string>
#include <vector>

#include "stairguide/core/ground_truth.hpp"

namespace stairguide::feedback {

enum class Cue {
  kReady,        ///< the pipeline is running
  kCameraLost,   ///< the camera stopped sending
  kCameraBack,   ///< the camera is back
  kBlind,        ///< frames come, but neither floor nor stair is seen: "cannot see"
  kStairsAhead,  ///< a staircase ahead, `direction`, `number` metres (-1 unknown), `clock`
  kDropWarning,  ///< a descending staircase near (or of unknown distance): always told
  kStepAhead,    ///< a single step or a curb ahead (`kind`), `direction`
  kFirstStep,    ///< on the first step of a flight
  kTick,         ///< one more step climbed or descended
  kCount,        ///< steps so far on the flight (`number`), said every count_interval steps
  kStepsLeft,    ///< steps still to go (`number`)
  kLastStep,     ///< the next step (or the one underfoot) is the last
  kEndOfStairs,  ///< off the flight, on the new floor
};

/// Number of Cue values (for tables indexed by cue).
constexpr int kCueKinds = static_cast<int>(Cue::kEndOfStairs) + 1;

/// Whether the cue marks a step of a flight (first step, tick, count, steps left, last step, end
/// of stairs): its moment passes with the next step, after which it must not be heard.
bool marks_a_step(Cue c);

/// "ready", "camera_lost", "camera_back", "blind", "stairs_ahead", "drop_warning", "step_ahead",
/// "first_step", "tick", "count", "steps_left", "last_step", "end_of_stairs".
const char* to_string(Cue c);

/// Higher interrupts lower: a warning cuts a tick. Fixed per cue (see cue.cpp for the order).
int cue_priority(Cue c);

struct CueEvent {
  Cue cue = Cue::kReady;
  int priority = 0;                   ///< cue_priority(cue)
  int direction = 0;                  ///< +1 up, -1 down (stairs, steps), else 0
  StairKind kind = StairKind::kNone;  ///< kSingleStep or kCurb for kStepAhead
  int number = -1;                    ///< metres, count or steps left; -1 when not said
  int clock = 0;                      ///< clock position 1..12 of the stairs, 0 when not said
  bool earcon_only = false;           ///< quiet verbosity: the earcon instead of the words
};

/// The cue as one token for the frame lines, e.g. "stairs_ahead_up:3m@2", "count:5", "tick".
std::string token(const CueEvent& e);
/// Several cues of one frame: their tokens joined by '+'; empty for none.
std::string tokens(const std::vector<CueEvent>& events);

/// The WAV clips (names without ".wav") that speak `e`, in order.
std::vector<std::string> clips_for(const CueEvent& e);
/// Every clip the cues can use (what tools/make-sounds makes and the sink preloads).
const std::vector<std::string>& all_clip_names();

}  // namespace stairguide::feedback
