#pragma once
/// \file haptic.hpp
/// The buzzer: a pattern of pulses per cue, played onto one output line by a `Haptic`. At most two things are
/// coded in a vibration: which (the pattern's shape) and how many (pulses).
///
///   up (stairs, step, curb): short-long (rising)      down: long-short (falling)
///   tick, first step, count: one short pulse          last step: one long pulse
///   end of stairs: two short                          drop warning (danger): five fast pulses
///   blind, camera lost: three long                    ready, camera back: one medium
///   approach (to a descent's edge): one sharp 40 ms pulse per beep, the beeps closer as it nears
///   battery low: two of 200 ms                         battery critical: four of 200 ms
///   muted (a long press): four 40 ms taps               unmuted: one medium
///
/// Here: the patterns, the line and player interfaces, `RecordingLine` (a fake: edges with their
/// times, in memory) and `NullHaptic`. The player that times the patterns on a thread of its own
/// (the timing must not wait on the frames) and the real lines, `GpiodLine` (libgpiod 1.6) and
/// `FileLine` (gpio_chip "file:PATH"), are the runtime room's
/// (stairguide/runtime/devices/haptic_player.hpp).

#include <chrono>
#include <mutex>
#include <string>
#include <vector>

#include "stairguide/feedback/cue.hpp"

namespace stairguide::feedback {

struct Pulse {
  int on_ms = 0;   ///< ms the buzzer is on
  int off_ms = 0;  ///< ms off after it (before the next pulse)
};
using HapticPattern = std::vector<Pulse>;

/// The pattern of a cue (see the table above); empty for none.
HapticPattern haptic_pattern(const CueEvent& e);

/// One output line driving the buzzer. `set` is called from the player's thread only.
class HapticLine {
 public:
  virtual ~HapticLine() = default;
  virtual void set(bool on) = 0;
  virtual std::string describe() const = 0;
};

/// Test fake: every edge with its time.
class RecordingLine : public HapticLine {
 public:
  struct Edge {
    std::chrono::steady_clock::time_point t;
    bool on;
  };
  void set(bool on) override {
    std::lock_guard<std::mutex> lk(m_);
    edges_.push_back({std::chrono::steady_clock::now(), on});
  }
  std::string describe() const override { return "recording"; }
  std::vector<Edge> edges() const {
    std::lock_guard<std::mutex> lk(m_);
    return edges_;
  }

 private:
  mutable std::mutex m_;
  std::vector<Edge> edges_;
};

class Haptic {
 public:
  virtual ~Haptic() = default;
  /// Starts `p` now, cutting a pattern of lower or equal priority that is playing; a pattern of
  /// higher priority that is playing is kept and `p` dropped (never queued: a late buzz misleads).
  virtual void play(const HapticPattern& p, int priority) = 0;
  /// Waits until no pattern is playing, at most `timeout`; true when idle.
  virtual bool drain(std::chrono::milliseconds timeout) = 0;
  virtual std::string describe() const = 0;
};

class NullHaptic : public Haptic {
 public:
  void play(const HapticPattern&, int) override {}
  bool drain(std::chrono::milliseconds) override { return true; }
  std::string describe() const override { return "null"; }
};

}  // namespace stairguide::feedback
