#pragma once
/// \file cue.hpp
/// What the user is told: one `CueEvent` per thing said (and felt), with its priority, and how
/// each is spoken (the WAV clips, in order) and buzzed (the haptic pattern, haptic.hpp).

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "stairguide/core/ground_truth.hpp"

namespace stairguide::feedback {

enum class Cue {
  kReady,            ///< the pipeline is running
  kCameraLost,       ///< the camera stopped sending
  kCameraBack,       ///< the camera is back
  kBlind,            ///< frames come, but neither floor nor stair is seen: "cannot see"
  kStairsAhead,      ///< a staircase ahead, `direction`, `number` metres (-1 unknown), `clock`
  kDropWarning,      ///< a descending staircase near (or of unknown distance): always told
  kStepAhead,        ///< a single step or a curb ahead (`kind`), `direction`
  kFirstStep,        ///< on the first step of a flight
  kTick,             ///< one more step climbed or descended
  kCount,            ///< steps so far on the flight (`number`), said every count_interval steps
  kStepsLeft,        ///< steps still to go (`number`)
  kLastStep,         ///< the next step (or the one underfoot) is the last
  kEndOfStairs,      ///< off the flight, on the new floor
  kApproach,         ///< the approach beep: a descending first edge within approach range, repeated
                     ///< faster as it nears (`distance_m`)
  kBatteryLow,       ///< the laptop's battery is low (`number`: percent), not charging
  kBatteryCritical,  ///< ... critically low: the daemon will soon stop
  kSlow,             ///< perception has fallen behind the camera for long enough to matter
  // Answers to the wearer's button (button.hpp):
  kWhere,      ///< short press: the nearest known staircase (`kind`, `direction`, `number` metres,
               ///< `clock`), steps left on a flight (`number`; not known: the flight's `kind`
               ///< and `direction`), or none known (`kind` kNone, `number` -1)
  kMuted,      ///< long press: the cues are muted for `number` s (a descent still warns)
  kUnmuted,    ///< the mute is over (its time, or another long press)
  kVerbosity,  ///< double press: the verbosity is now `number` (0 quiet, 1 normal, 2 verbose)
  kDropAhead,  ///< a drop-off (platform edge, dock, hole) near, `number` metres, `clock`: always told
};

/// Number of Cue values (for tables indexed by cue).
constexpr int kCueKinds = static_cast<int>(Cue::kDropAhead) + 1;

/// Whether the cue marks a step of a flight (first step, tick, count, steps left, last step, end
/// of stairs): its moment passes with the next step, after which it must not be heard.
bool marks_a_step(Cue c);

/// "ready", "camera_lost", "camera_back", "blind", "stairs_ahead", "drop_warning", "step_ahead",
/// "first_step", "tick", "count", "steps_left", "last_step", "end_of_stairs", "approach",
/// "battery_low", "battery_critical", "slow", "where", "muted", "unmuted", "verbosity", "drop_ahead".
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
  /// rad, bearing of the staircase the cue is about (positive to the right); NaN: not placed
  /// (system cues, and the flight's cues: the staircase is under the feet).
  float bearing_rad = std::numeric_limits<float>::quiet_NaN();
  /// m, the distance to the first edge or the drop's edge (kApproach); NaN otherwise.
  float distance_m = std::numeric_limits<float>::quiet_NaN();
};

/// How a cue is heard against what already sounds (audio_sink.hpp's deliveries):
/// - kEarcon (tick, approach beep): mixed over whatever sounds, at once;
/// - kStepPhrase (first step, count, steps left, last step, end of stairs): said at once, cutting
///   the phrase speaking, and making stale the older step and "ahead" phrases (its step has come);
///   when a phrase that outranks it is speaking (camera lost, cannot see) a tick marks the step;
/// - kPhrase (the rest): waits its turn by priority; a higher one cuts a lower one.
enum class CueSound { kPhrase, kStepPhrase, kEarcon };
CueSound cue_sound(Cue c);
/// The cue as a bit (for the sink's `kinds` and `supersedes` sets).
inline std::uint32_t cue_bit(Cue c) { return 1u << static_cast<unsigned>(c); }
/// The cues a cue makes stale when it is given (a bit set): for a step phrase, every older step
/// phrase and what was said of the staircase ahead; none for the others.
std::uint32_t cue_supersedes(Cue c);
/// Where the cue is placed between the ears: -1 left .. +1 right, from its bearing (0 for NaN).
/// Linear in the bearing up to kMaxPan at +-90 deg (3 and 9 o'clock) and beyond: never all in
/// one ear, so that a wearer who hears on one side only (or wears one earpiece) still hears it.
float cue_pan(const CueEvent& e);
constexpr float kMaxPan = 0.8f;

/// The cue as one token for the frame lines, e.g. "stairs_ahead_up:3m@2", "count:5", "tick".
std::string token(const CueEvent& e);
/// Several cues of one frame: their tokens joined by '+'; empty for none.
std::string tokens(const std::vector<CueEvent>& events);

/// The WAV clips (names without ".wav") that speak `e`, in order.
std::vector<std::string> clips_for(const CueEvent& e);
/// Every clip the cues can use (what tools/make-sounds makes and the sink preloads).
const std::vector<std::string>& all_clip_names();
/// Of them, the earcons (no words: one set for every language, in sounds_dir itself).
bool is_earcon_clip(const std::string& name);

}  // namespace stairguide::feedback
