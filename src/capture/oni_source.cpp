// .oni replay through OpenNI2's own player (see DESIGN.md for the checked facts this relies on).
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <opencv2/imgproc.hpp>
#include <set>
#include <thread>

#include "capture_util.hpp"
#include "openni_util.hpp"
#include "stairguide/capture/oni.hpp"

namespace fs = std::filesystem;

namespace stairguide {
namespace {

std::uint32_t le32(const unsigned char* b) {
  return static_cast<std::uint32_t>(b[0]) | static_cast<std::uint32_t>(b[1]) << 8 |
         static_cast<std::uint32_t>(b[2]) << 16 | static_cast<std::uint32_t>(b[3]) << 24;
}

// Walks the container's records before OpenNI2's player sees them. The player trusts every
// size it reads: a record whose header was overwritten (found by tests/fuzz/fuzz_oni) made it
// read far past its buffers and crash the process. Each record must carry the "NIR\0"
// signature and a known type, its header sizes must be sane, and a property's or a stream's
// name must lie inside its record. A record cut by the end of the file ends the walk (a
// truncated recording plays its whole frames and then reports the end as an error). Only the
// layout of 1.0.1 and later (28-byte record headers: OpenNI2's Recorder and OniWriter) is
// walked; a file without the NI10 signature is left to the player to refuse.
void check_oni_records(const std::string& path, std::uintmax_t size) {
  std::ifstream in(path, std::ios::binary);
  unsigned char h[28];
  if (!in.read(reinterpret_cast<char*>(h), 24)) return;
  if (std::memcmp(h, "NI10", 4) != 0) return;
  // The player allocates a table entry of some 2 kB per stream the header announces (a 50-byte
  // file asked for 6 GB); a recording holds a depth and a colour stream, a few more at most.
  // Every version's 24-byte file header ends with that count.
  if (le32(h + 20) > 64)
    throw SourceError("oni " + path + ": corrupt recording (the file header announces " +
                      std::to_string(le32(h + 20)) + " streams)");
  if (!(h[4] == 1 && h[5] == 0 && (h[6] | h[7] << 8) >= 1)) return;
  auto bad = [&](std::uintmax_t at, const std::string& why) {
    return SourceError("oni " + path + ": corrupt recording (record at byte " + std::to_string(at) + ": " +
                       why + ")");
  };
  std::uintmax_t pos = 24;
  std::set<std::uint32_t> cropped;  // streams (node ids) whose xnCropping property has come
  while (size - pos >= 28) {
    in.seekg(static_cast<std::streamoff>(pos));
    if (!in.read(reinterpret_cast<char*>(h), 28)) return;
    const std::uint32_t magic = le32(h), type = le32(h + 4), fields = le32(h + 12), payload = le32(h + 16);
    if (magic != 0x0052494E) throw bad(pos, "no NIR signature");
    if (type < 0x01 || type > 0x0E) throw bad(pos, "unknown type " + std::to_string(type));
    if (fields < 28 || fields > (1u << 20)) throw bad(pos, "header size " + std::to_string(fields));
    if (type != 0x0A && type != 0x0E && payload != 0) throw bad(pos, "a payload on a record that has none");
    if (static_cast<std::uintmax_t>(fields) + payload > size - pos) return;  // cut by the end: truncated
    const bool named = type == 0x02 || type == 0x03 || type == 0x04 || type == 0x05 || type == 0x06 ||
                       type == 0x0C || type == 0x0D;
    if (named) {
      if (fields < 32) throw bad(pos, "no room for its name");
      unsigned char l[4];
      if (!in.read(reinterpret_cast<char*>(l), 4)) return;
      const std::uint32_t len = le32(l);
      if (len < 1 || len > 256 || 32ull + len > fields) throw bad(pos, "name length " + std::to_string(len));
      std::string name(len, '\0');
      if (!in.read(&name[0], len)) return;
      if (name.back() != '\0' || name.find('\0') != len - 1) throw bad(pos, "name not a string");
      name.pop_back();
      for (char c : name)
        if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_' && c != ' ' && c != '-' && c != '.')
          throw bad(pos, "name not a string");
      if (type == 0x06 && name == "xnCropping") cropped.insert(le32(h + 8));
      if (type >= 0x03 && type <= 0x06) {  // properties: value size, then the value, filling the record
        unsigned char v[4];
        if (36ull + len > fields || !in.read(reinterpret_cast<char*>(v), 4)) throw bad(pos, "no value size");
        const std::uint32_t vsize = le32(v);
        if (36ull + len + vsize != fields) throw bad(pos, "value of " + std::to_string(vsize) + " bytes");
        if ((type == 0x03 || type == 0x04) && vsize != 8)
          throw bad(pos, "number of " + std::to_string(vsize) + " bytes");
      }
    }
    // A stream the player serves without its cropping state crashed it once its frames came
    // (fuzz_oni), and OpenNI2 2.2's player drops every frame of such a stream (checked): the
    // property must come before the stream's first frame. Only there: it may come after the
    // stream is ready (OpenNI2's player reads such a recording; refusing it at the ready record
    // refused a real Kinect recording, issue 41), and a stream with no frames needs none.
    if (type == 0x0A && !cropped.count(le32(h + 8)))
      throw bad(pos, "stream " + std::to_string(le32(h + 8)) +
                         " carries frames but has no xnCropping property before them (OpenNI2's player would "
                         "drop them all)");
    pos += static_cast<std::uintmax_t>(fields) + payload;
    if (type == 0x0B) return;  // End
  }
}

}  // namespace

struct OniSource::Impl {
  std::string path;
  OniOptions options;
  openni::Device device;
  openni::VideoStream depth, color;
  bool has_color = false;
  bool registered = false;
  long depth_frames = 0;  ///< announced by the recording
  long color_frames = 0;
  long next = 0;  ///< depth frames delivered so far
  long color_read = 0;
  long skipped = 0;
  int last_depth_number = 0;
  bool ended = false;
  CameraIntrinsics k;
  openni::VideoFrameRef depth_ref, color_ref;

