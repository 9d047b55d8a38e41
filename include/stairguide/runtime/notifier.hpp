#pragma once
/// \file notifier.hpp
/// The service manager's notification channel (sd_notify), behind an interface so that tests can
/// record what the runtime announces.

#include <cstdint>
#include <string>

namespace stairguide::runtime {

/// Receives "READY=1", "WATCHDOG=1", "STATUS=...", "STOPPING=1", "RELOADING=1".
class Notifier {
 public:
  virtual ~Notifier() = default;
  /// Sends one assignment (or several, newline-separated). Must be thread-safe.
  virtual void notify(const std::string& state) = 0;
  /// Watchdog period the service manager expects, in microseconds; 0 when none is set.
  virtual std::uint64_t watchdog_usec() const { return 0; }
};

/// sd_notify to $NOTIFY_SOCKET; does nothing when the variable is not set (not under systemd).
class SystemdNotifier : public Notifier {
 public:
  SystemdNotifier();
  void notify(const std::string& state) override;
  /// From $WATCHDOG_USEC (sd_watchdog_enabled), read once at construction.
  std::uint64_t watchdog_usec() const override { return watchdog_usec_; }

 private:
  std::uint64_t watchdog_usec_ = 0;
};

/// Does nothing (benchmarks, tools).
class NullNotifier : public Notifier {
 public:
  void notify(const std::string&) override {}
};

}  // namespace stairguide::runtime
