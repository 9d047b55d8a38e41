#pragma once
// Internals shared by the synthetic world's .cpp files (not part of the public API).
#include <cstdint>

#include "stairguide/synth/scene.hpp"

namespace stairguide::synth::detail {

constexpr int kTextureSize = 256;  // texels per side; every texture tiles with this period

// Zero-mean, unit-variance tileable texture of a family (made once, thread-safe).
const float* texture(Texture t);

// 65536 standard normal deviates (exact zero mean and unit variance), made once.
const float* gaussian_table();
constexpr std::uint32_t kGaussianMask = 0xFFFF;

}  // namespace stairguide::synth::detail

#include <functional>
#include <string>
#include <vector>

#include "stairguide/synth/synth.hpp"
#include "stairguide/synth/builders.hpp"

namespace stairguide::synth::detail {

// What a preset builds: a scene plus either one static view or a walk.
struct PresetBuild {
  Scene scene;
  bool sequence = false;
  WalkerState view;  // static presets
  WalkSpec walk;     // sequences
};

struct PresetDef {
  PresetInfo info;
  bool sequence = false;
  // Builds the preset from `rng` (seeded per frame for static presets, per seed for sequences).
  std::function<void(Rng& rng, const SynthOptions& o, PresetBuild& out)> build;
};

// A preset's definition: its name, what it shows, the frames a full run takes (1 for a static
// view), whether it is a sequence, and how it is built.
PresetDef def(const char* name, const char* summary, long frames, bool sequence,
              std::function<void(Rng& rng, const SynthOptions& o, PresetBuild& out)> build);

const std::vector<PresetDef>& preset_defs();
// The world's stairs (synth::world_presets()), apart from preset_defs().
const std::vector<PresetDef>& world_preset_defs();
/// The traversal walks (synth.hpp: walk_presets()).
const std::vector<PresetDef>& walk_defs();
/// Views from any chest or waist rig (synth.hpp: rig_presets()).
const std::vector<PresetDef>& rig_defs();
/// The second world (synth.hpp: world2_presets()), in world2.cpp.
const std::vector<PresetDef>& world2_defs();
/// The drop-offs (issue 42 item 4), in synthetic_drops.cpp; and their ground truth (FrameTruth's
/// drop_* fields) from the scene's drop edges and the ideal render.
const std::vector<PresetDef>& drop_defs();
/// True when the point (camera frame) is seen in the ideal render `depth`: it projects into the
/// image and a pixel of its 3x3 neighbourhood has a rendered depth close to its own (truth.cpp).
bool point_seen(const Eigen::Vector3f& p, const cv::Mat& depth, const CameraIntrinsics& K,
                const SynthOptions& o);
void drop_truth(const Scene& scene, const WalkerState& walker, const RenderBuffers& ideal,
                const CameraIntrinsics& K, const SynthOptions& o, FrameTruth& t);
// nullptr when unknown.
const PresetDef* find_preset(const std::string& name);
std::uint64_t name_hash(const std::string& s);

}  // namespace stairguide::synth::detail
