#pragma once
// Opening the input a command reads frames from, with the command's own words when it cannot be.

#include <cstdio>
#include <memory>
#include <string>

#include "stairguide/capture/frame_source.hpp"

namespace stairguide::cli {

/// `input` opened as a frame source (open_frame_source); when it cannot be, "WHO: why" goes to
/// stderr and the result is null (the command then exits 1).
inline std::unique_ptr<FrameSource> open_input(const std::string& input, const CaptureConfig& config,
                                               const char* who) {
  try {
    return open_frame_source(input, config);
  } catch (const SourceError& e) {
    std::fprintf(stderr, "%s: %s\n", who, e.what());
    return nullptr;
  }
}

}  // namespace stairguide::cli
