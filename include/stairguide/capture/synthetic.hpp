#pragma once
/// \file synthetic.hpp
/// The synthetic stair world: scenes of simple solids, a chest-mounted camera on a trajectory,
/// a Kinect-like sensor model, and per-frame ground truth. The project's ground truth for every
/// accuracy claim (the seed's real datasets cannot be had here).

#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "stairguide/capture/frame_source.hpp"

namespace stairguide::synth {

/// One line per preset: name and what it shows.
struct PresetInfo {
  std::string name;
  std::string summary;
  long default_frames = 1;  ///< frames a full run of the preset takes (1 for a static view)
};

/// All presets (at least 20, covering ascending, descending, open risers, single step, curb,
/// distractors, occluding people, rotated staircase, ...).
const std::vector<PresetInfo>& presets();

/// Sensor and trajectory options common to every preset.
struct SynthOptions {
  bool noise = true;              ///< Kinect-like depth noise, quantisation, holes
  int width = 640;
  int height = 480;
  /// Overrides of the camera mounting; NaN keeps the preset's (seeded) value.
  float camera_height_m = std::numeric_limits<float>::quiet_NaN();
  float camera_tilt_deg = std::numeric_limits<float>::quiet_NaN();
};

/// A FrameSource rendering a preset frame by frame; `truth()` gives each frame's ground truth.
/// Throws SourceError for an unknown preset name (the message lists the known ones).
std::unique_ptr<FrameSource> make_source(const std::string& preset, long frames, std::uint32_t seed,
                                         const SynthOptions& options = {});

}  // namespace stairguide::synth
