#pragma once
// The synthetic world through perception and the stairs stage, one frame at a time as in use:
// the set-up the stairs tests on rendered frames share.

#include <cstdint>
#include <string>

#include "stairguide/synth/synth.hpp"
#include "stairguide/perception/perception.hpp"
#include "stairguide/eval/stair_eval.hpp"
#include "stairguide/stairs/stairs.hpp"

namespace sgtest {

struct SynthStairs {
  explicit SynthStairs(const stairguide::PipelineConfig& config = stairguide::PipelineConfig{})
      : cfg(config), perception(cfg), stage(cfg) {}

  /// Renders frame `i` of `preset` (seed `seed`) and runs perception on it, from nothing when
  /// `cold` (an independent view), else tracking from the frames before.
  void perceive(const std::string& preset, long i, std::uint32_t seed, bool cold = false) {
    stairguide::synth::render_preset_frame(preset, i, seed, options, frame, truth);
    if (cold) perception.reset();
    perception.process(frame, scene);
  }
  /// The stairs stage on the last frame perceived.
  const stairguide::StairResult& stairs() {
    stage.run(scene, frame.intrinsics, result);
    return result;
  }
  /// Both.
  const stairguide::StairResult& step(const std::string& preset, long i, std::uint32_t seed,
                                      bool cold = false) {
    perceive(preset, i, seed, cold);
    return stairs();
  }

  stairguide::PipelineConfig cfg;
  stairguide::synth::SynthOptions options;  ///< the sensor model (the suites: the defaults)
  stairguide::Perception perception;
  stairguide::StairStage stage;
  stairguide::RgbdFrame frame;
  stairguide::FrameTruth truth;
  stairguide::SceneResult scene;
  stairguide::StairResult result;
};

/// The world suites' figures: every flight frame scored, the frames with two or more steps fully
/// visible and those of them detected, and the stair-free frames.
struct WorldFigures {
  stairguide::EvalSummary stairs, free;
  int full_frames = 0, full_detected = 0;
  /// Scores a flight frame; true when it is a miss worth describing (neither TP, TN nor skipped).
  bool add_flight(const stairguide::StairResult& r, const stairguide::FrameTruth& truth,
                  stairguide::StairFrameEval& e) {
    using stairguide::EvalOutcome;
    e = stairguide::evaluate_stair_frame(r, truth);
    stairs.add(e);
    if (e.fully_visible) {
      ++full_frames;
      full_detected += e.outcome == EvalOutcome::kTP;
    }
    return e.outcome != EvalOutcome::kTP && e.outcome != EvalOutcome::kTN &&
           e.outcome != EvalOutcome::kSkipped;
  }
};

/// One independent view (perception from nothing, as `stairguide eval` runs static presets): the
/// stairs stage's result and the frame's truth.
inline void run_view(const char* preset, long view, std::uint32_t seed, stairguide::StairResult& r,
                     stairguide::FrameTruth& truth) {
  SynthStairs p;
  r = p.step(preset, view, seed, /*cold=*/true);
  truth = p.truth;
}

}  // namespace sgtest
