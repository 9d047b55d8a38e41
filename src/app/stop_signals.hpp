#pragma once
// The signals the daemon takes itself (stop: SIGTERM, SIGINT; reload: SIGHUP), blocked before any
// thread starts and waited for by one thread. Shared by the static launcher
// (stairguided_launcher.cpp, no C++ runtime needed) and the daemon (stairguided_main.cpp).
#include <signal.h>

namespace stairguide_app {

inline sigset_t stop_and_reload_signals() {
  sigset_t sigs;
  sigemptyset(&sigs);
  sigaddset(&sigs, SIGTERM);
  sigaddset(&sigs, SIGINT);
  sigaddset(&sigs, SIGHUP);
  return sigs;
}

/// Blocks them in the calling thread (and in every thread it starts later); the signature is a
/// .preinit_array entry's.
inline void block_stop_signals(int, char**, char**) {
  const sigset_t sigs = stop_and_reload_signals();
  pthread_sigmask(SIG_BLOCK, &sigs, nullptr);
}

}  // namespace stairguide_app
