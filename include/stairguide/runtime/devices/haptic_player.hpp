#pragma once
/// \file haptic_player.hpp
/// The buzzer's devices: `HapticPlayer` plays the patterns (stairguide/feedback/haptic.hpp: one per
/// cue) onto an output line from a thread of its own (the timing must not wait on the frames; the
/// runtime room holds the threads), and the lines the config can name: `GpiodLine` (libgpiod
/// 1.6) and `FileLine` (writes every edge to a file: the daemon's test backend, gpio_chip
/// "file:PATH"). The line interface and its recording fake are the feedback room's.

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "stairguide/feedback/haptic.hpp"

namespace stairguide::runtime::devices {

/// A GPIO line through libgpiod's C++ API. Throws std::runtime_error naming the chip and line and
/// what failed (no such chip, line busy, permission) when it cannot be requested.
class GpiodLine : public feedback::HapticLine {
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
class FileLine : public feedback::HapticLine {
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

/// Plays patterns onto a line from a thread of its own, timed against the steady clock (each
/// edge at an absolute time from the pattern's start, so errors do not add up). The thread asks
/// for real-time scheduling (SCHED_FIFO, priority kRealtimePriority): a sleeping thread of the
/// normal class wakes several ms late on a busy 2-core laptop, which a 60 ms pulse feels. It needs
/// root or an RLIMIT_RTPRIO of at least that priority (the unit sets LimitRTPRIO); without it the
/// player still plays, at the normal class, and `realtime()` says so.
class HapticPlayer : public feedback::Haptic {
 public:
  explicit HapticPlayer(std::unique_ptr<feedback::HapticLine> line);
  ~HapticPlayer() override;  ///< finishes the pattern playing (they are short), line off
  void play(const feedback::HapticPattern& p, int priority) override;
  bool drain(std::chrono::milliseconds timeout) override;
  std::string describe() const override { return line_->describe(); }
  /// Whether the thread got real-time scheduling; blocks until the thread has tried.
  bool realtime();
  static constexpr int kRealtimePriority = 10;

 private:
  void run();
  std::unique_ptr<feedback::HapticLine> line_;
  std::mutex m_;
  std::condition_variable cv_;
  feedback::HapticPattern pending_;
  int pending_priority_ = -1;  // -1: nothing pending
  int playing_priority_ = -1;  // -1: idle
  std::uint64_t generation_ = 0;
  bool stop_ = false;
  int realtime_ = -1;  // -1: not tried yet, 0: refused, 1: SCHED_FIFO
  std::thread thread_;
};

/// The line the config names: "file:PATH" -> FileLine, else GpiodLine(chip, line). Throws
/// std::runtime_error with a clear message when it cannot be had.
std::unique_ptr<feedback::HapticLine> make_haptic_line(const std::string& chip, int line);

}  // namespace stairguide::runtime::devices
