// sd_notify behind the Notifier interface.
#include "stairguide/runtime/notifier.hpp"

#include <systemd/sd-daemon.h>

namespace stairguide::runtime {

SystemdNotifier::SystemdNotifier() {
  std::uint64_t usec = 0;
  // unset_environment = 0: the variables stay for anything we spawn (nothing today).
  if (sd_watchdog_enabled(0, &usec) > 0) watchdog_usec_ = usec;
}

void SystemdNotifier::notify(const std::string& state) {
  // sd_notify is a single sendmsg on a fresh socket: thread-safe, and a no-op without
  // $NOTIFY_SOCKET. A failure (manager gone) is not worth stopping for.
  (void)sd_notify(0, state.c_str());
}

}  // namespace stairguide::runtime
