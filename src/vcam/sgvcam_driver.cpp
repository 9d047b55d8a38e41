// sgvcam: a virtual OpenNI2 camera, as an OpenNI2 driver (libsgvcam.so.0), for tests of the live
// `device:` path through the real openni::Device API.
//
// What it serves: a dataset folder (as `stairguide synth` writes it) named by $SGVCAM_DATASET,
// loaded once when OpenNI2 initializes the driver (at most kMaxFrames frames, decoded into memory
// so that serving costs no decoding), then played in a loop at 30 Hz on the wall clock: a depth
// stream (DEPTH_1_MM) and, when the folder has rgb.txt, a colour stream (RGB888), both at the
// folder's image size, with the fields of view of its camera.yaml. The device's URI is
// "sgvcam://0". Without $SGVCAM_DATASET the driver has no device at all.
//
// Both paths must be absolute (OpenNI2 initializes its drivers from inside their folder).
// Unplug and replug: $SGVCAM_CONTROL names a file polled every frame period. "unplugged" (on its
// own, surrounding white space ignored) unplugs the camera as a USB unplug does: its streams stop
// delivering, OpenNI2's device-disconnected event fires and the device leaves the enumeration;
// handles opened before stay dead. "plugged", or no file, plugs it back in: device-connected fires
// and the device can be enumerated and opened again. Anything else is reported once on stderr and
// changes nothing.
//
// How a process gets OpenNI2 to load this driver (Debian's libOpenNI2 reads /etc/openni2/OpenNI.ini,
// an absolute path, and looks for drivers in "OpenNI2/Drivers/lib*.so.0" beside the libOpenNI2.so.0
// the process loaded, as dladdr names it): the build makes build/vcam/ with a symbolic link
// libOpenNI2.so.0 to the system library and OpenNI2/Drivers/ holding this driver and a link to
// OpenNI2's own file driver (so .oni replay keeps working); LD_LIBRARY_PATH=build/vcam makes the
// dynamic loader take the library through the link, and OpenNI2 then loads the drivers of
// build/vcam/OpenNI2/Drivers instead of the system ones. Nothing outside the build tree changes.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <mutex>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

// The driver API's export macro allocates with OpenNI's XnLib macros, which its public headers lack.
#define XN_NEW(type, arg) new type(arg)
#define XN_DELETE(p) delete (p)
#include <Driver/OniDriverAPI.h>

namespace {

constexpr const char* kUri = "sgvcam://0";
constexpr int kFps = 30;
constexpr std::size_t kMaxFrames = 120;  // 4 s of loop; ~1.5 MB a frame at 640x480

/// The frames, decoded: depth in millimetres, colour as RGB, both rows packed.
struct Clip {
  int width = 0, height = 0;
  float hfov = 0.f, vfov = 0.f;  // rad
  std::vector<std::vector<std::uint16_t>> depth;
  std::vector<std::vector<std::uint8_t>> rgb;  // empty: no colour stream
};

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return {};
  return s.substr(b, s.find_last_not_of(" \t\r\n") - b + 1);
}

/// "timestamp path" lines of depth.txt / rgb.txt, paths relative to the folder.
std::vector<std::string> read_list(const std::string& dir, const std::string& name, bool required) {
  std::ifstream f(dir + "/" + name);
  if (!f) {
    if (required) throw std::runtime_error(dir + "/" + name + ": missing (is this a dataset folder?)");
    return {};
  }
  std::vector<std::string> paths;
  std::string line;
  while (std::getline(f, line)) {
    line = trim(line);
    if (line.empty() || line[0] == '#') continue;
    std::istringstream is(line);
    double t = 0.0;
    std::string p;
    if (!(is >> t >> p)) throw std::runtime_error(dir + "/" + name + ": bad line '" + line + "'");
    paths.push_back(dir + "/" + p);
  }
  if (paths.empty() && required) throw std::runtime_error(dir + "/" + name + ": lists no images");
  return paths;
}

