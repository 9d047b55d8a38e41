#pragma once
/// \file cue_policy.hpp
/// The cue policy (pure: no threads, no I/O, no clock of its own): one frame's typed perception
/// and traversal output plus its time in, the cues to give the user out.
///
/// - Silence when all is well: a cue is given on a change the user must know of, never per frame.
/// - Hysteresis: a detection is announced once it has been seen on `confirm_frames` frames over
///   at least `confirm_time` s with no gap longer than `confirm_time`; an announced staircase is
///   kept (never retracted by a frame's dropout) until unseen for `forget_time` s, and the same one
///   is not announced again within `repeat_time` s.
/// - Rate limits: one cue of a kind per `min_cue_interval` s; ticks at most one per
///   `min_tick_interval` s.
/// - A descending staircase within `danger_distance` m (or of unknown distance) always warns,
///   whatever the verbosity: once while it is held, again when it comes back after being forgotten
///   (even within `repeat_time`).
/// - Blind: no floor and nothing seen nor tracked for `blind_after` s: told once, then every
///   `blind_repeat` s while it lasts.
/// - Approach: a confirmed descending staircase whose first edge is within `approach_range` m
///   beeps (kApproach, an earcon and a pulse), again and again, the interval shrinking linearly
///   from `approach_interval_far` s at the range to `approach_interval_near` s at `approach_near` m
///   (parking-sensor style; the distance is the nearest of this approach after a 5-frame median,
///   so a noisy reading never slows the beat while the wearer walks on). It stops on the first
///   step, when the edge's bearing leaves the `approach_cone` (turned away), when the wearer has
///   not come 0.15 m nearer for `approach_stall` s (stopped; it resumes on walking on), and when
///   the staircase is forgotten. At every verbosity. The drop warning counts as a beat (no beep over
///   its alarm; the next beep keeps the interval from it).
/// - A drop-off (platform edge, dock, hole) confirmed as a staircase is (`confirm_frames` over
///   `confirm_time`) and within `danger_distance` m is told once while it is held ("drop ahead",
///   distance, clock), at every verbosity, again when it comes back after being forgotten
///   (`forget_time`). Never while a descending staircase is held or seen: the stair cue wins. The
///   approach beep runs for a held drop's edge as for a descent's first edge.
/// - While the traversal tracker runs (`traversal.ran`), the flight cues (first step, ticks, counts,
///   steps left, last step, end) follow its states; without it only the detection cues are given.
///
/// - System state, at every verbosity: battery low and critical (battery()), and "slow" once
///   perception has been more than `slow_lag` s behind the camera (`lag_s`) for `slow_after` s,
///   again every `slow_repeat` s while it lasts (over when the lag falls below half `slow_lag`).
///
/// - The wearer's button (`presses`, or between_frames() when no frame comes): a short press is
///   answered with where the staircase held in mind is (kWhere: kind, up or down, metres, clock
///   position, said even at 12), the steps left on a flight (or which way it goes), or "no
///   stairs"; a long press mutes every cue for `mute` s (kMuted; another long press or the
///   time's end: kUnmuted), except what warns of a descent (the drop warning, the approach beep)
///   and the answers to the button; a double press cycles the verbosity quiet -> normal ->
///   verbose -> quiet (kVerbosity). What is muted is not told later (a short press asks). A
///   reload that changes `verbosity` sets it again.
///
/// Verbosity: quiet = warnings (drop, last step, blind, camera) and earcons for stairs and steps
/// ahead; normal = the words for what is ahead, first step, ticks, counts every `count_interval`
/// steps, steps left once known, end of stairs; verbose = also the distance as it shrinks and
/// the clock position straight ahead (12), steps left with every count.

#include <vector>

#include "stairguide/core/config.hpp"
#include "stairguide/feedback/button.hpp"
#include "stairguide/feedback/cue.hpp"
#include "stairguide/stairs/traversal_result.hpp"

namespace stairguide::feedback {

enum class Verbosity { kQuiet, kNormal, kVerbose };
/// "quiet", "normal", "verbose" (the loader has validated it); anything else is kNormal.
Verbosity parse_verbosity(const std::string& s);

/// What the policy reads of one perceived frame.
struct CueInput {
  double t = 0.0;              ///< s, the frame's timestamp (monotonic within a run)
  bool floor_found = false;    ///< the floor is seen in this frame
  StairSummary stair;          ///< this frame's detection
  TraversalResult traversal;   ///< the tracker's state (`ran` false: detection cues only)
  DropSummary drop;            ///< this frame's drop-off (not told when the stair stage tells a descent)
  double lag_s = 0.0;          ///< s from the frame's capture to this decision (perception behind)
  std::vector<Press> presses;  ///< the wearer's button presses since the last decision, in order
};

/// Clock position (1..12, 12 straight ahead, 3 to the right) of a bearing in rad; 12 for NaN.
int clock_position(float bearing_rad);

class CuePolicy {
 public:
  explicit CuePolicy(const FeedbackConfig& config);
  /// New tunables (verbosity...) from the next frame on; what was told is kept.
  void reconfigure(const FeedbackConfig& config);

