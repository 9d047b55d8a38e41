#include "stairguide/runtime/devices/haptic_player.hpp"

#include <pthread.h>
#include <sched.h>

#include <stdexcept>
#include <system_error>

#include "gpio_chip_line.hpp"

namespace stairguide::runtime::devices {

using feedback::HapticLine;
using feedback::HapticPattern;
using feedback::Pulse;

// ---------------------------------------------------------------- lines

struct GpiodLine::Impl : detail::GpioChipLine {};

GpiodLine::GpiodLine(const std::string& chip, int line, const std::string& consumer)
    : impl_(std::make_unique<Impl>()) {
  desc_ = "gpiod:" + chip + ":" + std::to_string(line);
  impl_->open("haptic", chip, line);
  try {
    impl_->line.request({consumer, gpiod::line_request::DIRECTION_OUTPUT, 0}, 0);
  } catch (const std::exception& e) {
    throw std::runtime_error(detail::GpioChipLine::what("haptic", chip, line) +
                             "cannot request the line as an output (" + e.what() + ")");
  }
}

GpiodLine::~GpiodLine() {
  try {
    if (impl_->line) impl_->line.set_value(0);  // the buzzer is left off
  } catch (const std::exception&) {
  }
  impl_->release();
}

void GpiodLine::set(bool on) {
  try {
    impl_->line.set_value(on ? 1 : 0);
  } catch (const std::system_error&) {
    // A line that stops answering mid-pattern: nothing better to do on the haptic thread.
  }
}

FileLine::FileLine(const std::string& path) : path_(path), t0_(std::chrono::steady_clock::now()) {
  f_ = std::fopen(path.c_str(), "w");
  if (!f_) throw std::runtime_error("haptic: cannot create the edge file '" + path + "'");
}
FileLine::~FileLine() {
  if (f_) std::fclose(f_);
}
void FileLine::set(bool on) {
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0_).count();
  std::fprintf(f_, "%.3f %d\n", ms, on ? 1 : 0);
  std::fflush(f_);
}

std::unique_ptr<HapticLine> make_haptic_line(const std::string& chip, int line) {
  if (chip.rfind("file:", 0) == 0) return std::make_unique<FileLine>(chip.substr(5));
  return std::make_unique<GpiodLine>(chip, line);
}

// ---------------------------------------------------------------- player

HapticPlayer::HapticPlayer(std::unique_ptr<HapticLine> line) : line_(std::move(line)) {
  thread_ = std::thread([this] { run(); });
}

HapticPlayer::~HapticPlayer() {
  {
    std::lock_guard<std::mutex> lk(m_);
    stop_ = true;
  }
  cv_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void HapticPlayer::play(const HapticPattern& p, int priority) {
  if (p.empty()) return;
  {
    std::lock_guard<std::mutex> lk(m_);
    if (priority < playing_priority_ || priority < pending_priority_) return;
    pending_ = p;
    pending_priority_ = priority;
    ++generation_;
  }
  cv_.notify_all();
}

bool HapticPlayer::realtime() {
  std::unique_lock<std::mutex> lk(m_);
  cv_.wait(lk, [&] { return realtime_ >= 0; });
  return realtime_ == 1;
}

bool HapticPlayer::drain(std::chrono::milliseconds timeout) {
  std::unique_lock<std::mutex> lk(m_);
  return cv_.wait_for(lk, timeout, [&] { return pending_priority_ < 0 && playing_priority_ < 0; });
}

void HapticPlayer::run() {
  using Clock = std::chrono::steady_clock;
  {
    sched_param sp{};
    sp.sched_priority = kRealtimePriority;
    const bool rt = pthread_setschedparam(pthread_self(), SCHED_FIFO, &sp) == 0;
    std::lock_guard<std::mutex> lk(m_);
    realtime_ = rt ? 1 : 0;
  }
  cv_.notify_all();
  for (;;) {
    HapticPattern p;
    std::uint64_t gen = 0;
    {
      std::unique_lock<std::mutex> lk(m_);
      cv_.wait(lk, [&] { return stop_ || pending_priority_ >= 0; });
      if (pending_priority_ < 0) break;  // stopping, nothing left
      p = std::move(pending_);
      playing_priority_ = pending_priority_;
      pending_priority_ = -1;
      gen = generation_;
    }
    // Waits until `t`; true when a newer pattern cut this one.
    auto wait_until = [&](Clock::time_point t) {
      std::unique_lock<std::mutex> lk(m_);
      return cv_.wait_until(lk, t, [&] { return generation_ != gen; });
    };
    auto t = Clock::now();
    bool cut = false, on = false;
    for (const Pulse& q : p) {
      line_->set(true);
      on = true;
      t += std::chrono::milliseconds(q.on_ms);
      if ((cut = wait_until(t))) break;
      line_->set(false);
      on = false;
      t += std::chrono::milliseconds(q.off_ms);
      if ((cut = wait_until(t))) break;
    }
    if (on) line_->set(false);
    // A cut pattern leaves a gap before the next so the two are not felt as one.
    if (cut) std::this_thread::sleep_for(std::chrono::milliseconds(100));
    {
      std::lock_guard<std::mutex> lk(m_);
      playing_priority_ = -1;
    }
    cv_.notify_all();
  }
}

}  // namespace stairguide::runtime::devices
