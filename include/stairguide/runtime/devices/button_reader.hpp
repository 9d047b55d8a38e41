#pragma once
/// \file button_reader.hpp
/// The wearer's button's devices: the input lines the config can name, `GpiodButtonLine`
/// (libgpiod 1.6 edge events) and `FileButtonLine` (a file or FIFO of "<seconds> down|up" lines:
/// the daemon's test backend, button_chip "file:PATH"), and `ButtonReader`, which reads a line on a
/// thread of its own (the runtime room holds the threads) and hands the presses over (take()), so
/// that nothing on the frames' path waits on the button. Decoding edges into presses (debounce,
/// short, long, double) and the line interface are the feedback room's
/// (stairguide/feedback/button.hpp).

#include <atomic>
#include <chrono>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "stairguide/feedback/button.hpp"

namespace stairguide::runtime::devices {

/// A GPIO line through libgpiod's C++ API, requested for both edges (active low: a button to
/// ground with the line pulled up reads "pressed" when low). Throws std::runtime_error naming the
/// chip and line and what failed (no such chip, line busy, permission) when it cannot be requested.
class GpiodButtonLine : public feedback::ButtonLine {
 public:
  GpiodButtonLine(const std::string& chip, int line, bool active_low,
                  const std::string& consumer = "stairguide-button");
  ~GpiodButtonLine() override;
  void wait(std::chrono::milliseconds timeout, std::vector<feedback::ButtonEdge>& out) override;
  std::string describe() const override { return desc_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::string desc_;
};

/// Presses read from a file or FIFO the test writes, one edge a line:
///
///     <seconds> down|up        e.g. "2.5 down", "2.62 up"; '#' starts a comment
///
/// `seconds` counts from when the file was opened (the daemon's start); the edge is given at that
/// time (at once when it has passed). The file is followed as it grows (as `tail -f`); a FIFO may
/// be opened by its writer later. A line that does not parse, or goes back in time, is reported
/// through `warn` (naming the file and the line) and skipped. Throws std::runtime_error when the
/// file cannot be opened.
class FileButtonLine : public feedback::ButtonLine {
 public:
  FileButtonLine(const std::string& path, std::function<void(const std::string&)> warn);
  ~FileButtonLine() override;
  void wait(std::chrono::milliseconds timeout, std::vector<feedback::ButtonEdge>& out) override;
  std::string describe() const override { return "file:" + path_; }

 private:
  void read_more();
  void parse_line(const std::string& line);
  std::string path_;
  std::function<void(const std::string&)> warn_;
  int fd_ = -1;
  double t0_ = 0.0;  // s on the steady clock at open
  std::string partial_;
  int line_no_ = 0;
  double last_t_ = -1.0;
  std::deque<feedback::ButtonEdge> due_;  // parsed, on the steady clock, waiting for their time
};

/// s on the steady clock (the button's and the reader's time base).
double steady_seconds();

/// The line the config names: "file:PATH" -> FileButtonLine, else GpiodButtonLine(chip, line).
/// Throws std::runtime_error with a clear message when it cannot be had.
std::unique_ptr<feedback::ButtonLine> make_button_line(const std::string& chip, int line, bool active_low,
                                                       std::function<void(const std::string&)> warn);

/// Reads a line on a thread of its own and decodes its presses; take() hands them over (any
/// thread). A line that fails is reported once through `warn` and read no more.
class ButtonReader {
 public:
  ButtonReader(std::unique_ptr<feedback::ButtonLine> line, feedback::PressTiming timing,
               std::function<void(const std::string&)> warn);
  ~ButtonReader();
  std::vector<feedback::PressEvent> take();
  std::string describe() const { return line_->describe(); }

 private:
  void run();
  std::unique_ptr<feedback::ButtonLine> line_;
  feedback::PressDecoder decoder_;
  std::function<void(const std::string&)> warn_;
  std::mutex m_;
  std::vector<feedback::PressEvent> presses_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace stairguide::runtime::devices