  ~Impl() {
    // OpenNI2's player thread (libOniFile PlayerDevice::MainLoop) walks its list of streams with
    // no lock, and a stream's destruction removes it from that list. Once the recording has
    // been read to its end the thread spins through that walk without pause, so destroying a
    // stream then crashed about one run in twenty (a read-to-the-end test, under load). With every
    // stream stopped the thread walks the list only once per 10 ms sleep: stop them all, give it
    // time to settle into that sleep, then destroy them and close the device (which joins it).
    bool stopped = false;
    if (color.isValid()) color.stop(), stopped = true;
    if (depth.isValid()) depth.stop(), stopped = true;
    if (stopped) std::this_thread::sleep_for(std::chrono::milliseconds(30));
    if (color.isValid()) color.destroy();
    if (depth.isValid()) depth.destroy();
    if (device.isValid()) device.close();
  }

  // Waits for one frame of `s` (which pokes the manual-mode trigger) and reads it.
  bool read_one(openni::VideoStream& s, openni::VideoFrameRef& ref, int timeout_ms, std::string& why) {
    openni::VideoStream* streams[] = {&s};
    int ready = -1;
    const openni::Status st = openni::OpenNI::waitForAnyStream(streams, 1, &ready, timeout_ms);
    if (st != openni::STATUS_OK) {
      why = st == openni::STATUS_TIME_OUT ? "no frame within " + fmt_num(timeout_ms / 1000.0) + " s"
                                          : openni_error("wait failed");
      return false;
    }
    if (s.readFrame(&ref) != openni::STATUS_OK || !ref.isValid()) {
      why = openni_error("readFrame failed");
      return false;
    }
    return true;
  }
};

OniSource::OniSource(const std::string& path, const OniOptions& options) : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.path = path;
  m.options = options;
  // OpenNI gives the same status for a missing, corrupt or directory path: check first.
  std::error_code ec;
  if (const std::string why = why_unreadable(path); !why.empty() && !fs::is_directory(path, ec))
    throw SourceError("oni " + path + ": " +
                      (why == "no such file" ? "recording missing (no such file)"
                                             : "cannot read the recording (" + why + ")"));
  if (!fs::is_regular_file(path, ec)) throw SourceError("oni " + path + ": not a regular file");
  if (fs::file_size(path, ec) < 24)
    throw SourceError("oni " + path + ": too short to be a recording (truncated?)");
  check_oni_records(path, fs::file_size(path, ec));
  const std::string init = ensure_openni();
  if (!init.empty()) throw SourceError("oni " + path + ": OpenNI2 unavailable: " + init);
  if (m.device.open(path.c_str()) != openni::STATUS_OK)
    throw SourceError("oni " + path +
                      ": OpenNI2's player cannot open it (corrupt, truncated or not an .oni recording): " +
                      openni_error("open failed"));
  openni::PlaybackControl* pc = m.device.getPlaybackControl();
  if (!pc) throw SourceError("oni " + path + ": opened, but OpenNI2 gives no playback control");
  // Manual, frame-exact mode; no wrap-around at the end.
  pc->setSpeed(-1.0f);
  pc->setRepeatEnabled(false);
  if (!m.device.hasSensor(openni::SENSOR_DEPTH) ||
      m.depth.create(m.device, openni::SENSOR_DEPTH) != openni::STATUS_OK)
    throw SourceError("oni " + path + ": the recording has no depth stream");
  m.depth_frames = pc->getNumberOfFrames(m.depth);
  if (m.depth_frames <= 0) throw SourceError("oni " + path + ": the recording announces no depth frames");
  if (options.use_color && m.device.hasSensor(openni::SENSOR_COLOR) &&
      m.color.create(m.device, openni::SENSOR_COLOR) == openni::STATUS_OK) {
    m.has_color = true;
    m.color_frames = pc->getNumberOfFrames(m.color);
  }
  if (m.has_color && options.depth_registration &&
      m.device.isImageRegistrationModeSupported(openni::IMAGE_REGISTRATION_DEPTH_TO_COLOR))
    m.registered =
        m.device.setImageRegistrationMode(openni::IMAGE_REGISTRATION_DEPTH_TO_COLOR) == openni::STATUS_OK;
  if (m.depth.start() != openni::STATUS_OK)
    throw SourceError("oni " + path + ": cannot start the depth stream: " + openni_error(""));
  if (m.has_color && m.color.start() != openni::STATUS_OK)
    throw SourceError("oni " + path + ": cannot start the colour stream: " + openni_error(""));

