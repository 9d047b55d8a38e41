#pragma once
// Helpers shared by the capture tests (dataset, .oni, device): a scratch folder, hand-made frames
// and the message of a SourceError. Header-only: each test binary includes it once.
#include <filesystem>
#include <opencv2/core.hpp>
#include <random>
#include <string>
#include <vector>

#include "stairguide/capture/frame_source.hpp"
#include "stairguide/core/types.hpp"

namespace stairguide::test {

/// An empty path `name` under the build tree's test_scratch/`group` (removed if it exists).
inline std::filesystem::path scratch(const std::string& group, const std::string& name) {
  const std::filesystem::path dir = std::filesystem::path(STAIRGUIDE_BINARY_DIR) / "test_scratch" / group;
  std::filesystem::create_directories(dir);
  const std::filesystem::path p = dir / name;
  std::filesystem::remove_all(p);
  return p;
}

/// `n` frames of w x h made here (the synthetic renderer is tested on its own): depth on the 1 mm
/// grid (what PNG and .oni store exactly) between 0.4 m and `max_mm`, with holes every few pixels;
/// colour random; timestamps from `t0` at 30 Hz.
inline std::vector<RgbdFrame> make_frames(int n, int w, int h, std::uint32_t seed, int max_mm, double t0) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> mm(400, max_mm);
  std::vector<RgbdFrame> out;
  for (int i = 0; i < n; ++i) {
    RgbdFrame f;
    f.index = static_cast<std::uint64_t>(i);
    f.timestamp = t0 + i / 30.0;
    f.intrinsics = CameraIntrinsics{}.scaled(static_cast<float>(w) / 640.f);
    f.depth.create(h, w, CV_32FC1);
    for (int r = 0; r < h; ++r)
      for (int c = 0; c < w; ++c) f.depth.at<float>(r, c) = ((r + c + i) % 7 == 0) ? 0.f : mm(rng) / 1000.f;
    f.color.create(h, w, CV_8UC3);
    cv::randu(f.color, 0, 256);
    out.push_back(f);
  }
  return out;
}

/// The message of the SourceError `f` throws, or "(no error)".
template <class F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const SourceError& e) {
    return e.what();
  }
  return "(no error)";
}

}  // namespace stairguide::test
