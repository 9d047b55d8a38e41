// .oni writer. OpenNI2 cannot record without a device (DESIGN.md), so this emits the container
// OpenNI2's player (Source/Drivers/OniFile) reads: a 24-byte file header, then records, each a
// 28-byte header (magic "NIR\0", type, node id, size of header + fields, payload size, undo
// position) followed by its fields and payload, all little-endian and packed. Per stream:
// NodeAdded, its properties, NodeStateReady; then NodeDataBegin per stream, NewData records
// (depth then colour for each frame, so that a reader alternating depth and colour in manual
// mode is served in file order), and End. Frame counts and the last timestamp are patched in at
// close. Frames are stored uncompressed (codec "NONE"), which the player passes through as is.
#include <cerrno>
#include <cmath>
#include <cstring>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "capture_util.hpp"
#include "stairguide/capture/oni.hpp"

namespace stairguide {
namespace {

static_assert(sizeof(double) == 8, "IEEE double expected");

constexpr std::uint32_t kRecordMagic = 0x0052494E;  // "NIR\0"
enum : std::uint32_t {
  kIntProperty = 0x03,
  kGeneralProperty = 0x06,
  kNodeDataBegin = 0x08,
  kNodeStateReady = 0x09,
  kNewData = 0x0A,
  kEnd = 0x0B,
  kNodeAdded = 0x0D,
};
constexpr std::int32_t kNodeTypeDepth = 2, kNodeTypeImage = 3;
constexpr std::uint32_t kCodecNone = 'N' | ('O' << 8) | ('N' << 16) | (static_cast<std::uint32_t>('E') << 24);
constexpr std::uint64_t kXnPixelFormatRgb24 = 1, kXnPixelFormatGray16 = 4;
constexpr std::uint64_t kOniDepth1mm = 100, kOniRgb888 = 200;
constexpr std::uint32_t kDepthNode = 1, kColorNode = 2;  // node 0 unused, as OpenNI2's Recorder does

// Little-endian byte builder (x86 and ARM are both little-endian; stated here so the intent is
// explicit rather than relying on struct layout).
class Bytes {
 public:
  void u8(std::uint8_t v) { b_.push_back(v); }
  void u16(std::uint16_t v) { put(v, 2); }
  void u32(std::uint32_t v) { put(v, 4); }
  void i32(std::int32_t v) { put(static_cast<std::uint32_t>(v), 4); }
  void u64(std::uint64_t v) { put(v, 8); }
  void f64(double v) {
    std::uint64_t u;
    std::memcpy(&u, &v, 8);
    u64(u);
  }
  void raw(const void* p, std::size_t n) {
    const auto* c = static_cast<const std::uint8_t*>(p);
    b_.insert(b_.end(), c, c + n);
  }
  void str(const char* s) {  // length including the terminating NUL, then the bytes and NUL
    const auto n = static_cast<std::uint32_t>(std::strlen(s) + 1);
    u32(n);
    raw(s, n);
  }
  std::vector<std::uint8_t>& data() { return b_; }
  void set_u32(std::size_t at, std::uint32_t v) {
    for (int i = 0; i < 4; ++i)
      b_[at + static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(v >> (8 * i));
  }

 private:
  void put(std::uint64_t v, int n) {
    for (int i = 0; i < n; ++i) b_.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
  }
  std::vector<std::uint8_t> b_;
};

// A record: header with the fields size filled in by finish().
class Record {
 public:
  Record(std::uint32_t type, std::uint32_t node) {
    b.u32(kRecordMagic);
    b.u32(type);
    b.u32(node);
    b.u32(0);  // fields size, set by finish()
    b.u32(0);  // payload size
    b.u64(0);  // undo record position: none (seeking backwards is not needed for replay)
  }
  Bytes& fields() { return b; }
  std::vector<std::uint8_t>& finish(std::uint32_t payload_size = 0) {
    b.set_u32(12, static_cast<std::uint32_t>(b.data().size()));
    b.set_u32(16, payload_size);
    return b.data();
  }