  const openni::VideoMode vm = m.depth.getVideoMode();
  const int w = vm.getResolutionX(), h = vm.getResolutionY();
  if (w <= 0 || h <= 0) throw SourceError("oni " + path + ": the depth stream has no resolution");
  // Registered depth follows the colour camera's geometry, so its field of view applies.
  const openni::VideoStream& geo = (m.registered && m.has_color) ? m.color : m.depth;
  const float hfov = geo.getHorizontalFieldOfView(), vfov = geo.getVerticalFieldOfView();
  if (std::isfinite(hfov) && std::isfinite(vfov) && hfov > 0.05f && hfov < 3.0f && vfov > 0.05f &&
      vfov < 3.0f)
    m.k = intrinsics_from_fov(w, h, hfov, vfov);
  else
    m.k = default_intrinsics(w, h);
}

OniSource::~OniSource() = default;

ReadResult OniSource::read(RgbdFrame& out) {
  Impl& m = *impl_;
  if (m.ended || m.next >= m.depth_frames) {
    m.ended = true;
    return {ReadStatus::kEnd, {}};
  }
  const int timeout_ms = std::max(1, static_cast<int>(std::lround(m.options.frame_timeout * 1000.0)));
  std::string why;
  // A readFrame past the last frame blocks in manual mode, hence the frame count above; a
  // recording shorter than it announces (truncated) shows as a wait that times out. That is an
  // error, not an end: the frames it announced are missing (the ones before it were delivered).
  if (!m.read_one(m.depth, m.depth_ref, timeout_ms, why)) {
    m.ended = true;
    return {ReadStatus::kError, "oni " + m.path + ": recording ended early after " + std::to_string(m.next) +
                                    " of " + std::to_string(m.depth_frames) + " frames (truncated?): " + why};
  }
  if (!depth_frame_to_metres(m.depth_ref, out.depth)) {
    m.ended = true;
    return {ReadStatus::kError,
            "oni " + m.path + ": unsupported depth pixel format " +
                std::to_string(static_cast<int>(m.depth_ref.getVideoMode().getPixelFormat()))};
  }
  const int number = m.depth_ref.getFrameIndex();
  if (m.last_depth_number > 0 && number > m.last_depth_number + 1)
    m.skipped += number - m.last_depth_number - 1;
  m.last_depth_number = number;
  out.timestamp = static_cast<double>(m.depth_ref.getTimestamp()) * 1e-6;
  out.color.release();
  out.gray.release();
  if (m.has_color && m.color_read < m.color_frames) {
    if (m.read_one(m.color, m.color_ref, timeout_ms, why)) {
      ++m.color_read;
      if (color_frame_to_bgr(m.color_ref, out.color) && out.color.size() != out.depth.size()) {
        // Unregistered recordings may carry a colour mode of another size: scale it onto depth.
        cv::Mat resized;
        cv::resize(out.color, resized, out.depth.size(), 0, 0, cv::INTER_LINEAR);
        out.color = resized;
      }
      if (!out.color.empty()) cv::cvtColor(out.color, out.gray, cv::COLOR_BGR2GRAY);
    } else {
      m.color_read = m.color_frames;  // colour ended early: give depth alone from here on
    }
  }
  out.index = static_cast<std::uint64_t>(m.next++);
  out.intrinsics = m.k;
  return {};
}

CameraIntrinsics OniSource::intrinsics() const { return impl_->k; }
long OniSource::frame_count() const { return impl_->depth_frames; }
bool OniSource::has_color() const { return impl_->has_color; }
bool OniSource::registered() const { return impl_->registered; }
long OniSource::skipped_frames() const { return impl_->skipped; }

std::string OniSource::describe() const {
  const Impl& m = *impl_;
  std::string s = "oni " + m.path + " (" + std::to_string(m.depth_frames) + " depth frames";
  if (m.has_color) s += ", colour" + std::string(m.registered ? ", registered" : "");
  return s + ")";
}

}  // namespace stairguide
