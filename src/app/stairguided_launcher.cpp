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

#include "stop_signals.hpp"

#ifndef STAIRGUIDED_CORE
#define STAIRGUIDED_CORE "/usr/libexec/stairguide/stairguided-core"
#endif

namespace {

using stairguide_app::block_stop_signals;
// Before main and the C++ runtime's constructors.
__attribute__((section(".preinit_array"), used)) void (*const block_early)(int, char**,
                                                                           char**) = block_stop_signals;

}  // namespace

#ifndef STAIRGUIDED_CORE_FROM_BINDIR
#define STAIRGUIDED_CORE_FROM_BINDIR "../libexec/stairguide/stairguided-core"
#endif

// Runs `dir`/`name` when it exists; returns only when it does not (0) or cannot be run (126).
int exec_in(const char* dir, size_t dir_len, const char* name, char** argv) {
  char path[PATH_MAX];
  const size_t name_len = strlen(name);
  if (dir_len + 1 + name_len + 1 > sizeof path) return 0;
  memcpy(path, dir, dir_len);
  path[dir_len] = '/';
  memcpy(path + dir_len + 1, name, name_len + 1);
  execv(path, argv);
  if (errno == ENOENT || errno == ENOTDIR) return 0;
  fprintf(stderr, "stairguided: cannot run %s: %s\n", path, strerror(errno));
  return 126;
}

int main(int, char** argv) {
  block_stop_signals(0, nullptr, nullptr);
  // The daemon beside this binary (the build tree), else where this install put it relative to
  // this binary (any prefix, or an install staged under DESTDIR), else where it was configured.
  char self[PATH_MAX];
  const ssize_t n = readlink("/proc/self/exe", self, sizeof self - 1);
  if (n > 0) {
    self[n] = '\0';
    if (const char* slash = strrchr(self, '/')) {
      const size_t dir_len = static_cast<size_t>(slash - self);
      static const char* const kNames[] = {"stairguided-core", STAIRGUIDED_CORE_FROM_BINDIR};
      for (const char* name : kNames)
        if (const int code = exec_in(self, dir_len, name, argv)) return code;
    }
  }
  execv(STAIRGUIDED_CORE, argv);
  fprintf(stderr, "stairguided: cannot run %s: %s\n", STAIRGUIDED_CORE, strerror(errno));
  return 127;
}
