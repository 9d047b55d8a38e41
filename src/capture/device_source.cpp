// Live OpenNI2 camera.
#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <opencv2/imgproc.hpp>

#include "capture_util.hpp"
#include "openni_util.hpp"
#include "stairguide/capture/device.hpp"

namespace stairguide {
namespace {

// Picks the supported mode of the requested size, rate and pixel format.
bool find_mode(const openni::SensorInfo* info, int w, int h, int fps, openni::PixelFormat fmt,
               openni::VideoMode& out) {
  if (!info) return false;
  const auto& modes = info->getSupportedVideoModes();
  for (int i = 0; i < modes.getSize(); ++i) {
    const openni::VideoMode& m = modes[i];
    if (m.getResolutionX() == w && m.getResolutionY() == h && m.getFps() == fps &&
        m.getPixelFormat() == fmt) {
      out = m;
      return true;
    }
  }
  return false;
}

std::string list_modes(const openni::SensorInfo* info) {
  if (!info) return "none";
  std::string s;
  const auto& modes = info->getSupportedVideoModes();
  for (int i = 0; i < modes.getSize(); ++i) {
    const openni::VideoMode& m = modes[i];
    s += (i ? ", " : "") + std::to_string(m.getResolutionX()) + "x" + std::to_string(m.getResolutionY()) +
         "@" + std::to_string(m.getFps()) + " fmt " + std::to_string(static_cast<int>(m.getPixelFormat()));
  }
  return s.empty() ? "none" : s;
}

}  // namespace

// Not in the anonymous namespace: DeviceSource::Impl (declared in the public header) holds one.
namespace device_detail {
// OpenNI2's device-disconnected event (a USB unplug) for one URI: read() reports the camera gone
// at once instead of after read_timeout without frames. Raised on the driver's thread.
struct UnplugListener : openni::OpenNI::DeviceDisconnectedListener {
  std::string uri;
  std::atomic<bool> gone{false};
  void onDeviceDisconnected(const openni::DeviceInfo* info) override {
    if (info && uri == info->getUri()) gone = true;
  }
};
}  // namespace device_detail

struct DeviceSource::Impl {
  CaptureConfig config;
  std::string uri;   ///< as asked ("" = first camera)
  std::string name;  ///< for messages
  openni::Device device;
  openni::VideoStream depth, color;
  openni::VideoFrameRef depth_ref, color_ref;
  bool has_color = false;
  bool registered = false;
  long without_color = 0;
  std::uint64_t next = 0;
  CameraIntrinsics k;
  device_detail::UnplugListener unplug;
  bool listening = false;

  ~Impl() {
    if (listening) openni::OpenNI::removeDeviceDisconnectedListener(&unplug);
    if (color.isValid()) {
      color.stop();
      color.destroy();
    }
    if (depth.isValid()) {
      depth.stop();
      depth.destroy();
    }
    if (device.isValid()) device.close();
  }
};

DeviceSource::DeviceSource(const CaptureConfig& config, const std::string& uri)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.config = config;
  m.uri = uri.empty() ? config.device_uri : uri;
  m.name = m.uri.empty() ? "OpenNI2 device (first camera found)" : "OpenNI2 device '" + m.uri + "'";
  const std::string init = ensure_openni();
  if (!init.empty()) throw SourceError(m.name + ": OpenNI2 unavailable: " + init);
  openni::Array<openni::DeviceInfo> found;
  openni::OpenNI::enumerateDevices(&found);
  // Recordings are not cameras: count only devices whose URI is not a file.
  int cameras = 0;
  std::string uris;
  for (int i = 0; i < found.getSize(); ++i) {
    std::error_code ec;
    if (std::filesystem::exists(found[i].getUri(), ec)) continue;
    ++cameras;
    uris += std::string(cameras > 1 ? ", " : "") + found[i].getUri();
  }
  if (m.uri.empty() && cameras == 0)
    throw SourceError(m.name +
                      ": no camera found (is it plugged in and powered, and is the user in group 'video'?)");
  if (m.device.open(m.uri.empty() ? openni::ANY_DEVICE : m.uri.c_str()) != openni::STATUS_OK)
    throw SourceError(m.name + ": cannot open: " + openni_error("open failed") +
                      (cameras ? " (cameras found: " + uris + ")" : " (no camera found)"));
  const openni::DeviceInfo& info = m.device.getDeviceInfo();
  m.unplug.uri = info.getUri();
  m.listening = openni::OpenNI::addDeviceDisconnectedListener(&m.unplug) == openni::STATUS_OK;
  m.name =
      std::string("OpenNI2 device ") + info.getVendor() + " " + info.getName() + " (" + info.getUri() + ")";

