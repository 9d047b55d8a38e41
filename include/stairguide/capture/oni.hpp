#pragma once
/// \file oni.hpp
/// OpenNI2 .oni recordings: a FrameSource replaying one through OpenNI2's own player, and a
/// writer producing .oni files that player plays back (OpenNI2 itself cannot record without a
/// device, so the writer emits the container records directly, uncompressed).

#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>

#include "stairguide/capture/frame_source.hpp"

namespace stairguide {

struct OniOptions {
  /// s to wait for the player to deliver a frame before the replay counts as ended early (a
  /// truncated recording never delivers its announced last frames).
  double frame_timeout = 2.0;
  bool use_color = true;           ///< replay the colour stream when the recording has one
  bool depth_registration = true;  ///< ask for depth-to-colour registration where allowed
};

/// Replays an .oni file through OpenNI2's player in frame-exact manual mode (speed -1, repeat
/// off): every depth frame in order, each paired with the colour frame read after it, until the
/// number of frames the recording announces. A recording that ends early (truncated) ends the
/// replay with kEnd and a message naming the file and the frame count.
///
/// Intrinsics: from the recording's field of view (colour stream's when depth is registered to
/// colour, else depth's), principal point at the image centre; without a field of view, the
/// 640x480 Kinect defaults (f 525) scaled to the recording's size.
class OniSource : public FrameSource {
 public:
  /// Throws SourceError naming the file when it is missing, not a file, or not a playable
  /// recording (corrupt, truncated header, no depth stream).
  explicit OniSource(const std::string& path, const OniOptions& options = {});
  ~OniSource() override;
  OniSource(const OniSource&) = delete;
  OniSource& operator=(const OniSource&) = delete;

  ReadResult read(RgbdFrame& out) override;
  CameraIntrinsics intrinsics() const override;
  long frame_count() const override;
  std::string describe() const override;

  bool has_color() const;
  bool registered() const;  ///< depth-to-colour registration was switched on in the player
  /// Frames the player skipped (frame numbers that jumped); 0 for a good replay.
  long skipped_frames() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Writes an .oni file (format 1.0.1.0, the one OpenNI2's Recorder writes) with a depth stream
/// (DEPTH_1_MM, uncompressed) and, when `with_color`, an RGB888 colour stream (uncompressed),
/// frames interleaved depth then colour. Depth is stored as round(depth_m * 1000) mm; readings
/// beyond 65.535 m become 0. The field of view is stored from the intrinsics (the principal point
/// is not representable in the format: readers assume the image centre). Timestamps come from the
/// frames (s -> us, made strictly increasing). Complete after close() (also called by the
/// destructor, which swallows errors).
class OniWriter {
 public:
  OniWriter(const std::string& path, const CameraIntrinsics& intrinsics, bool with_color = true,
            int fps = 30);
  ~OniWriter();
  OniWriter(const OniWriter&) = delete;
  OniWriter& operator=(const OniWriter&) = delete;

  /// Throws SourceError naming the file on a write failure or a frame of the wrong size/type.
  /// A frame without colour gets a black colour frame when the file has a colour stream.
  void write(const RgbdFrame& frame);
  void close();
  long frames_written() const { return frames_; }

 private:
  void write_node_headers();
  void patch_counts();
  std::string path_;
  CameraIntrinsics intrinsics_;
  bool with_color_;
  int fps_;
  std::FILE* f_ = nullptr;
  long frames_ = 0;
  std::uint64_t last_ts_us_ = 0;
  std::uint64_t first_ts_us_ = 0;
  long node_added_pos_[2] = {0, 0};
  long data_begin_pos_[2] = {0, 0};
  bool closed_ = false;
};

}  // namespace stairguide
