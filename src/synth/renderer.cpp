// The per-frame driver: build the preset's scene and camera, render, apply the sensor model,
// compute the ground truth (PresetRenderer; capture's synthetic FrameSource reads through it).
#include <cmath>

#include "stairguide/synth/synth.hpp"
#include "internal.hpp"

namespace stairguide::synth {
namespace {

void check_options(const SynthOptions& o) {
  auto bad = [](const std::string& what) { throw SourceError("synthetic source: " + what); };
  if (o.width < 16 || o.height < 12 || o.width > 4096 || o.height > 4096)
    bad("image size " + std::to_string(o.width) + "x" + std::to_string(o.height) +
        " is out of range (16x12 .. 4096x4096)");
  if (!(o.min_range_m >= 0.f) || !(o.max_range_m > o.min_range_m))
    bad("range [" + std::to_string(o.min_range_m) + ", " + std::to_string(o.max_range_m) +
        "] m is not a valid interval");
  if (!(o.fps > 0.0)) bad("fps must be positive");
  if (!std::isnan(o.camera_height_m) && !(o.camera_height_m > 0.2f && o.camera_height_m < 3.f))
    bad("camera height " + std::to_string(o.camera_height_m) + " m is out of range (0.2 .. 3 m)");
  if (!std::isnan(o.camera_tilt_deg) && !(o.camera_tilt_deg >= -30.f && o.camera_tilt_deg <= 90.f))
    bad("camera tilt " + std::to_string(o.camera_tilt_deg) + " deg is out of range (-30 .. 90)");
  if (!(o.disparity_step_px > 0.f) || !(o.depth_step_m > 0.f) || !(o.baseline_m > 0.f) ||
      !(o.disparity_focal_px > 0.f))
    bad("sensor model steps, baseline and focal must be positive");
  auto share = [](float v) { return v >= 0.f && v <= 1.f; };
  if (!share(o.speckle_holes) || !share(o.dark_surface_chance) || !share(o.flying_pixels))
    bad("speckle_holes, dark_surface_chance and flying_pixels are shares in [0, 1]");
  if (!(o.dark_surface_range_m > 0.f)) bad("dark_surface_range_m must be positive");
  if (!(o.tof_sigma_m >= 0.f) || !(o.tof_sigma_per_m2 >= 0.f)) bad("time-of-flight sigmas must be >= 0");
  if (!std::isnan(o.focal_px) && !(o.focal_px > 1.f && o.focal_px < 10000.f))
    bad("focal length " + std::to_string(o.focal_px) + " px is out of range (1 .. 10000)");
  if (!(o.multipath_m >= 0.f && o.multipath_m < 0.5f) || !(o.multipath_range_m > 0.f))
    bad("multipath_m must be in [0, 0.5) m and multipath_range_m positive");
  if (o.edge_hole_px < 1 || o.edge_hole_px > 16) bad("edge_hole_px must be 1 .. 16");
}

const detail::PresetDef& need_preset(const std::string& name) {
  const detail::PresetDef* d = detail::find_preset(name);
  if (!d) {
    std::string known;
    for (const auto& p : detail::preset_defs()) known += (known.empty() ? "" : ", ") + p.info.name;
    for (const auto& p : detail::world_preset_defs()) known += ", " + p.info.name;
    for (const auto& p : detail::walk_defs()) known += ", " + p.info.name;
    for (const auto& p : detail::rig_defs()) known += ", " + p.info.name;
    for (const auto& p : detail::world2_defs()) known += ", " + p.info.name;
    for (const auto& p : detail::drop_defs()) known += ", " + p.info.name;
    throw SourceError("synthetic source: unknown scene '" + name + "' (known: " + known + ")");
  }
  return *d;
}

std::uint64_t build_seed(const detail::PresetDef& d, std::uint32_t seed, long index) {
  return d.sequence ? mix_seed(seed, detail::name_hash(d.info.name))
                    : mix_seed(seed, detail::name_hash(d.info.name), static_cast<std::uint64_t>(index) + 1);
}

void render_into(const Scene& scene, const WalkerState& walker, long index, std::uint32_t seed,
                 const SynthOptions& o, RenderBuffers& buf, RgbdFrame& frame, FrameTruth& truth) {
  const CameraIntrinsics K = synthetic_intrinsics(o);
  render(scene, walker.T_world_camera, K, buf, true);
  const std::uint64_t noise_seed = mix_seed(seed, static_cast<std::uint64_t>(index), 0xD3 + o.noise_salt);
  apply_depth_sensor(buf, K, o, noise_seed, frame.depth);
  apply_color_sensor(buf, o, noise_seed, frame.color, frame.gray);
  frame.index = static_cast<std::uint64_t>(index);
  frame.timestamp = static_cast<double>(index) / o.fps;
  frame.intrinsics = K;
  truth = compute_truth(scene, walker, buf, K, o);
  truth.index = frame.index;
  truth.timestamp = frame.timestamp;
}

// The public descriptions of a list of preset definitions.
std::vector<PresetInfo> infos(const std::vector<detail::PresetDef>& defs) {
  std::vector<PresetInfo> v;
  for (const auto& d : defs) v.push_back(d.info);
  return v;
}
}  // namespace

const std::vector<PresetInfo>& presets() {
  static const std::vector<PresetInfo> list = infos(detail::preset_defs());
  return list;
}

const std::vector<PresetInfo>& world_presets() {
  static const std::vector<PresetInfo> list = infos(detail::world_preset_defs());
  return list;
}

const std::vector<PresetInfo>& walk_presets() {
  static const std::vector<PresetInfo> list = infos(detail::walk_defs());
  return list;
}

const std::vector<PresetInfo>& rig_presets() {
  static const std::vector<PresetInfo> list = infos(detail::rig_defs());
  return list;
}

const std::vector<PresetInfo>& world2_presets() {
  static const std::vector<PresetInfo> list = infos(detail::world2_defs());
  return list;
}

const PresetInfo* find_preset_info(const std::string& name) {
  for (const auto* l :
       {&presets(), &world_presets(), &walk_presets(), &rig_presets(), &world2_presets(), &drop_presets()})
    for (const auto& p : *l)
      if (p.name == name) return &p;
  return nullptr;
}

CameraIntrinsics synthetic_intrinsics(const SynthOptions& o) {
  CameraIntrinsics K;  // 525 / 319.5 / 239.5 at 640x480
  const float sx = static_cast<float>(o.width) / 640.f, sy = static_cast<float>(o.height) / 480.f;
  K.width = o.width;
  K.height = o.height;
  K.fx = 525.f * sx;
  K.fy = 525.f * sy;
  if (!std::isnan(o.focal_px)) K.fx = K.fy = o.focal_px;
  K.cx = (319.5f + 0.5f) * sx - 0.5f;
  K.cy = (239.5f + 0.5f) * sy - 0.5f;
  return K;
}

PresetFrame build_preset_frame(const std::string& preset, long index, std::uint32_t seed,
                               const SynthOptions& o) {
  const detail::PresetDef& d = need_preset(preset);
  detail::PresetBuild b;
  Rng rng(build_seed(d, seed, index));
  d.build(rng, o, b);
  PresetFrame pf;
  pf.scene = std::move(b.scene);
  pf.scene.name = preset;
  if (d.sequence) {
    pf.walker = Walk(b.walk, o.fps, index + 1).at(index);
  } else {
    pf.walker = b.view;
  }
  return pf;
}

void render_preset_frame(const std::string& preset, long index, std::uint32_t seed,
                         const SynthOptions& options, RgbdFrame& frame, FrameTruth& truth) {
  check_options(options);
  const PresetFrame pf = build_preset_frame(preset, index, seed, options);
  RenderBuffers buf;
  render_into(pf.scene, pf.walker, index, seed, options, buf, frame, truth);
}

PresetRenderer::PresetRenderer(const std::string& preset, long frames, std::uint32_t seed,
                               const SynthOptions& o)
    : def_(&need_preset(preset)), seed_(seed), options_(o) {
  check_options(o);
  frames_ = frames > 0 ? frames : def_->info.default_frames;
  if (def_->sequence) {
    detail::PresetBuild b;
    Rng rng(build_seed(*def_, seed, 0));
    def_->build(rng, o, b);
    scene_ = std::move(b.scene);
    scene_.name = preset;
    walk_ = Walk(b.walk, o.fps, frames_);
  }
}

void PresetRenderer::render(long index, RgbdFrame& frame, FrameTruth& truth) {
  if (def_->sequence) {
    render_into(scene_, walk_.at(index), index, seed_, options_, buf_, frame, truth);
  } else {
    const PresetFrame pf = build_preset_frame(def_->info.name, index, seed_, options_);
    render_into(pf.scene, pf.walker, index, seed_, options_, buf_, frame, truth);
  }
}

bool PresetRenderer::sequence() const { return def_->sequence; }

const PresetInfo& PresetRenderer::info() const { return def_->info; }

}  // namespace stairguide::synth
