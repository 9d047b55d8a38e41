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
/// Here: the decoder (pure) and the line interface. The lines, `GpiodButtonLine` (libgpiod 1.6
/// edge events) and `FileButtonLine` (button_chip "file:PATH"), and `ButtonReader`, which reads a
/// line on a thread of its own so that nothing on the frames' path waits on the button, are the
/// runtime room's (stairguide/runtime/devices/button_reader.hpp).

#include <chrono>
#include <string>
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

}  // namespace stairguide::feedback
