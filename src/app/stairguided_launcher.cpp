// stairguided: blocks the stop and reload signals, then becomes the daemon proper
// (stairguided-core, the main in stairguided_main.cpp) by execv, in the same process.
//
// Why: the daemon links OpenCV, PCL and through them VTK, GDAL and some 190 shared libraries;
// mapping and relocating them takes 50 ms on a quiet machine and several hundred on a loaded one,
// before any code of the program can run. A SIGTERM in that time (a unit stopped right after it
// was started) killed the process: exit 143 instead of a clean stop. This launcher is linked
// statically and does nothing else, so its signals are blocked microseconds after the exec; the
// mask and any signal already pending survive execv, and the daemon's signal thread takes them.
#include <errno.h>
#include <limits.h>
#include <signal.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#ifndef STAIRGUIDED_CORE
#define STAIRGUIDED_CORE "/usr/libexec/stairguide/stairguided-core"
#endif

namespace {

void block_stop_signals(int, char**, char**) {
  sigset_t sigs;
  sigemptyset(&sigs);
  sigaddset(&sigs, SIGTERM);
  sigaddset(&sigs, SIGINT);
  sigaddset(&sigs, SIGHUP);
  sigprocmask(SIG_BLOCK, &sigs, nullptr);
}
// Before main and the C++ runtime's constructors.
__attribute__((section(".preinit_array"), used)) void (*const block_early)(int, char**,
                                                                           char**) = block_stop_signals;

}  // namespace

int main(int, char** argv) {
  block_stop_signals(0, nullptr, nullptr);
  // The daemon beside this binary (the build tree), else where it is installed.
  char self[PATH_MAX];
  const ssize_t n = readlink("/proc/self/exe", self, sizeof self - 1);
  static const char kName[] = "/stairguided-core";
  if (n > 0) {
    self[n] = '\0';
    char* slash = strrchr(self, '/');
    if (slash && static_cast<size_t>(slash - self) + sizeof kName <= sizeof self) {
      memcpy(slash, kName, sizeof kName);
      execv(self, argv);
      if (errno != ENOENT) {
        fprintf(stderr, "stairguided: cannot run %s: %s\n", self, strerror(errno));
        return 126;
      }
    }
  }
  execv(STAIRGUIDED_CORE, argv);
  fprintf(stderr, "stairguided: cannot run %s: %s\n", STAIRGUIDED_CORE, strerror(errno));
  return 127;
}
