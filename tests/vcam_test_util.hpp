#pragma once
// Helpers for the tests on the virtual OpenNI2 camera (src/vcam): a staircase dataset folder for
// it to serve, its control file, and running this test binary with OpenNI2 taking its drivers from
// the build's vcam/ folder. Header-only: each test binary includes it once.
#include <dlfcn.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "stairguide/capture/dataset.hpp"
#include "stairguide/capture/synth_source.hpp"

namespace stairguide::test {

/// The folder the build makes for the virtual camera (libOpenNI2.so.0 link, OpenNI2/Drivers/).
inline std::string vcam_dir() { return STAIRGUIDE_VCAM_DIR; }

/// The path of the libOpenNI2 this process loaded ("" when none is loaded).
inline std::string loaded_openni2() {
  void* sym = dlsym(RTLD_DEFAULT, "oniInitialize");
  Dl_info info{};
  if (!sym || !dladdr(sym, &info) || !info.dli_fname) return {};
  return info.dli_fname;
}

/// OpenNI2 looks for its drivers beside the library the process loaded, and the dynamic loader
/// chose that at start: a binary started without LD_LIBRARY_PATH=vcam_dir() runs itself again
/// with it (once; the arguments kept), before main, so that ctest and a run by hand both work.
inline void reexec_with_vcam_drivers() {
  if (loaded_openni2().rfind(vcam_dir() + "/", 0) == 0 || std::getenv("SGVCAM_REEXEC")) return;
  std::ifstream f("/proc/self/cmdline", std::ios::binary);
  const std::string all((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  std::vector<std::string> args;
  for (std::size_t at = 0; at < all.size();) {
    const std::size_t end = all.find('\0', at);
    args.push_back(all.substr(at, end == std::string::npos ? std::string::npos : end - at));
    if (end == std::string::npos) break;
    at = end + 1;
  }
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  const char* old = std::getenv("LD_LIBRARY_PATH");
  setenv("LD_LIBRARY_PATH", (vcam_dir() + (old && *old ? std::string(":") + old : std::string())).c_str(), 1);
  setenv("SGVCAM_REEXEC", "1", 1);
  execv("/proc/self/exe", argv.data());
  // execv failed: carry on; the tests say that the virtual camera's driver is not loaded.
}

/// Writes `frames` frames of a synthetic preset (default size, 640x480) into `dir` as a dataset
/// folder, unless it holds one already; the write goes to a temporary folder renamed at the end, as
/// ctest may run two test cases (processes) at once.
inline void write_vcam_dataset(const std::filesystem::path& dir, const std::string& preset, long frames,
                               std::uint32_t seed) {
  namespace fs = std::filesystem;
  if (fs::exists(dir / "depth.txt")) return;
  const fs::path tmp = dir.string() + ".part" + std::to_string(getpid());
  fs::remove_all(tmp);
  fs::create_directories(dir.parent_path());
  {
    auto src = synth::make_source(preset, frames, seed);
    DatasetWriter w(tmp.string(), src->intrinsics());
    RgbdFrame f;
    for (long i = 0; i < frames; ++i) {
      if (!src->read(f).ok()) break;
      const auto truth = src->truth();
      w.write(f, truth ? &*truth : nullptr);
    }
    w.close();
  }
  std::error_code ec;
  fs::rename(tmp, dir, ec);
  if (ec) fs::remove_all(tmp);  // another process was first: its folder is the same
}

/// Plugs the virtual camera in or out through its control file.
inline void set_plugged(const std::filesystem::path& control, bool plugged) {
  const std::filesystem::path tmp = control.string() + ".tmp";
  {
    std::ofstream f(tmp);
    f << (plugged ? "plugged\n" : "unplugged\n");
  }
  std::filesystem::rename(tmp, control);  // the driver never reads half a word
}

}  // namespace stairguide::test
