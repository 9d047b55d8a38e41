#pragma once
// Writing a command's picture (an overlay, a plot), with the command's own words when it cannot be.

#include <cstdio>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>

namespace stairguide::cli {

/// `img` written to `path` (the format by its extension); when it cannot be, "WHO: cannot write
/// PATH ..." goes to stderr and the result is false (the command then exits 1).
inline bool write_image(const std::string& path, const cv::Mat& img, const char* who) {
  try {
    if (cv::imwrite(path, img)) return true;
    std::fprintf(stderr, "%s: cannot write %s (unknown extension or unwritable folder)\n", who, path.c_str());
  } catch (const cv::Exception& e) {
    std::fprintf(stderr, "%s: cannot write %s: %s\n", who, path.c_str(), e.what());
  }
  return false;
}

}  // namespace stairguide::cli
