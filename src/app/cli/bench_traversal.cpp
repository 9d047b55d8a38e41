// `stairguide bench traversal [--walks A,B,...] [--fps HZ] [--seed N] [--json]`: the traversal
// tracker's time per frame on synthetic walks (a climb and a descent by default), with the ground
// truth poses as the odometry. Perception runs untimed; the reference, measured on the same frames
// in the same run, is the stairs stage (detection + modelling) that feeds the tracker: the paper
// gives ST 1 ms beside its stair stage.
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
#include "stairguide/stairs/traversal.hpp"

namespace stairguide::cli {
namespace {

int bench_traversal(Context& ctx) {
  const bool json = ctx.flag("--json");
  std::vector<std::string> walks;
  if (const auto list = ctx.option("--walks")) {
    std::size_t a = 0;
    while (a <= list->size()) {
      const std::size_t b = std::min(list->find(',', a), list->size());
      if (b > a) walks.push_back(list->substr(a, b - a));
      a = b + 1;
    }
  }
  const double fps = static_cast<double>(ctx.int_option("--fps", 1, 60).value_or(15));
  const std::uint32_t seed = static_cast<std::uint32_t>(ctx.int_option("--seed", 0, 4294967295L).value_or(1));
  ctx.positionals(0, 0);
  if (walks.empty()) walks = {"climb_8_steps", "descend_8_steps"};
  for (const auto& w : walks)
    if (!synth::find_preset_info(w))
      throw UsageError("unknown walk '" + w + "' (see 'stairguide synth --list')");

  std::vector<double> tracker_ms, stairs_ms, holding_ms;  // holding: frames with a staircase held
  int frames = 0, on_stairs = 0;
  for (const auto& w : walks) {
    synth::SynthOptions opt;
    opt.fps = fps;
    const long n =
        static_cast<long>(static_cast<double>(synth::find_preset_info(w)->default_frames) * fps / 30.0);
    auto source = synth::make_source(w, n, seed, opt);
    Perception perception(ctx.config);
    StairStage stage(ctx.config);
    TraversalTracker tracker(ctx.config.traversal);
    RgbdFrame frame;
    SceneResult scene;
    StairResult stair;
    while (source->read(frame).ok()) {
      perception.process(frame, scene);
      const Timer ts;
      stage.run(scene, frame.intrinsics, stair);
      stairs_ms.push_back(ts.cpu());
      const Pose T = source->truth() ? source->truth()->T_world_camera : Pose::Identity();
      const Timer tt;
      const TraversalResult& r = tracker.update(scene, stair, T, true, frame.timestamp);
      tracker_ms.push_back(tt.cpu());
      if (r.direction != 0) holding_ms.push_back(tracker_ms.back());
      on_stairs += r.step_index >= 1;
      ++frames;
    }
  }
  if (frames == 0) {
    std::fprintf(stderr, "stairguide bench traversal: no frames rendered\n");
    return 1;
  }
  const double med = percentile(tracker_ms, 0.5), p95 = percentile(tracker_ms, 0.95);
  const double rmed = percentile(stairs_ms, 0.5);
  if (json) {
    std::printf(
        "{\"median_ms\": %.4f, \"p95_ms\": %.4f, \"max_ms\": %.4f, \"frames\": %d, \"frames_on_stairs\": %d, "
        "\"holding_median_ms\": %.4f, \"holding_frames\": %zu, \"reference_median_ms\": %.4f, "
        "\"reference\": \"stairs stage\", \"ratio\": %.3f, \"goal_ms\": 1.0}\n",
        med, p95, percentile(tracker_ms, 1.0), frames, on_stairs, percentile(holding_ms, 0.5),
        holding_ms.size(), rmed, med > 0 ? rmed / med : 0.0);
    return 0;
  }
  std::printf("traversal tracker, %d frames of %zu walk(s) at %.0f Hz (%d on the flight), thread CPU time\n",
              frames, walks.size(), fps, on_stairs);
  std::printf("  tracker:   median %.4f ms  p95 %.4f ms  max %.4f ms  (goal: median <= 1 ms)\n", med, p95,
              percentile(tracker_ms, 1.0));
  std::printf("  tracker, frames with a staircase held (%zu): median %.4f ms  p95 %.4f ms\n",
              holding_ms.size(), percentile(holding_ms, 0.5), percentile(holding_ms, 0.95));
  std::printf("  reference: stairs stage on the same frames, median %.3f ms (%.0fx the tracker)\n", rmed,
              med > 0 ? rmed / med : 0.0);
  return 0;
}

}  // namespace

SG_BENCH("traversal", "traversal [--walks A,B,...] [--fps HZ] [--seed N] [--json]",
         "traversal tracker per frame on synthetic walks (stairs stage as the reference)", bench_traversal);

}  // namespace stairguide::cli
