#pragma once
/// \file device.hpp
/// The live OpenNI2 camera (Asus Xtion / Kinect class).

#include <memory>
#include <string>

#include "stairguide/capture/frame_source.hpp"

namespace stairguide {

/// A live OpenNI2 device: depth + colour at the configured mode (640x480 at 30 Hz by default),
/// depth registered to colour when the device allows it and the config asks for it, mirroring as
/// configured (off for a body camera), depth/colour frame sync on. read() waits up to
/// `read_timeout` for a depth frame and reports kTimeout when none came (the caller decides when
/// the camera counts as lost and reopens it); kError when the device is gone, at once when OpenNI2
/// reports it disconnected (a USB unplug fires its device-disconnected event), without waiting
/// out `read_timeout`. A source whose device was unplugged stays dead: open a new one.
class DeviceSource : public FrameSource {
 public:
  /// Opens `uri` (empty: config.device_uri, and when that is empty too the first camera found).
  /// Throws SourceError naming the device when there is no camera, it cannot be opened, or it has
  /// no depth mode matching the config.
  explicit DeviceSource(const CaptureConfig& config, const std::string& uri = {});
  ~DeviceSource() override;
  DeviceSource(const DeviceSource&) = delete;
  DeviceSource& operator=(const DeviceSource&) = delete;

  ReadResult read(RgbdFrame& out) override;
  CameraIntrinsics intrinsics() const override;
  std::string describe() const override;
  bool is_live() const override { return true; }

  bool registered() const;
  /// Depth frames delivered without a colour frame (colour late or missing).
  long frames_without_color() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace stairguide