  /// The cues for one frame, highest priority first (empty when nothing is to be said).
  std::vector<CueEvent> step(const CueInput& in);
  /// The camera stopped sending / is back (`t`: time of the last frame seen, s).
  std::vector<CueEvent> camera_lost(double t);
  std::vector<CueEvent> camera_back(double t);
  /// The battery as last read (power_supply.hpp), at frame time `t`: "battery low" when the charge
  /// falls to `battery_low` (not charging), again every `battery_repeat` s while it lasts;
  /// "battery critical" at `battery_critical`, every `battery_critical_repeat` s. Charging, or a
  /// charge 3 points above the low mark, ends it (told again on the next fall).
  std::vector<CueEvent> battery(double t, bool present, float charge, bool charging);
  /// Between two frames (none has come for a while: the camera is lost, perception is slow): the
  /// button's `presses` at time `t` (on the frames' clock, carried on), and the end of a mute.
  std::vector<CueEvent> between_frames(double t, const std::vector<Press>& presses);
  bool muted() const { return mute_until_ >= 0.0; }
  Verbosity verbosity() const { return verbosity_; }

 private:
  struct Sighting {
    bool present = false;
    StairKind kind = StairKind::kNone;
    int direction = 0;
    float distance_m = 0.f;  // NaN: unknown
    float bearing_rad = 0.f;
  };
  struct Candidate {
    bool active = false;
    int key = 0;
    int frames = 0;
    double first_t = 0.0, last_t = 0.0;
  };
  struct Told {
    bool active = false;     // a staircase (or step) is confirmed and held
    bool announced = false;  // ... and the user has been told of it
    bool warned = false;     // ... the drop warning has been given
    int key = 0;
    double last_seen_t = 0.0, told_t = -1e9;
    int last_metres = -1;
  };

  static int key_of(StairKind kind, int direction);
  bool allowed(Cue c) const;
  bool rate_ok(Cue c, double t) const;
  void emit(std::vector<CueEvent>& out, CueEvent e, double t);
  CueEvent ahead_event(const Sighting& s, bool drop) const;
  void detection_cues(const Sighting& s, double t, std::vector<CueEvent>& out);
  void flight_cues(const TraversalResult& tr, double t, std::vector<CueEvent>& out);
  void blind_cues(const CueInput& in, double t, std::vector<CueEvent>& out);
  void approach_cues(const Sighting& s, const DropSummary& drop, const TraversalResult& tr, double t,
                     std::vector<CueEvent>& out);
  void approach_beat(float d, float bearing, double t, std::vector<CueEvent>& out);
  void drop_cues(const DropSummary& drop, bool descent, double t, std::vector<CueEvent>& out);
  float approach_interval(float d) const;
  void button_cues(const std::vector<Press>& presses, double t, std::vector<CueEvent>& out);
  CueEvent where_event(double t) const;
  void mute_filter(std::vector<CueEvent>& out, double t);
  static void by_priority(std::vector<CueEvent>& out);

  FeedbackConfig cfg_;
  Verbosity verbosity_ = Verbosity::kNormal;
  bool ready_told_ = false;
  bool camera_down_ = false;
  Candidate cand_;
  Told told_;
  // Flight (traversal tracker) state.
  TraversalState prev_state_ = TraversalState::kSearching;
  int prev_climbed_ = 0;
  bool steps_left_told_ = false;
  double last_tick_t_ = -1e9;
  // Approach beep (to a descending first edge).
  struct Approach {
    bool on = false;  // within range, ahead, walking: beeping
    double last_beep_t = -1e9;
    float nearest = 0.f;   // m, the nearest (filtered) distance of this approach
    float ref_d = 0.f;     // m, distance when the wearer last came 0.15 m nearer ...
    double ref_t = 0.0;    // ... and when
    float recent[5] = {};  // the last distances, for the median
    int n_recent = 0;
  };
  Approach approach_;
  // A drop-off: confirmed (as a staircase is), held until forgotten, warned of once while held.
  struct DropHold {
    bool active = false, warned = false;
    int frames = 0;                       // confirming sightings
    double first_t = 0.0, last_t = -1e9;  // of the candidate's sightings
    double last_seen_t = -1e9;
  };
  DropHold drop_;
  // Blind.
  double blind_since_ = -1.0;
  double last_blind_t_ = -1e9;
  double last_frame_t_ = -1e9;
  double last_t_[kCueKinds] = {};  // per Cue, the last time it was given
  // System state.
  int battery_told_ = 0;  // 0 nothing, 1 low, 2 critical: the level told of this fall
  double slow_since_ = -1.0;
  // The button.
  double mute_until_ = -1.0;  // < 0: not muted
  Sighting held_;             // the last sighting of the staircase held in mind (told_)
  int flight_left_ = -1;      // the tracker's steps left and direction, as of the last frame
  int flight_dir_ = 0;
};

}  // namespace stairguide::feedback
