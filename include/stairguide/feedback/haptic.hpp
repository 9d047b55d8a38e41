#pragma once
/// \file haptic.hpp
/// The buzzer: a pattern of pulses per cue, played on a thread of its own (the timing must not
/// wait on the frames) onto one output line. At most two things are coded in a vibration: which
/// (the pattern's shape) and how many (pulses).
///
///   up (stairs, step, curb): short-long (rising)      down: long-short (falling)
///   tick, first step, count: one short pulse          last step: one long pulse
///   end of stairs: two short                          drop warning (danger): five fast pulses
///   blind, camera lost: three long                    ready, camera back: one medium
///   approach (to a descent's edge): one sharp 40 ms pulse per beep, the beeps closer as it nears
///   battery low: two of 200 ms                         battery critical: four of 200 ms
///   muted (a long press): four 40 ms taps               unmuted: one medium
///
/// Lines: `GpiodLine` (libgpiod 1.6), `FileLine` (writes every edge to a file: the daemon's test
/// backend, gpio_chip "file:PATH"), `RecordingLine` (a fake: edges with their times, in memory).

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
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

/// One output line driving the buzzer. `set` is called from the haptic thread only.
class HapticLine {
 public:
  virtual ~HapticLine() = default;
  virtual void set(bool on) = 0;
  virtual std::string describe() const = 0;
};

/// A GPIO line through libgpiod's C++ API. Throws std::runtime_error naming the chip and line and
/// what failed (no such chip, line busy, permission) when it cannot be requested.
class GpiodLine : public HapticLine {
 public:
  GpiodLine(const std::string& chip, int line, const std::string& consumer = "stairguide");
  ~GpiodLine() override;
  void set(bool on) override;
  std::string describe() const override { return desc_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::string desc_;
};

/// Writes "<ms since opened, 3 decimals> <0|1>" per edge to a file (flushed). Throws
/// std::runtime_error when the file cannot be created.
class FileLine : public HapticLine {
 public:
  explicit FileLine(const std::string& path);
  ~FileLine() override;
  void set(bool on) override;
  std::string describe() const override { return "file:" + path_; }

 private:
  std::string path_;
  std::FILE* f_ = nullptr;
  std::chrono::steady_clock::time_point t0_;
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

/// Plays patterns onto a line from a thread of its own, timed against the steady clock (each
/// edge at an absolute time from the pattern's start, so errors do not add up). The thread asks
/// for real-time scheduling (SCHED_FIFO, priority kRealtimePriority): a sleeping thread of the
/// normal class wakes several ms late on a busy 2-core laptop, which a 60 ms pulse feels. It needs
/// root or an RLIMIT_RTPRIO of at least that priority (the unit sets LimitRTPRIO); without it the
/// player still plays, at the normal class, and `realtime()` says so.
class HapticPlayer : public Haptic {
 public:
  explicit HapticPlayer(std::unique_ptr<HapticLine> line);
  ~HapticPlayer() override;  ///< finishes the pattern playing (they are short), line off
  void play(const HapticPattern& p, int priority) override;
  bool drain(std::chrono::milliseconds timeout) override;
  std::string describe() const override { return line_->describe(); }
  /// Whether the thread got real-time scheduling; blocks until the thread has tried.
  bool realtime();
  static constexpr int kRealtimePriority = 10;

 private:
  void run();
  std::unique_ptr<HapticLine> line_;
  std::mutex m_;
  std::condition_variable cv_;
  HapticPattern pending_;
  int pending_priority_ = -1;  // -1: nothing pending
  int playing_priority_ = -1;  // -1: idle
  std::uint64_t generation_ = 0;
  bool stop_ = false;
  int realtime_ = -1;  // -1: not tried yet, 0: refused, 1: SCHED_FIFO
  std::thread thread_;
};

/// The line the config names: "file:PATH" -> FileLine, else GpiodLine(chip, line). Throws
/// std::runtime_error with a clear message when it cannot be had.
std::unique_ptr<HapticLine> make_haptic_line(const std::string& chip, int line);

}  // namespace stairguide::feedback