Clip load_clip(const std::string& dir) {
  // camera.yaml: flat "key: value" lines (the project's reader validates it fully; the driver
  // needs four numbers and refuses what it cannot use).
  double fx = 0, fy = 0, scale = 0;
  int w = 0, h = 0;
  {
    std::ifstream f(dir + "/camera.yaml");
    if (!f) throw std::runtime_error(dir + "/camera.yaml: missing");
    std::string line;
    while (std::getline(f, line)) {
      const auto c = line.find('#');
      if (c != std::string::npos) line.resize(c);
      const auto colon = line.find(':');
      if (colon == std::string::npos) continue;
      const std::string key = trim(line.substr(0, colon)), val = trim(line.substr(colon + 1));
      const double v = std::atof(val.c_str());
      if (key == "fx") fx = v;
      if (key == "fy") fy = v;
      if (key == "width") w = static_cast<int>(v);
      if (key == "height") h = static_cast<int>(v);
      if (key == "depth_scale") scale = v;
    }
    if (!(fx > 0 && fy > 0 && w > 0 && h > 0 && scale > 0))
      throw std::runtime_error(dir + "/camera.yaml: needs positive fx, fy, width, height and depth_scale");
  }
  Clip clip;
  clip.width = w;
  clip.height = h;
  clip.hfov = static_cast<float>(2.0 * std::atan(w / (2.0 * fx)));
  clip.vfov = static_cast<float>(2.0 * std::atan(h / (2.0 * fy)));
  const auto depth = read_list(dir, "depth.txt", true);
  const auto rgb = read_list(dir, "rgb.txt", false);
  if (!rgb.empty() && rgb.size() != depth.size())
    throw std::runtime_error(dir + ": depth.txt lists " + std::to_string(depth.size()) + " images, rgb.txt " +
                             std::to_string(rgb.size()));
  const std::size_t n = std::min(depth.size(), kMaxFrames);
  for (std::size_t i = 0; i < n; ++i) {
    const cv::Mat d = cv::imread(depth[i], cv::IMREAD_UNCHANGED);
    if (d.empty() || d.type() != CV_16UC1 || d.cols != w || d.rows != h)
      throw std::runtime_error(depth[i] + ": not a 16-bit " + std::to_string(w) + "x" + std::to_string(h) +
                               " depth PNG");
    std::vector<std::uint16_t> mm(static_cast<std::size_t>(w) * static_cast<std::size_t>(h));
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const long m = std::lround(d.at<std::uint16_t>(y, x) * 1000.0 / scale);
        mm[static_cast<std::size_t>(y) * static_cast<std::size_t>(w) + static_cast<std::size_t>(x)] =
            static_cast<std::uint16_t>(std::min<long>(65535, m));
      }
    clip.depth.push_back(std::move(mm));
    if (rgb.empty()) continue;
    const cv::Mat c = cv::imread(rgb[i], cv::IMREAD_COLOR);  // BGR
    if (c.empty() || c.cols != w || c.rows != h)
      throw std::runtime_error(rgb[i] + ": not a " + std::to_string(w) + "x" + std::to_string(h) +
                               " colour image");
    std::vector<std::uint8_t> px(static_cast<std::size_t>(w) * static_cast<std::size_t>(h) * 3);
    std::size_t k = 0;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x, k += 3) {
        const cv::Vec3b& b = c.at<cv::Vec3b>(y, x);
        px[k] = b[2];
        px[k + 1] = b[1];
        px[k + 2] = b[0];
      }
    clip.rgb.push_back(std::move(px));
  }
  return clip;
}

class VcamDevice;

class VcamStream : public oni::driver::StreamBase {
 public:
  VcamStream(OniSensorType type, const OniVideoMode& mode, float hfov, float vfov)
      : type_(type), mode_(mode), hfov_(hfov), vfov_(vfov) {}

  OniStatus start() override {
    started_ = true;
    return ONI_STATUS_OK;
  }
  void stop() override { started_ = false; }
  bool started() const { return started_; }
  OniSensorType type() const { return type_; }

  int getRequiredFrameSize() override { return mode_.resolutionX * mode_.resolutionY * bpp(); }

  OniBool isPropertySupported(int id) override {
    return id == ONI_STREAM_PROPERTY_VIDEO_MODE || id == ONI_STREAM_PROPERTY_HORIZONTAL_FOV ||
           id == ONI_STREAM_PROPERTY_VERTICAL_FOV || id == ONI_STREAM_PROPERTY_MIRRORING ||
           id == ONI_STREAM_PROPERTY_STRIDE ||
           (type_ == ONI_SENSOR_DEPTH &&
            (id == ONI_STREAM_PROPERTY_MAX_VALUE || id == ONI_STREAM_PROPERTY_MIN_VALUE));
  }

