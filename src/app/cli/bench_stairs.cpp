// `stairguide bench stairs [--json] [--frames N] [--repeat R]`: stair detection + modelling time per
// frame on the synthetic presets. Perception runs beforehand and is not timed. The reference, run on
// the same scenes in the same process, is the same stage with the connection test on every point
// of every region (no subsampling): the cost of Algorithm 1's neighbour search done exhaustively.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "cli/bench_util.hpp"
#include "cli/command.hpp"
#include "stairguide/capture/synth_source.hpp"
#include "stairguide/perception/perception.hpp"
#include "stairguide/stairs/stairs.hpp"

namespace stairguide::cli {
namespace {

std::vector<double> time_stage(StairStage& stage, const std::vector<SceneResult>& scenes,
                               const CameraIntrinsics& K, int repeat, int& detected) {
  std::vector<double> ms;
  StairResult r;
  for (const auto& s : scenes) stage.run(s, K, r);  // warm-up: buffers reach their size
  detected = 0;
  for (int k = 0; k < repeat; ++k) {
    for (const auto& s : scenes) {
      const auto t0 = std::chrono::steady_clock::now();
      stage.run(s, K, r);
      const auto t1 = std::chrono::steady_clock::now();
      ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
      if (k == 0 && r.detected) ++detected;
    }
  }
  return ms;
}

int bench_stairs(Context& ctx) {
  const bool json = ctx.flag("--json");
  const long per_preset = ctx.int_option("--frames", 1, 1000).value_or(4);
  const long repeat = ctx.int_option("--repeat", 1, 1000).value_or(5);
  ctx.positionals(0, 0);

  Perception perception(ctx.config);
  std::vector<SceneResult> scenes;
  const CameraIntrinsics K = synth::synthetic_intrinsics({});
  std::size_t regions = 0, candidates = 0;
  for (const auto& p : synth::presets()) {
    auto source = synth::make_source(p.name, per_preset, 7);
    RgbdFrame frame;
    while (source->read(frame).ok()) {
      perception.reset();
      scenes.push_back(perception.process(frame));
      regions += scenes.back().regions.size();
      for (const auto& r : scenes.back().regions)
        if (r.cls == RegionClass::kStepCandidate) ++candidates;
    }
  }
  if (scenes.empty()) {
    std::fprintf(stderr, "stairguide bench stairs: no frames rendered\n");
    return 1;
  }
  StairStage ours(ctx.config);
  PipelineConfig ref_cfg = ctx.config;
  ref_cfg.stair_detection.connection_max_points = 100000;
  StairStage reference(ref_cfg);
  int det_ours = 0, det_ref = 0;
  const auto t_ours = time_stage(ours, scenes, K, static_cast<int>(repeat), det_ours);
  const auto t_ref = time_stage(reference, scenes, K, static_cast<int>(repeat), det_ref);
  const double med = percentile(t_ours, 0.5), p95 = percentile(t_ours, 0.95);
  const double rmed = percentile(t_ref, 0.5), rp95 = percentile(t_ref, 0.95);
  const double ratio = med > 0 ? rmed / med : 0.0;
  if (json) {
    std::printf(
        "{\"median_ms\": %.4f, \"p95_ms\": %.4f, \"max_ms\": %.4f, \"frames\": %zu, \"repeat\": %ld, "
        "\"detected\": %d, \"reference_median_ms\": %.4f, \"reference_p95_ms\": %.4f, "
        "\"reference_detected\": %d, \"ratio\": %.3f, \"step_candidates_per_frame\": %.2f, "
        "\"regions_per_frame\": %.2f}\n",
        med, p95, percentile(t_ours, 1.0), scenes.size(), repeat, det_ours, rmed, rp95, det_ref, ratio,
        static_cast<double>(candidates) / static_cast<double>(scenes.size()),
        static_cast<double>(regions) / static_cast<double>(scenes.size()));
    return 0;
  }
  std::printf("stair detection + modelling, %zu frames (%ld per preset) x %ld runs, perception not timed\n",
              scenes.size(), per_preset, repeat);
  std::printf("  ours:      median %.3f ms  p95 %.3f ms  max %.3f ms  (%d frames with a stair)\n", med, p95,
              percentile(t_ours, 1.0), det_ours);
  std::printf(
      "  reference: median %.3f ms  p95 %.3f ms  (exhaustive connection test, %d frames with a stair)\n",
      rmed, rp95, det_ref);
  std::printf("  ratio reference/ours (median): %.2fx\n", ratio);
  std::printf("  %.1f regions, %.1f step candidates per frame\n",
              static_cast<double>(regions) / static_cast<double>(scenes.size()),
              static_cast<double>(candidates) / static_cast<double>(scenes.size()));
  return 0;
}

}  // namespace

SG_BENCH("stairs", "stairs [--json] [--frames N] [--repeat R]",
         "stair detection + modelling per frame (perception done beforehand)", bench_stairs);

}  // namespace stairguide::cli
