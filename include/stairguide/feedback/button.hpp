#pragma once
/// \file button.hpp
/// The wearer's push button: edges from an input line, debounced and decoded into presses.
///
///   short press (released before `long_press` s, no second press within `double_press` s):
///       "where are the stairs?"
///   long press (held `long_press` s; told when the time is reached, not at the release): mute
///   double press (two short presses, the second pressed within `double_press` s of the first's
///       release): the next verbosity
///
/// A level counts once it has held `debounce` s (contact bounce is shorter); the press is timed from
/// the edge that began it. A short press followed by a long one is a long press.
///
/// Lines: `GpiodButtonLine` (libgpiod 1.6 edge events), `FileButtonLine` (a file or FIFO of
/// "<seconds> down|up" lines: the daemon's test backend, button_chip "file:PATH"). `ButtonReader`
/// reads a line on a thread of its own and hands the presses over (take()), so that nothing on the
/// frames' path waits on the button.

#include <atomic>
#include <chrono>
#include <cstdio>
#include <deque>
#include <functional>
#include <limits>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace stairguide::feedback {

enum class Press { kShort, kLong, kDouble };
/// "short", "long", "double".
const char* to_string(Press p);

/// One change of the line: pressed (`down`) or released, at `t` (s on the steady clock).
struct ButtonEdge {
  double t = 0.0;
  bool down = false;
};

struct PressEvent {
  double t = 0.0;  ///< s on the steady clock: when the press was recognised
  Press press = Press::kShort;
};

struct PressTiming {
  double debounce = 0.03;     ///< s a level must hold to count
  double long_press = 1.0;    ///< s held: a long press
  double double_press = 0.4;  ///< s from a short press's release to the next press: a double press
};

/// Edges in, presses out (pure: the caller gives the times).
class PressDecoder {
 public:
  explicit PressDecoder(PressTiming timing) : tm_(timing) {}
  /// A raw edge of the line (bounces included), in time order.
  void edge(const ButtonEdge& e, std::vector<PressEvent>& out);
  /// The time is now `t`: a level that has held, a press held long enough, a short press with no
  /// second one in time are decided.
  void advance(double t, std::vector<PressEvent>& out);
  /// s: when advance() may next decide something (infinity: not before the next edge).
  double next_deadline() const;
  bool pressed() const { return level_; }  ///< the debounced level

 private:
  void accept(double t, bool down, std::vector<PressEvent>& out);
  PressTiming tm_;
  bool raw_ = false;             // the line's last raw level ...
  double raw_t_ = -1e9;          // ... since
  bool level_ = false;           // debounced
  double down_t_ = 0.0;          // when the press being held began
  bool long_told_ = false;       // ... and it has been told as a long press
  bool second_ = false;          // ... and it is the second of a double press
  bool single_pending_ = false;  // a short press released at release_t_, waiting for a second
  double release_t_ = 0.0;
};

/// An input line the button is wired to. Called from the reader's thread only.
class ButtonLine {
 public:
  virtual ~ButtonLine() = default;
  /// Waits at most `timeout` for edges; appends those that came (times on the steady clock, s).
  /// Throws std::runtime_error naming the line when it fails.
  virtual void wait(std::chrono::milliseconds timeout, std::vector<ButtonEdge>& out) = 0;
  virtual std::string describe() const = 0;
};

/// A GPIO line through libgpiod's C++ API, requested for both edges (active low: a button to
/// ground with the line pulled up reads "pressed" when low). Throws std::runtime_error naming the
/// chip and line and what failed (no such chip, line busy, permission) when it cannot be requested.
class GpiodButtonLine : public ButtonLine {
 public:
  GpiodButtonLine(const std::string& chip, int line, bool active_low,
                  const std::string& consumer = "stairguide-button");
  ~GpiodButtonLine() override;
  void wait(std::chrono::milliseconds timeout, std::vector<ButtonEdge>& out) override;
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
class FileButtonLine : public ButtonLine {
 public:
  FileButtonLine(const std::string& path, std::function<void(const std::string&)> warn);
  ~FileButtonLine() override;
  void wait(std::chrono::milliseconds timeout, std::vector<ButtonEdge>& out) override;
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
  std::deque<ButtonEdge> due_;  // parsed, on the steady clock, waiting for their time
};

/// s on the steady clock (the button's and the reader's time base).
double steady_seconds();

/// The line the config names: "file:PATH" -> FileButtonLine, else GpiodButtonLine(chip, line).
/// Throws std::runtime_error with a clear message when it cannot be had.
std::unique_ptr<ButtonLine> make_button_line(const std::string& chip, int line, bool active_low,
                                             std::function<void(const std::string&)> warn);

/// Reads a line on a thread of its own and decodes its presses; take() hands them over (any
/// thread). A line that fails is reported once through `warn` and read no more.
class ButtonReader {
 public:
  ButtonReader(std::unique_ptr<ButtonLine> line, PressTiming timing,
               std::function<void(const std::string&)> warn);
  ~ButtonReader();
  std::vector<PressEvent> take();
  std::string describe() const { return line_->describe(); }

 private:
  void run();
  std::unique_ptr<ButtonLine> line_;
  PressDecoder decoder_;
  std::function<void(const std::string&)> warn_;
  std::mutex m_;
  std::vector<PressEvent> presses_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace stairguide::feedback
