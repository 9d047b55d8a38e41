// open_frame_source: the one place that maps an input name to a source.
#include "stairguide/capture/frame_source.hpp"

#include <cmath>
#include <filesystem>

#include "capture_util.hpp"
#include "stairguide/capture/dataset.hpp"
#include "stairguide/capture/device.hpp"
#include "stairguide/capture/oni.hpp"
#include "stairguide/capture/synth_source.hpp"

namespace fs = std::filesystem;

namespace stairguide {
namespace {

long parse_count(const std::string& s, const std::string& input, const char* what) {
  double v = 0.0;
  if (!parse_double(s, v) || v != std::floor(v) || v < 0 || v > 4e9)
    throw SourceError("input '" + input + "': " + what + " must be a whole number, got '" + s + "'");
  return static_cast<long>(v);
}

std::unique_ptr<FrameSource> open_synth(const std::string& input) {
  // synth:SCENE[:FRAMES[:SEED[:NOISE]]], NOISE white (the default), kinect
  // (synth::with_real_kinect_noise: correlated in space as the real sensor's), or real-v1 / real-v2
  // (synth::with_real_artefacts: the real frames' holes, dark faces, flying pixels; Kinect v1 or v2)
  std::vector<std::string> parts;
  std::size_t start = 0;
  for (;;) {
    const std::size_t c = input.find(':', start);
    parts.push_back(input.substr(start, c == std::string::npos ? std::string::npos : c - start));
    if (c == std::string::npos) break;
    start = c + 1;
  }
  if (parts.size() < 2 || parts.size() > 5 || parts[1].empty())
    throw SourceError("input '" + input +
                      "': expected synth:SCENE[:FRAMES[:SEED[:NOISE]]] (see 'stairguide synth --list')");
  long frames = -1;
  if (const synth::PresetInfo* p = synth::find_preset_info(parts[1])) frames = p->default_frames;
  if (parts.size() >= 3 && !parts[2].empty()) frames = parse_count(parts[2], input, "FRAMES");
  if (frames == 0) throw SourceError("input '" + input + "': FRAMES must be at least 1");
  std::uint32_t seed = 1;
  if (parts.size() >= 4 && !parts[3].empty())
    seed = static_cast<std::uint32_t>(parse_count(parts[3], input, "SEED"));
  synth::SynthOptions options;
  if (parts.size() == 5 && !synth::sensor_options(parts[4], options))
    throw SourceError("input '" + input + "': NOISE must be " + synth::sensor_names() + ", got '" + parts[4] +
                      "'");
  // An unknown scene name is reported by make_source (its message lists the presets).
  return synth::make_source(parts[1], frames < 0 ? 1 : frames, seed, options);
}

// capture.min_range_m / max_range_m: depth outside them is no reading, for every consumer
// (perception, odometry, the CLI) and every source, whatever the sensor or file holds. Beyond
// ~5 m a Kinect-class sensor's noise is several centimetres and its quantisation steps coarser
// still; nearer than its minimum range it reads garbage.
class RangeGatedSource final : public FrameSource {
 public:
  RangeGatedSource(std::unique_ptr<FrameSource> inner, float min_range, float max_range)
      : inner_(std::move(inner)), lo_(min_range), hi_(max_range) {}
  ReadResult read(RgbdFrame& out) override {
    ReadResult r = inner_->read(out);
    if (r.ok() && out.depth.type() == CV_32FC1) {
      for (int v = 0; v < out.depth.rows; ++v) {
        float* row = out.depth.ptr<float>(v);
        for (int u = 0; u < out.depth.cols; ++u)
          if (!(row[u] >= lo_ && row[u] <= hi_)) row[u] = 0.f;  // NaN too
      }
    }
    return r;
  }
  CameraIntrinsics intrinsics() const override { return inner_->intrinsics(); }
  long frame_count() const override { return inner_->frame_count(); }
  std::string describe() const override { return inner_->describe(); }
  std::optional<FrameTruth> truth() const override { return inner_->truth(); }
  bool is_live() const override { return inner_->is_live(); }
  bool independent_frames() const override { return inner_->independent_frames(); }

 private:
  std::unique_ptr<FrameSource> inner_;
  float lo_, hi_;
};

std::unique_ptr<FrameSource> open_ungated(const std::string& input, const CaptureConfig& config);

}  // namespace

std::unique_ptr<FrameSource> open_frame_source(const std::string& input, const CaptureConfig& config) {
  return std::make_unique<RangeGatedSource>(open_ungated(input, config), config.min_range, config.max_range);
}

namespace {

std::unique_ptr<FrameSource> open_ungated(const std::string& input, const CaptureConfig& config) {
  if (input.empty())
    throw SourceError(
        "no input given (a dataset folder, FILE.oni, FILE.pcd, FILE.png, device[:URI] or synth:SCENE)");
  if (input.rfind("synth:", 0) == 0) return open_synth(input);
  if (input == "device") return std::make_unique<DeviceSource>(config);
  if (input.rfind("device:", 0) == 0) return std::make_unique<DeviceSource>(config, input.substr(7));
  std::error_code ec;
  const std::string ext = lower_extension(input);
  if (fs::is_directory(input, ec)) return std::make_unique<DatasetSource>(input);
  if (ext == ".oni") {
    OniOptions o;
    o.depth_registration = config.depth_registration;
    return std::make_unique<OniSource>(input, o);
  }
  if (ext == ".pcd") return std::make_unique<SingleFrameSource>(read_pcd_frame(input), "pcd " + input);
  if (ext == ".png")
    return std::make_unique<SingleFrameSource>(read_depth_png_frame(input), "depth image " + input);
  // The cause, as the system gives it: a symlink loop or a folder the user may not enter read
  // "no such file" (issue 41).
  if (const std::string why = why_unreadable(input); !why.empty())
    throw SourceError("input '" + input + "': cannot open it (" + why + ")");
  throw SourceError("input '" + input +
                    "': unknown kind (expected a dataset folder, FILE.oni, FILE.pcd, FILE.png, device[:URI] "
                    "or synth:SCENE[:FRAMES[:SEED[:NOISE]]])");
}

}  // namespace
}  // namespace stairguide
