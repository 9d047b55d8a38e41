#pragma once
/// \file synth_source.hpp
/// The synthetic world (synth/synth.hpp) as a FrameSource: what a `synth:` input opens.

#include <cstdint>
#include <memory>
#include <string>

#include "stairguide/capture/frame_source.hpp"
#include "stairguide/synth/synth.hpp"

namespace stairguide::synth {

/// A FrameSource rendering a preset frame by frame (synth::PresetRenderer); `truth()` gives each
/// frame's ground truth. `frames` <= 0 takes the preset's default_frames; a sequence asked for more
/// frames than its default holds its final pose. Timestamps are index / fps.
/// Throws SourceError for an unknown preset name (the message lists the known ones) or bad options.
std::unique_ptr<FrameSource> make_source(const std::string& preset, long frames, std::uint32_t seed,
                                         const SynthOptions& options = {});

}  // namespace stairguide::synth
