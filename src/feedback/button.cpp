#include "stairguide/feedback/button.hpp"

#include <algorithm>
#include <limits>

namespace stairguide::feedback {

const char* to_string(Press p) {
  switch (p) {
    case Press::kShort: return "short";
    case Press::kLong: return "long";
    case Press::kDouble: return "double";
  }
  return "?";
}

// ---------------------------------------------------------------- decoder

void PressDecoder::edge(const ButtonEdge& e, std::vector<PressEvent>& out) {
  advance(e.t, out);           // what the level did before this edge is decided first
  if (e.down == raw_) return;  // no change (a repeated report)
  raw_ = e.down;
  raw_t_ = e.t;
}

void PressDecoder::advance(double t, std::vector<PressEvent>& out) {
  constexpr double kEps = 1e-9;
  if (raw_ != level_ && t - raw_t_ >= tm_.debounce - kEps) accept(raw_t_, raw_, out);
  if (level_ && !long_told_ && t - down_t_ >= tm_.long_press - kEps) {
    out.push_back({down_t_ + tm_.long_press, Press::kLong});
    long_told_ = true;
    second_ = false;
  }
  // A second press still bouncing (not yet a level) may yet make this a double press.
  const bool second_coming = raw_ && !level_;
  if (single_pending_ && !second_coming && t - release_t_ > tm_.double_press) {
    out.push_back({release_t_ + tm_.double_press, Press::kShort});
    single_pending_ = false;
  }
}

void PressDecoder::accept(double t, bool down, std::vector<PressEvent>& out) {
  level_ = down;
  if (down) {
    if (single_pending_ && t - release_t_ > tm_.double_press) {
      out.push_back({release_t_ + tm_.double_press, Press::kShort});  // too late to be its second
      single_pending_ = false;
    }
    second_ = single_pending_;
    single_pending_ = false;
    down_t_ = t;
    long_told_ = false;
    return;
  }
  if (long_told_) return;  // told when the time was reached
  if (second_) {
    out.push_back({t, Press::kDouble});
    second_ = false;
    return;
  }
  single_pending_ = true;
  release_t_ = t;
}

double PressDecoder::next_deadline() const {
  double d = std::numeric_limits<double>::infinity();
  if (raw_ != level_) d = std::min(d, raw_t_ + tm_.debounce);
  if (level_ && !long_told_) d = std::min(d, down_t_ + tm_.long_press);
  if (single_pending_) d = std::min(d, release_t_ + tm_.double_press + 1e-3);
  return d;
}

}  // namespace stairguide::feedback
