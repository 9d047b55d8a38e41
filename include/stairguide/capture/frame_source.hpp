#pragma once
/// \file frame_source.hpp
/// One interface for every input: OpenNI2 device, .oni recording, dataset folder, synthetic scene.

#include <memory>
#include <optional>
#include <string>

#include "stairguide/core/config.hpp"
#include "stairguide/core/ground_truth.hpp"
#include "stairguide/core/source_error.hpp"
#include "stairguide/core/types.hpp"

namespace stairguide {

enum class ReadStatus {
  kOk,       ///< a frame was read
  kEnd,      ///< the recording or sequence ended cleanly, after every frame it holds
  kTimeout,  ///< live camera: no frame within the timeout (may come back)
  kError     ///< unreadable frame, lost device, or a recording that ends before the frames it
             ///< announces (truncated); see message
};

struct ReadResult {
  ReadStatus status = ReadStatus::kOk;
  std::string message;  ///< empty on kOk; names the file/device and the problem otherwise
  bool ok() const { return status == ReadStatus::kOk; }
};

/// A stream of RGB-D frames. Not thread-safe: one thread reads it.
class FrameSource {
 public:
  virtual ~FrameSource() = default;

  /// Reads the next frame into `out` (reusing its buffers where it can).
  virtual ReadResult read(RgbdFrame& out) = 0;

  /// Intrinsics of the frames this source gives.
  virtual CameraIntrinsics intrinsics() const = 0;

  /// Number of frames, or -1 when unknown (live camera).
  virtual long frame_count() const { return -1; }

  /// Human-readable name ("dataset /path", "oni file.oni", "OpenNI2 device ...", "synthetic NAME").
  virtual std::string describe() const = 0;

  /// Ground truth of the frame last read, where the source has it (synthetic, labelled dataset).
  virtual std::optional<FrameTruth> truth() const { return std::nullopt; }

  /// True for a live device (pacing comes from the device, reconnection makes sense).
  virtual bool is_live() const { return false; }

  /// True when consecutive frames are unrelated views (a static synthetic preset draws a new scene
  /// for every index): tracking from one frame to the next means nothing there.
  virtual bool independent_frames() const { return false; }
};

/// Why `path` cannot be read, in words for a person: "" when it can be opened for reading (a
/// directory when `directory`), else "no such file", "permission denied", "a symbolic link loop
/// (too many levels of symbolic links)", "not a directory" (a component of the path), or the
/// system's words. Permission denied must not read as missing or corrupt (issue 41).
std::string why_unreadable(const std::string& path, bool directory = false);
/// The words why_unreadable() uses for an errno value (ENOENT, EACCES, ELOOP, ...).
std::string errno_words(int err);

/// Opens an input by name: a directory is a dataset folder, a path ending in .oni an OpenNI2
/// recording, "device" or "device:URI" the live camera, "synth:SCENE[:FRAMES[:SEED]]" the renderer.
/// Depth outside [config.min_range, config.max_range] reads as no reading (0), whatever the source.
/// Throws SourceError with a clear message when it cannot.
std::unique_ptr<FrameSource> open_frame_source(const std::string& input, const CaptureConfig& config);

}  // namespace stairguide