  OniStatus getProperty(int id, void* data, int* size) override {
    switch (id) {
      case ONI_STREAM_PROPERTY_VIDEO_MODE: return put(mode_, data, size);
      case ONI_STREAM_PROPERTY_HORIZONTAL_FOV: return put(hfov_, data, size);
      case ONI_STREAM_PROPERTY_VERTICAL_FOV: return put(vfov_, data, size);
      case ONI_STREAM_PROPERTY_MIRRORING: return put(OniBool(FALSE), data, size);
      case ONI_STREAM_PROPERTY_STRIDE: return put(mode_.resolutionX * bpp(), data, size);
      case ONI_STREAM_PROPERTY_MAX_VALUE:
        return type_ == ONI_SENSOR_DEPTH ? put(int(10000), data, size) : ONI_STATUS_NOT_SUPPORTED;
      case ONI_STREAM_PROPERTY_MIN_VALUE:
        return type_ == ONI_SENSOR_DEPTH ? put(int(0), data, size) : ONI_STATUS_NOT_SUPPORTED;
      default: return ONI_STATUS_NOT_SUPPORTED;
    }
  }

  OniStatus setProperty(int id, const void* data, int size) override {
    if (id == ONI_STREAM_PROPERTY_VIDEO_MODE) {
      // One mode per sensor: the clip's own.
      if (size != static_cast<int>(sizeof(OniVideoMode))) return ONI_STATUS_BAD_PARAMETER;
      const auto* m = static_cast<const OniVideoMode*>(data);
      return m->resolutionX == mode_.resolutionX && m->resolutionY == mode_.resolutionY &&
                     m->fps == mode_.fps && m->pixelFormat == mode_.pixelFormat
                 ? ONI_STATUS_OK
                 : ONI_STATUS_NOT_SUPPORTED;
    }
    if (id == ONI_STREAM_PROPERTY_MIRRORING) {
      // The frames are what they are; mirroring off is the only setting (a body camera's).
      if (size != static_cast<int>(sizeof(OniBool))) return ONI_STATUS_BAD_PARAMETER;
      return *static_cast<const OniBool*>(data) ? ONI_STATUS_NOT_SUPPORTED : ONI_STATUS_OK;
    }
    return ONI_STATUS_NOT_SUPPORTED;
  }

  /// Hands OpenNI2 frame `index` of the clip (called by the driver's clock thread).
  void deliver(const Clip& clip, std::uint64_t index, std::uint64_t timestamp_us) {
    if (!started_) return;
    OniFrame* f = getServices().acquireFrame();
    if (!f) return;
    const std::size_t i = static_cast<std::size_t>(index % clip.depth.size());
    const int bytes = getRequiredFrameSize();
    if (type_ == ONI_SENSOR_DEPTH)
      std::memcpy(f->data, clip.depth[i].data(), static_cast<std::size_t>(bytes));
    else
      std::memcpy(f->data, clip.rgb[i].data(), static_cast<std::size_t>(bytes));
    f->dataSize = bytes;
    f->sensorType = type_;
    f->timestamp = timestamp_us;
    f->frameIndex = static_cast<int>(index & 0x7fffffff);
    f->width = mode_.resolutionX;
    f->height = mode_.resolutionY;
    f->videoMode = mode_;
    f->croppingEnabled = FALSE;
    f->cropOriginX = f->cropOriginY = 0;
    f->stride = mode_.resolutionX * bpp();
    raiseNewFrame(f);
    getServices().releaseFrame(f);
  }

 private:
  int bpp() const { return type_ == ONI_SENSOR_DEPTH ? 2 : 3; }
  template <typename T>
  static OniStatus put(const T& v, void* data, int* size) {
    if (!size || *size < static_cast<int>(sizeof(T))) return ONI_STATUS_BAD_PARAMETER;
    std::memcpy(data, &v, sizeof(T));
    *size = static_cast<int>(sizeof(T));
    return ONI_STATUS_OK;
  }

  OniSensorType type_;
  OniVideoMode mode_;
  float hfov_, vfov_;
  std::atomic<bool> started_{false};
};

class VcamDriver;
std::atomic<VcamDriver*> g_live{nullptr};  // for the exit handler
void stop_at_exit();

class VcamDevice : public oni::driver::DeviceBase {
 public:
  VcamDevice(VcamDriver& driver, std::uint64_t generation);
  ~VcamDevice() override {
    for (auto* s : streams_) delete s;
  }

  OniStatus getSensorInfoList(OniSensorInfo** infos, int* n) override {
    *infos = sensors_;
    *n = sensor_count_;
    return ONI_STATUS_OK;
  }
  oni::driver::StreamBase* createStream(OniSensorType type) override;
  void destroyStream(oni::driver::StreamBase* s) override;

