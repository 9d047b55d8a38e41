// The synthetic FrameSource: a thin reader over synth::PresetRenderer.
#include "stairguide/capture/synth_source.hpp"

namespace stairguide::synth {
namespace {

class SyntheticSource final : public FrameSource {
 public:
  SyntheticSource(const std::string& preset, long frames, std::uint32_t seed, const SynthOptions& o)
      : renderer_(preset, frames, seed, o) {}

  ReadResult read(RgbdFrame& out) override {
    if (next_ >= renderer_.frames())
      return {ReadStatus::kEnd,
              describe() + ": end of sequence after " + std::to_string(renderer_.frames()) + " frames"};
    renderer_.render(next_++, out, truth_);
    has_truth_ = true;
    return {};
  }
  CameraIntrinsics intrinsics() const override { return renderer_.intrinsics(); }
  long frame_count() const override { return renderer_.frames(); }
  bool independent_frames() const override { return !renderer_.sequence(); }
  std::string describe() const override { return "synthetic " + renderer_.info().name; }
  std::optional<FrameTruth> truth() const override {
    if (!has_truth_) return std::nullopt;
    return truth_;
  }

 private:
  PresetRenderer renderer_;
  long next_ = 0;
  FrameTruth truth_;
  bool has_truth_ = false;
};

}  // namespace

std::unique_ptr<FrameSource> make_source(const std::string& preset, long frames, std::uint32_t seed,
                                         const SynthOptions& options) {
  return std::make_unique<SyntheticSource>(preset, frames, seed, options);
}

}  // namespace stairguide::synth
