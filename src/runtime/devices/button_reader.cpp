#include "stairguide/runtime/devices/button_reader.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <sstream>
#include <stdexcept>
#include <system_error>

#include "gpio_chip_line.hpp"

namespace stairguide::runtime::devices {

using feedback::ButtonEdge;
using feedback::ButtonLine;
using feedback::PressEvent;
using feedback::PressTiming;

double steady_seconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// ---------------------------------------------------------------- libgpiod line

struct GpiodButtonLine::Impl : detail::GpioChipLine {};

GpiodButtonLine::GpiodButtonLine(const std::string& chip, int line, bool active_low,
                                 const std::string& consumer)
    : impl_(std::make_unique<Impl>()) {
  desc_ = "gpiod:" + chip + ":" + std::to_string(line);
  impl_->open("button", chip, line);
  std::bitset<32> flags;
  if (active_low) flags = gpiod::line_request::FLAG_ACTIVE_LOW;
  try {
    try {
      // A button to ground wants the line pulled up; kernels before 5.5 cannot set the bias
      // (an external pull-up then does it), so the request is tried again without it.
      const auto bias = active_low ? gpiod::line_request::FLAG_BIAS_PULL_UP : std::bitset<32>();
      impl_->line.request({consumer, gpiod::line_request::EVENT_BOTH_EDGES, flags | bias});
    } catch (const std::system_error&) {
      if (!active_low) throw;
      impl_->line.request({consumer, gpiod::line_request::EVENT_BOTH_EDGES, flags});
    }
  } catch (const std::exception& e) {
    throw std::runtime_error(detail::GpioChipLine::what("button", chip, line) +
                             "cannot request the line for edge events (" + e.what() + ")");
  }
}

GpiodButtonLine::~GpiodButtonLine() { impl_->release(); }

void GpiodButtonLine::wait(std::chrono::milliseconds timeout, std::vector<ButtonEdge>& out) {
  try {
    if (!impl_->line.event_wait(std::chrono::duration_cast<std::chrono::nanoseconds>(timeout))) return;
    // Timed on arrival: the kernel's event clock is the realtime one on older kernels.
    const double now = steady_seconds();
    for (const gpiod::line_event& ev : impl_->line.event_read_multiple())
      out.push_back({now, ev.event_type == gpiod::line_event::RISING_EDGE});
  } catch (const std::exception& e) {
    throw std::runtime_error("button: " + desc_ + ": reading its events failed (" + e.what() + ")");
  }
}

// ---------------------------------------------------------------- file line (tests)

FileButtonLine::FileButtonLine(const std::string& path, std::function<void(const std::string&)> warn)
    : path_(path), warn_(std::move(warn)) {
  // Non-blocking: a FIFO opens at once with no writer yet, and a read never waits.
  fd_ = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd_ < 0)
    throw std::runtime_error("button: cannot open the press file '" + path + "' (" + std::strerror(errno) +
                             ")");
  t0_ = steady_seconds();
}

FileButtonLine::~FileButtonLine() {
  if (fd_ >= 0) ::close(fd_);
}

void FileButtonLine::parse_line(const std::string& raw) {
  ++line_no_;
  const std::string line = raw.substr(0, raw.find('#'));
  std::istringstream is(line);
  std::string when, what, extra;
  if (!(is >> when)) return;  // blank or a comment
  char* end = nullptr;
  const double t = std::strtod(when.c_str(), &end);
  const bool ok = *end == '\0' && std::isfinite(t) && t >= 0 && (is >> what) &&
                  (what == "down" || what == "up") && !(is >> extra);
  const std::string where = "button: " + describe() + " line " + std::to_string(line_no_) + ": ";
  if (!ok) {
    if (warn_) warn_(where + "expected '<seconds> down|up', found '" + raw + "'; skipped");
    return;
  }
  if (t < last_t_) {
    if (warn_) warn_(where + "time " + when + " s is before the line above it; skipped");
    return;
  }
  last_t_ = t;
  due_.push_back({t0_ + t, what == "down"});
}

void FileButtonLine::read_more() {
  char buf[4096];
  for (;;) {
    const ssize_t n = ::read(fd_, buf, sizeof buf);
    if (n <= 0) return;  // nothing more for now (EOF of a file that may grow, no FIFO writer, EAGAIN)
    partial_.append(buf, static_cast<std::size_t>(n));
    for (std::size_t nl; (nl = partial_.find('\n')) != std::string::npos;) {
      parse_line(partial_.substr(0, nl));
      partial_.erase(0, nl + 1);
    }
    if (partial_.size() > 4096) {  // not a text of lines: say so once and start over
      if (warn_) warn_("button: " + describe() + ": a line longer than 4096 bytes; dropped");
      partial_.clear();
    }
  }
}

void FileButtonLine::wait(std::chrono::milliseconds timeout, std::vector<ButtonEdge>& out) {
  const double until = steady_seconds() + timeout.count() * 1e-3;
  for (;;) {
    read_more();
    const double now = steady_seconds();
    while (!due_.empty() && due_.front().t <= now) {
      out.push_back(due_.front());
      due_.pop_front();
    }
    if (!out.empty() || now >= until) return;
    double next = std::min(until, now + 0.02);  // the file is looked at again every 20 ms
    if (!due_.empty()) next = std::min(next, due_.front().t);
    std::this_thread::sleep_for(std::chrono::duration<double>(std::max(0.0, next - now)));
  }
}

std::unique_ptr<ButtonLine> make_button_line(const std::string& chip, int line, bool active_low,
                                             std::function<void(const std::string&)> warn) {
  if (chip.rfind("file:", 0) == 0) return std::make_unique<FileButtonLine>(chip.substr(5), std::move(warn));
  return std::make_unique<GpiodButtonLine>(chip, line, active_low);
}

// ---------------------------------------------------------------- reader

ButtonReader::ButtonReader(std::unique_ptr<ButtonLine> line, PressTiming timing,
                           std::function<void(const std::string&)> warn)
    : line_(std::move(line)), decoder_(timing), warn_(std::move(warn)) {
  thread_ = std::thread([this] { run(); });
}

ButtonReader::~ButtonReader() {
  stop_.store(true);
  if (thread_.joinable()) thread_.join();
}

std::vector<PressEvent> ButtonReader::take() {
  std::lock_guard<std::mutex> lk(m_);
  std::vector<PressEvent> out;
  out.swap(presses_);
  return out;
}

void ButtonReader::run() {
  std::vector<ButtonEdge> edges;
  std::vector<PressEvent> got;
  while (!stop_.load()) {
    // Wake for the decoder's next decision, and at least every 100 ms to see a stop.
    const double left_ms = (decoder_.next_deadline() - steady_seconds()) * 1e3;
    const auto wait =
        std::chrono::milliseconds(static_cast<long>(std::clamp(std::ceil(left_ms), 0.0, 100.0)));
    edges.clear();
    try {
      line_->wait(wait, edges);
    } catch (const std::exception& e) {
      if (warn_) warn_(std::string(e.what()) + "; the button is read no more");
      return;
    }
    got.clear();
    for (const ButtonEdge& e : edges) decoder_.edge(e, got);
    decoder_.advance(steady_seconds(), got);
    if (got.empty()) continue;
    std::lock_guard<std::mutex> lk(m_);
    presses_.insert(presses_.end(), got.begin(), got.end());
  }
}

}  // namespace stairguide::runtime::devices