  openni::VideoMode dm, cm;
  if (!find_mode(m.device.getSensorInfo(openni::SENSOR_DEPTH), config.width, config.height, config.fps,
                 openni::PIXEL_FORMAT_DEPTH_1_MM, dm))
    throw SourceError(m.name + ": no depth mode " + std::to_string(config.width) + "x" +
                      std::to_string(config.height) + "@" + std::to_string(config.fps) +
                      " in millimetres (modes: " + list_modes(m.device.getSensorInfo(openni::SENSOR_DEPTH)) +
                      ")");
  if (m.depth.create(m.device, openni::SENSOR_DEPTH) != openni::STATUS_OK ||
      m.depth.setVideoMode(dm) != openni::STATUS_OK)
    throw SourceError(m.name + ": cannot set up the depth stream: " + openni_error(""));
  m.has_color = find_mode(m.device.getSensorInfo(openni::SENSOR_COLOR), config.width, config.height,
                          config.fps, openni::PIXEL_FORMAT_RGB888, cm) &&
                m.color.create(m.device, openni::SENSOR_COLOR) == openni::STATUS_OK &&
                m.color.setVideoMode(cm) == openni::STATUS_OK;
  m.depth.setMirroringEnabled(config.mirroring);
  if (m.has_color) {
    m.color.setMirroringEnabled(config.mirroring);
    m.device.setDepthColorSyncEnabled(true);
    if (config.depth_registration &&
        m.device.isImageRegistrationModeSupported(openni::IMAGE_REGISTRATION_DEPTH_TO_COLOR))
      m.registered =
          m.device.setImageRegistrationMode(openni::IMAGE_REGISTRATION_DEPTH_TO_COLOR) == openni::STATUS_OK;
  }
  if (m.depth.start() != openni::STATUS_OK)
    throw SourceError(m.name + ": cannot start the depth stream: " + openni_error(""));
  if (m.has_color && m.color.start() != openni::STATUS_OK)
    throw SourceError(m.name + ": cannot start the colour stream: " + openni_error(""));
  const openni::VideoStream& geo = m.registered ? m.color : m.depth;
  const float hfov = geo.getHorizontalFieldOfView(), vfov = geo.getVerticalFieldOfView();
  if (std::isfinite(hfov) && hfov > 0.05f && hfov < 3.0f && std::isfinite(vfov) && vfov > 0.05f &&
      vfov < 3.0f)
    m.k = intrinsics_from_fov(config.width, config.height, hfov, vfov);
  else
    m.k = default_intrinsics(config.width, config.height);
}

DeviceSource::~DeviceSource() = default;

ReadResult DeviceSource::read(RgbdFrame& out) {
  Impl& m = *impl_;
  const int timeout_ms = std::max(1, static_cast<int>(std::lround(m.config.read_timeout * 1000.0)));
  openni::VideoStream* ds[] = {&m.depth};
  int ready = -1;
  // Waits in slices so that an unplug, which stops the frames, is reported when it happens.
  const auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
  openni::Status st = openni::STATUS_TIME_OUT;
  for (;;) {
    if (m.unplug.gone)
      return {ReadStatus::kError, m.name + ": unplugged (OpenNI2 reported the device disconnected)"};
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(until - std::chrono::steady_clock::now())
            .count();
    if (left <= 0) break;
    st = openni::OpenNI::waitForAnyStream(ds, 1, &ready, static_cast<int>(std::min<long long>(left, 100)));
    if (st != openni::STATUS_TIME_OUT) break;
  }
  if (st == openni::STATUS_TIME_OUT)
    return {ReadStatus::kTimeout,
            m.name + ": no depth frame within " + fmt_num(m.config.read_timeout) + " s"};
  if (st != openni::STATUS_OK || m.depth.readFrame(&m.depth_ref) != openni::STATUS_OK ||
      !m.depth_ref.isValid())
    return {ReadStatus::kError,
            m.name + ": reading depth failed (device lost?): " + openni_error("read failed")};
  if (!depth_frame_to_metres(m.depth_ref, out.depth))
    return {ReadStatus::kError, m.name + ": unexpected depth pixel format"};
  out.timestamp = static_cast<double>(m.depth_ref.getTimestamp()) * 1e-6;
  out.color.release();
  out.gray.release();
  if (m.has_color) {
    // With frame sync on, the matching colour frame arrives with the depth one; allow two frame
    // periods before giving depth alone (counted).
    openni::VideoStream* cs[] = {&m.color};
    const int wait_ms = std::max(1, 2000 / std::max(1, m.config.fps));
    if (openni::OpenNI::waitForAnyStream(cs, 1, &ready, wait_ms) == openni::STATUS_OK &&
        m.color.readFrame(&m.color_ref) == openni::STATUS_OK && color_frame_to_bgr(m.color_ref, out.color) &&
        out.color.size() == out.depth.size())
      cv::cvtColor(out.color, out.gray, cv::COLOR_BGR2GRAY);
    else {
      out.color.release();
      ++m.without_color;
    }
  }
  out.index = m.next++;
  out.intrinsics = m.k;
  return {};
}

CameraIntrinsics DeviceSource::intrinsics() const { return impl_->k; }
std::string DeviceSource::describe() const { return impl_->name; }
bool DeviceSource::registered() const { return impl_->registered; }
long DeviceSource::frames_without_color() const { return impl_->without_color; }

}  // namespace stairguide
