// Stairs of the world seen from any chest or waist rig (issue 34): the camera 0.5-1.8 m above the
// floor and tilted 15-80 deg, with no config change. The wearer's first views of an empty floor
// establish the rig (FloorDetector's rig model); then a flight drawn from the world's codes comes
// into view. Seeds 4201-4202: used nowhere else, never tuned on.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "stairguide/eval/stair_eval.hpp"
#include "synth_stairs_test_util.hpp"

namespace {

using namespace stairguide;

struct Figures : sgtest::WorldFigures {
  int floor_found = 0;
};

void run_rig(Figures& f, float h, float tilt, synth::RealSensor sensor, std::uint32_t seed, long views,
             bool free) {
  sgtest::SynthStairs p;
  p.options = synth::with_real_artefacts(sensor);
  p.options.camera_height_m = h;
  p.options.camera_tilt_deg = tilt;
  const long learn = p.cfg.floor.rig_learn_frames;
  for (const char* preset : {"world_ascending_static", "world_descending_static"}) {
    for (long i = 0; i < views; ++i) {
      // A new wearer: the rig learned on the first views of the floor, then the flight.
      p.perception.reset();
      for (long k = 0; k < learn; ++k) p.perceive("rig_floor_static", i * 16 + k, seed);
      const StairResult& r = p.step(preset, i, seed);
      f.floor_found += p.scene.floor_found;
      StairFrameEval e;
      if (f.add_flight(r, p.truth, e)) {
        const StairTruth* t = p.truth.stairs.empty() ? nullptr : &p.truth.stairs[0];
        std::printf(
            "rig %.1f m %.0f deg seed %u %s #%ld: %s%s (%s) truth riser %.1f tread %.1f; got %d levels "
            "riser %.1f tread %.1f floor %d (%s)\n",
            h, tilt, seed, preset, i, to_string(e.outcome), e.fully_visible ? " fully visible" : "",
            to_string(r.verdict), t ? 100 * t->riser_m : 0.f, t ? 100 * t->tread_m : 0.f, r.levels,
            100 * r.riser_m, 100 * r.tread_m, p.scene.floor_found, p.scene.why.c_str());
      }
    }
  }
  // The stair-free scenes (a table, a bench, shelves, a low box, a sofa...) from the same rig: from
  // a waist rig a bench's seat is as far below the camera as a chest rig's step is.
  if (!free) return;
  for (const char* preset : {"table_static", "bench_static", "shelves_static", "low_platform_static",
                             "sofa_static", "corridor_static", "room_clutter_static", "floor_only_static"}) {
    p.perception.reset();
    for (long k = 0; k < learn; ++k) p.perceive("rig_floor_static", 1000 + k, seed);
    const StairResult& r = p.step(preset, 0, seed);
    f.free.add(evaluate_stair_frame(r, p.truth));
    if (r.detected)
      std::printf("rig %.1f m %.0f deg seed %u %s: FALSE POSITIVE %s %d levels riser %.1f tread %.1f\n", h,
                  tilt, seed, preset, to_string(r.kind), r.levels, 100 * r.riser_m, 100 * r.tread_m);
  }
}

TEST(StairsRig, WorldFlightsFromAnyRig) {
  Figures f;
  for (float h : {0.6f, 0.9f, 1.3f, 1.8f})
    for (float tilt : {15.f, 35.f, 55.f, 75.f}) {
      run_rig(f, h, tilt, synth::RealSensor::kKinectV2, 4201u, 3, true);
      run_rig(f, h, tilt, synth::RealSensor::kKinectV1, 4202u, 3, false);
    }
  const EvalSummary& s = f.stairs;
  std::printf(
      "rigs: %d frames, TP %d FN %d FP %d skipped %d; fully visible %d of %d; floor %d; riser |err| %.2f cm "
      "(n %d), tread |err| %.2f cm (n %d); stair-free: %d frames, %d FP\n",
      s.frames, s.tp, s.fn, s.fp, s.skipped, f.full_detected, f.full_frames, f.floor_found,
      100 * s.riser.mean_abs(), s.riser.n, 100 * s.tread.mean_abs(), s.tread.n, f.free.frames, f.free.fp);
  // The figures of the world's range, from any rig. Measured: 51 of 51 fully visible
  // flights detected, riser 0.06 / tread 0.17 cm, 0 of 128 stair-free views, the floor on 183 of
  // 192 stair views. One detection lies off the true first edge: a narrow descent in a trench seen
  // from 1.3 m at 15 deg, its first edge under the view (not fully visible), reported at the
  // first edge in view, one tread farther (9 levels for 10); the tracker counts from the edges it
  // has seen as the user walks on.
  EXPECT_EQ(f.free.fp, 0);
  EXPECT_EQ(s.wrong_direction, 0);
  EXPECT_LE(s.fp, 1);
  EXPECT_GE(f.full_frames, 40);
  EXPECT_GE(f.full_detected, 0.98 * f.full_frames);
  EXPECT_GE(f.floor_found, 0.9 * s.frames) << "the rig's floor is lost before its stairs";
  EXPECT_GE(s.riser.n, 60);
  EXPECT_LE(s.riser.mean_abs(), 0.01);
  EXPECT_LE(s.tread.mean_abs(), 0.01);
}

}  // namespace