 private:
  Bytes b;
};

Bytes node_added(std::uint32_t node, const char* name, std::int32_t type, std::uint32_t frames,
                 std::uint64_t max_ts) {
  Record r(kNodeAdded, node);
  r.fields().str(name);
  r.fields().i32(type);
  r.fields().u32(kCodecNone);
  r.fields().u32(frames);
  r.fields().u64(0);       // min timestamp
  r.fields().u64(max_ts);  // max timestamp
  r.fields().u64(0);       // seek table position: none
  Bytes out;
  out.data() = r.finish();
  return out;
}

Bytes data_begin(std::uint32_t node, std::uint32_t frames, std::uint64_t max_ts) {
  Record r(kNodeDataBegin, node);
  r.fields().u32(frames);
  r.fields().u64(max_ts);
  Bytes out;
  out.data() = r.finish();
  return out;
}

}  // namespace

OniWriter::OniWriter(const std::string& path, const CameraIntrinsics& intrinsics, bool with_color, int fps)
    : path_(path), intrinsics_(intrinsics), with_color_(with_color), fps_(fps > 0 ? fps : 30) {
  if (!intrinsics.valid()) throw SourceError(path + ": invalid intrinsics for the recording");
  // The player's buffer holds at most 1600x1200x3 bytes per frame.
  if (static_cast<long>(intrinsics.width) * intrinsics.height * 3 > 1600L * 1200L * 3L)
    throw SourceError(path + ": frames larger than 1600x1200 do not fit OpenNI2's player");
  f_ = std::fopen(path.c_str(), "wb");
  if (!f_) throw SourceError(path + ": cannot create (" + std::strerror(errno) + ")");
  write_node_headers();
}

OniWriter::~OniWriter() {
  try {
    close();
  } catch (...) {
  }
}

void OniWriter::write_node_headers() {
  auto put = [&](const std::vector<std::uint8_t>& b) {
    if (std::fwrite(b.data(), 1, b.size(), f_) != b.size())
      throw SourceError(path_ + ": write failed (" + std::strerror(errno) + ")");
  };
  Bytes header;
  header.raw("NI10", 4);
  header.u8(1);  // version 1.0.1.0: 64-bit positions, as OpenNI2's Recorder writes
  header.u8(0);
  header.u16(1);
  header.u32(0);
  header.u64(0);                                      // global max timestamp, patched at close
  header.u32(with_color_ ? kColorNode : kDepthNode);  // max node id
  put(header.data());

  const int w = intrinsics_.width, h = intrinsics_.height;
  const double hfov = 2.0 * std::atan(w / (2.0 * static_cast<double>(intrinsics_.fx)));
  const double vfov = 2.0 * std::atan(h / (2.0 * static_cast<double>(intrinsics_.fy)));
  auto int_prop = [&](std::uint32_t node, const char* name, std::uint64_t v) {
    Record r(kIntProperty, node);
    r.fields().str(name);
    r.fields().u32(8);
    r.fields().u64(v);
    put(r.finish());
  };
  auto general_prop = [&](std::uint32_t node, const char* name, const Bytes& value) {
    Bytes v = value;
    Record r(kGeneralProperty, node);
    r.fields().str(name);
    r.fields().u32(static_cast<std::uint32_t>(v.data().size()));
    r.fields().raw(v.data().data(), v.data().size());
    put(r.finish());
  };
  auto stream = [&](int i, std::uint32_t node, const char* name, std::int32_t type, int bpp,
                    std::uint64_t xn_format, std::uint64_t oni_format) {
    node_added_pos_[i] = std::ftell(f_);
    put(node_added(node, name, type, 0, 0).data());
    Bytes mode;  // xnMapOutputMode: x, y, fps (sets the stream's video mode)
    mode.u32(static_cast<std::uint32_t>(w));
    mode.u32(static_cast<std::uint32_t>(h));
    mode.u32(static_cast<std::uint32_t>(fps_));
    general_prop(node, "xnMapOutputMode", mode);
    int_prop(node, "xnPixelFormat", xn_format);
    int_prop(node, "oniPixelFormat", oni_format);
    int_prop(node, "oniRequiredFrameSize",
             static_cast<std::uint64_t>(w) * static_cast<std::uint64_t>(h) * static_cast<std::uint64_t>(bpp));
    int_prop(node, "xnIsGenerating", 1);
    if (type == kNodeTypeDepth) int_prop(node, "xnDeviceMaxDepth", 65535);
    int_prop(node, "xnMirror", 0);
    // The player drops every frame of a stream that has no cropping property, so state "off".
    Bytes crop;  // xnCropping: enabled (4-byte bool), x, y, width, height (16-bit)
    crop.u32(0);
    for (int i = 0; i < 4; ++i) crop.u16(0);
    general_prop(node, "xnCropping", crop);
    Bytes fov;  // xnFOV: horizontal, vertical field of view in radians
    fov.f64(hfov);
    fov.f64(vfov);
    general_prop(node, "xnFOV", fov);
    Record ready(kNodeStateReady, node);
    put(ready.finish());
  };
  stream(0, kDepthNode, "Depth", kNodeTypeDepth, 2, kXnPixelFormatGray16, kOniDepth1mm);
  if (with_color_) stream(1, kColorNode, "Image", kNodeTypeImage, 3, kXnPixelFormatRgb24, kOniRgb888);
  data_begin_pos_[0] = std::ftell(f_);
  put(data_begin(kDepthNode, 0, 0).data());
  if (with_color_) {
    data_begin_pos_[1] = std::ftell(f_);
    put(data_begin(kColorNode, 0, 0).data());
  }
  if (std::ferror(f_)) throw SourceError(path_ + ": write failed");
}

void OniWriter::write(const RgbdFrame& frame) {
  if (closed_) throw SourceError(path_ + ": write after close");
  const int w = intrinsics_.width, h = intrinsics_.height;
  if (frame.depth.type() != CV_32FC1 || frame.depth.cols != w || frame.depth.rows != h)
    throw SourceError(path_ + ": frame " + std::to_string(frame.index) + " depth is " +
                      describe_mat_type(frame.depth) + " " + std::to_string(frame.depth.cols) + "x" +
                      std::to_string(frame.depth.rows) + ", expected 32-bit float " + std::to_string(w) +
                      "x" + std::to_string(h));
  if (!frame.color.empty() && (frame.color.type() != CV_8UC3 || frame.color.size() != frame.depth.size()))
    throw SourceError(path_ + ": frame " + std::to_string(frame.index) +
                      " colour must be 8-bit BGR of the depth's size");

  // Timestamps in microseconds, strictly increasing (the player orders nothing by them, but
  // frame numbers and timestamps must both grow for seeking tools and for our own reader).
  const double t = frame.timestamp * 1e6;
  std::uint64_t ts = (std::isfinite(t) && t > 0.0) ? static_cast<std::uint64_t>(std::llround(t)) : 0;
  if (frames_ > 0 && ts <= last_ts_us_) ts = last_ts_us_ + static_cast<std::uint64_t>(1000000 / fps_);
  if (frames_ == 0) first_ts_us_ = ts;
  last_ts_us_ = ts;
  const auto number = static_cast<std::uint32_t>(frames_ + 1);  // 1-based frame numbers

  auto put_frame = [&](std::uint32_t node, const cv::Mat& m) {
    const std::size_t n = m.total() * m.elemSize();
    Record r(kNewData, node);
    r.fields().u64(ts);
    r.fields().u32(number);
    const auto& head = r.finish(static_cast<std::uint32_t>(n));
    if (std::fwrite(head.data(), 1, head.size(), f_) != head.size() || std::fwrite(m.data, 1, n, f_) != n)
      throw SourceError(path_ + ": write failed (" + std::strerror(errno) + ")");
  };
  put_frame(kDepthNode, depth_to_u16(frame.depth, 1000.0));
  if (with_color_) {
    cv::Mat rgb;
    if (frame.color.empty())
      rgb = cv::Mat::zeros(h, w, CV_8UC3);
    else
      cv::cvtColor(frame.color, rgb, cv::COLOR_BGR2RGB);
    put_frame(kColorNode, rgb);
  }
  ++frames_;
}

void OniWriter::patch_counts() {
  auto put_at = [&](long pos, const std::vector<std::uint8_t>& b) {
    if (std::fseek(f_, pos, SEEK_SET) != 0 || std::fwrite(b.data(), 1, b.size(), f_) != b.size())
      throw SourceError(path_ + ": patching the header failed (" + std::strerror(errno) + ")");
  };
  const auto n = static_cast<std::uint32_t>(frames_);
  Bytes global;
  global.u64(last_ts_us_);
  put_at(12, global.data());  // after "NI10" and the 8-byte version
  put_at(node_added_pos_[0], node_added(kDepthNode, "Depth", kNodeTypeDepth, n, last_ts_us_).data());
  put_at(data_begin_pos_[0], data_begin(kDepthNode, n, last_ts_us_).data());
  if (with_color_) {
    put_at(node_added_pos_[1], node_added(kColorNode, "Image", kNodeTypeImage, n, last_ts_us_).data());
    put_at(data_begin_pos_[1], data_begin(kColorNode, n, last_ts_us_).data());
  }
}

void OniWriter::close() {
  if (closed_) return;
  closed_ = true;
  if (!f_) return;
  try {
    if (frames_ == 0)
      throw SourceError(path_ + ": no frames written (OpenNI2's player rejects an empty recording)");
    Record end(kEnd, 0);
    const auto& b = end.finish();
    if (std::fwrite(b.data(), 1, b.size(), f_) != b.size()) throw SourceError(path_ + ": write failed");
    patch_counts();
  } catch (...) {
    std::fclose(f_);
    f_ = nullptr;
    throw;
  }
  const bool ok = std::fclose(f_) == 0;
  f_ = nullptr;
  if (!ok) throw SourceError(path_ + ": closing failed (disk full?)");
}

}  // namespace stairguide