  OniBool isImageRegistrationModeSupported(OniImageRegistrationMode) override { return TRUE; }
  OniBool isPropertySupported(int id) override { return id == ONI_DEVICE_PROPERTY_IMAGE_REGISTRATION; }
  OniStatus getProperty(int id, void* data, int* size) override {
    if (id != ONI_DEVICE_PROPERTY_IMAGE_REGISTRATION || !size || *size < static_cast<int>(sizeof(int)))
      return ONI_STATUS_NOT_SUPPORTED;
    std::memcpy(data, &registration_, sizeof(int));
    *size = sizeof(int);
    return ONI_STATUS_OK;
  }
  OniStatus setProperty(int id, const void* data, int size) override {
    // The clip's colour is registered to its depth already: either mode serves the same frames.
    if (id != ONI_DEVICE_PROPERTY_IMAGE_REGISTRATION || size != static_cast<int>(sizeof(int)))
      return ONI_STATUS_NOT_SUPPORTED;
    std::memcpy(&registration_, data, sizeof(int));
    return ONI_STATUS_OK;
  }

  std::uint64_t generation() const { return generation_; }
  std::vector<VcamStream*>& streams() { return streams_; }

 private:
  VcamDriver& driver_;
  std::uint64_t generation_;  // the plug-in it was opened in; dead after that one ends
  OniVideoMode modes_[2]{};
  OniSensorInfo sensors_[2]{};
  int sensor_count_ = 0;
  int registration_ = ONI_IMAGE_REGISTRATION_OFF;
  std::vector<VcamStream*> streams_;  // guarded by the driver's mutex
};

class VcamDriver : public oni::driver::DriverBase {
 public:
  explicit VcamDriver(OniDriverServices* services) : DriverBase(services) {
    std::memset(&info_, 0, sizeof info_);
    std::snprintf(info_.uri, sizeof info_.uri, "%s", kUri);
    std::snprintf(info_.vendor, sizeof info_.vendor, "stairguide");
    std::snprintf(info_.name, sizeof info_.name, "virtual camera");
  }
  ~VcamDriver() override {
    shutdown();
    g_live = nullptr;
  }

