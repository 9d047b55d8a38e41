// Drop-offs through the runtime's synchronous mode (the daemon's composition: odometry beside
// perception, the drop stage in PerceptionStage): on the walks towards a platform edge, every frame
// with the edge in view within 2 m is told, also where the view keeps only a strip of floor at the
// edge (the floor carried by the odometry). Seeds not tuned on.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "stairguide/runtime/pipeline.hpp"
#include "stairguide/runtime/runtime.hpp"

using namespace stairguide;

namespace {

struct WalkFigures {
  int near = 0, near_told = 0, far_told = 0, frames = 0;
  float first_told_m = -1.f;
  double abs_err = 0.0;
};

WalkFigures run_walk(const std::string& input) {
  PipelineConfig c;
  c.runtime.log_level = "warn";
  c.feedback.haptic_enabled = false;
  c.feedback.audio_enabled = false;
  runtime::RuntimeOptions o;
  o.input = input;
  o.realtime = false;
  o.synchronous = true;
  WalkFigures w;
  o.observer = [&](const runtime::FrameObservation& ob) {
    const auto truth = ob.source.truth();
    if (!truth) return;
    ++w.frames;
    const DropSummary& d = ob.perception.drop;
    if (d.detected && w.first_told_m < 0.f && truth->drop_in_view) w.first_told_m = truth->drop_distance_m;
    if (truth->drop_in_view && truth->drop_distance_m <= 2.f) {
      ++w.near;
      if (d.detected) {
        ++w.near_told;
        w.abs_err += std::fabs(d.distance_m - truth->drop_distance_m);
      }
    } else if (d.detected && !truth->drop_in_view) {
      ++w.far_told;
    }
  };
  runtime::Runtime rt(c, o, nullptr);
  EXPECT_EQ(rt.run(), 0) << input;
  return w;
}

}  // namespace

TEST(RuntimeDrops, PlatformWalkToldOnEveryNearFrame) {
  int near = 0, told = 0;
  for (const char* input :
       {"synth:drop_platform_walk:460:911:real-v1", "synth:drop_platform_walk:460:912:tof-v2",
        "synth:drop_platform_walk:460:913:sl-v1"}) {
    const WalkFigures w = run_walk(input);
    std::printf(
        "%s: first told %.2f m before the edge; near %d/%d (mean |error| %.3f m); told out of view %d\n",
        input, w.first_told_m, w.near_told, w.near, w.near_told ? w.abs_err / w.near_told : 0.0, w.far_told);
    EXPECT_GE(w.first_told_m, 1.9f) << input;
    EXPECT_GE(w.near, 100) << input;
    near += w.near;
    told += w.near_told;
  }
  EXPECT_GE(told, 0.98 * near);
}