  OniStatus initialize(oni::driver::DeviceConnectedCallback connected,
                       oni::driver::DeviceDisconnectedCallback disconnected,
                       oni::driver::DeviceStateChangedCallback state, void* cookie) override {
    DriverBase::initialize(connected, disconnected, state, cookie);
    const char* dir = std::getenv("SGVCAM_DATASET");
    if (!dir || !*dir) return ONI_STATUS_OK;  // no clip, no camera
    const char* control = std::getenv("SGVCAM_CONTROL");
    try {
      // OpenNI2 initializes its drivers with the current directory changed to theirs: a relative
      // path would name a file in there.
      if (dir[0] != '/') throw std::runtime_error("must be an absolute path");
      if (control && *control && control[0] != '/')
        throw std::runtime_error(std::string("SGVCAM_CONTROL=") + control + " must be an absolute path");
      clip_ = load_clip(dir);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "sgvcam: SGVCAM_DATASET=%s: %s; the virtual camera is not there\n", dir, e.what());
      return ONI_STATUS_OK;
    }
    if (control) control_ = control;
    have_clip_ = true;
    plugged_ = read_control(true);
    if (plugged_) deviceConnected(&info_);
    thread_ = std::thread([this] { run(); });
    // A process that never shuts OpenNI2 down (the project's never does) exits with the clock
    // thread running; stop it before the static objects it calls into (OpenNI2's context, built
    // before this handler was registered) are destroyed.
    g_live = this;
    std::atexit(stop_at_exit);
    return ONI_STATUS_OK;
  }

  oni::driver::DeviceBase* deviceOpen(const char* uri, const char*) override {
    std::lock_guard<std::mutex> lk(mutex_);
    if (!have_clip_ || !uri || std::strcmp(uri, kUri) != 0) return nullptr;
    if (!plugged_) {
      getServices().errorLoggerAppend("sgvcam: %s is unplugged", kUri);
      return nullptr;
    }
    auto* d = new VcamDevice(*this, generation_);
    devices_.push_back(d);
    return d;
  }

  void deviceClose(oni::driver::DeviceBase* base) override {
    std::lock_guard<std::mutex> lk(mutex_);
    auto* d = static_cast<VcamDevice*>(base);
    devices_.erase(std::remove(devices_.begin(), devices_.end(), d), devices_.end());
    delete d;
  }

  OniStatus tryDevice(const char*) override { return ONI_STATUS_ERROR; }

  // Depth and colour frames of one tick carry the same frame index, which is what OpenNI2's
  // frame sync matches; the driver needs no state for it.
  void* enableFrameSync(oni::driver::StreamBase**, int) override { return &sync_token_; }
  void disableFrameSync(void*) override {}

  void shutdown() override {
    {
      std::lock_guard<std::mutex> lk(mutex_);
      quit_ = true;
    }
    wake_.notify_all();
    if (thread_.joinable()) thread_.join();
  }

  const Clip& clip() const { return clip_; }
  std::mutex& mutex() { return mutex_; }

 private:
  /// Reads the control file: true = plugged. A missing file is plugged; unreadable content keeps
  /// the current state and is reported once.
  bool read_control(bool current) {
    if (control_.empty()) return true;
    std::ifstream f(control_);
    if (!f) return true;
    std::stringstream ss;
    ss << f.rdbuf();
    const std::string v = trim(ss.str());
    if (v == "plugged") return true;
    if (v == "unplugged") return false;
    if (v != bad_control_) {
      bad_control_ = v;
      std::fprintf(stderr, "sgvcam: %s: expected 'plugged' or 'unplugged', got '%s'; the camera stays %s\n",
                   control_.c_str(), v.c_str(), current ? "plugged" : "unplugged");
    }
    return current;
  }

  // The camera's clock: a frame of every started stream of the current plug-in each 1/30 s, on an
  // absolute schedule (late ticks are dropped, as a camera drops frames nobody took).
  void run() {
    using Clock = std::chrono::steady_clock;
    const auto period =
        std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / kFps));
    const auto t0 = Clock::now();
    std::uint64_t tick = 0;
    std::unique_lock<std::mutex> lk(mutex_);
    while (!quit_) {
      wake_.wait_until(lk, t0 + period * static_cast<long>(tick + 1), [this] { return quit_; });
      if (quit_) break;
      const auto now = Clock::now();
      tick = static_cast<std::uint64_t>((now - t0) / period);
      const bool plugged = read_control(plugged_);
      if (plugged != plugged_) {
        plugged_ = plugged;
        if (!plugged) ++generation_;  // handles opened so far die with this plug-in
        // OpenNI2 takes its own lock in these callbacks; call them without ours.
        lk.unlock();
        if (plugged)
          deviceConnected(&info_);
        else
          deviceDisconnected(&info_);
        lk.lock();
        continue;
      }
      if (!plugged_) continue;
      const std::uint64_t ts = tick * 1000000ull / kFps;
      for (auto* d : devices_) {
        if (d->generation() != generation_) continue;
        for (auto* s : d->streams()) s->deliver(clip_, tick, ts);
      }
    }
  }

  OniDeviceInfo info_;
  Clip clip_;
  bool have_clip_ = false;
  std::string control_, bad_control_;
  std::mutex mutex_;
  std::condition_variable wake_;
  bool quit_ = false;
  bool plugged_ = false;
  std::uint64_t generation_ = 0;
  std::vector<VcamDevice*> devices_;
  std::thread thread_;
  int sync_token_ = 0;
};

VcamDevice::VcamDevice(VcamDriver& driver, std::uint64_t generation)
    : driver_(driver), generation_(generation) {
  const Clip& c = driver.clip();
  modes_[0] = {ONI_PIXEL_FORMAT_DEPTH_1_MM, c.width, c.height, kFps};
  sensors_[0] = {ONI_SENSOR_DEPTH, 1, &modes_[0]};
  sensor_count_ = 1;
  if (!c.rgb.empty()) {
    modes_[1] = {ONI_PIXEL_FORMAT_RGB888, c.width, c.height, kFps};
    sensors_[1] = {ONI_SENSOR_COLOR, 1, &modes_[1]};
    sensor_count_ = 2;
  }
}

oni::driver::StreamBase* VcamDevice::createStream(OniSensorType type) {
  for (int i = 0; i < sensor_count_; ++i)
    if (sensors_[i].sensorType == type) {
      const Clip& c = driver_.clip();
      auto* s = new VcamStream(type, modes_[i], c.hfov, c.vfov);
      std::lock_guard<std::mutex> lk(driver_.mutex());
      streams_.push_back(s);
      return s;
    }
  return nullptr;
}

void VcamDevice::destroyStream(oni::driver::StreamBase* base) {
  std::lock_guard<std::mutex> lk(driver_.mutex());
  auto* s = static_cast<VcamStream*>(base);
  streams_.erase(std::remove(streams_.begin(), streams_.end(), s), streams_.end());
  delete s;
}

void stop_at_exit() {
  if (VcamDriver* d = g_live.exchange(nullptr)) d->shutdown();
}

}  // namespace

ONI_EXPORT_DRIVER(VcamDriver)
