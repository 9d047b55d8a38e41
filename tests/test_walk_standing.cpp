// A wearer standing still at a staircase (issue 39, "the floor of a standing wearer"): any rig in
// range (0.5-1.8 m, 15-80 deg), nothing learned before, the flight in view from the first frame.
// The daemon's own perception stage (runtime::PerceptionStage, as in --sync) sees the same view
// frame after frame, each through fresh sensor noise; within 30 frames (one second) it must have
// the floor and the staircase, placed where it is.
//
// StandingWearer.FloorAndStairsWithinASecond runs a grid small enough for CI (seed 4301, never
// tuned on). DISABLED_Measure is the figure: SG_STANDING_SEEDS (default "4301 4302"),
// SG_STANDING_VIEWS (default 3) views per flight preset, on every rig of the grid below;
// SG_STANDING_JSON=FILE also writes the figure as JSON (tools/figures does).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "stairguide/synth/synth.hpp"
#include "stairguide/perception/scene.hpp"
#include "stairguide/runtime/pipeline.hpp"
#include "stairguide/eval/stair_eval.hpp"
#include "stairguide/stairs/stair_result.hpp"

namespace {

using namespace stairguide;

constexpr long kFrames = 30;  // one second at the sensor's pace

struct Rig {
  float height_m, tilt_deg;
};

/// What became of one (rig, flight) pair.
struct PairOutcome {
  bool in_view = false;  ///< two or more whole steps of the flight in view (truth)
  int first_frame = -1;  ///< first frame with the floor and the flight (a true positive); -1 none
  bool held = false;     ///< and still so on the last frame
  std::string last;      ///< the last frame's state, for the report
};

PairOutcome stand(const PipelineConfig& cfg, const std::string& preset, long view, std::uint32_t seed,
                  Rig rig, synth::RealSensor sensor) {
  synth::SynthOptions o = synth::with_real_artefacts(sensor);
  o.camera_height_m = rig.height_m;
  o.camera_tilt_deg = rig.tilt_deg;
  runtime::PerceptionStage stage(cfg);
  RgbdFrame frame;
  FrameTruth truth;
  PairOutcome out;
  for (long k = 0; k < kFrames; ++k) {
    o.noise_salt = static_cast<std::uint32_t>(k);
    synth::render_preset_frame(preset, view, seed, o, frame, truth);
    frame.index = static_cast<std::uint64_t>(k);
    frame.timestamp = static_cast<double>(k) / 30.0;
    const runtime::PerceptionOutput p = stage.step(frame, static_cast<std::uint64_t>(k), {});
    const StairFrameEval e = evaluate_stair_frame(stage.last_stair(), truth);
    if (k == 0) {
      out.in_view = e.fully_visible;
      if (!out.in_view) return out;  // a rig that does not see the flight: not a pair
    }
    const bool ok = p.floor_found && e.outcome == EvalOutcome::kTP;
    if (ok && out.first_frame < 0) out.first_frame = static_cast<int>(k);
    out.held = ok;
    out.last = p.state + " (" + p.detail + ")";
  }
  return out;
}

struct Tally {
  int pairs = 0, told = 0;
  std::vector<int> first_frames;    ///< of the pairs told
  std::vector<std::string> misses;  ///< what was missed, and the last frame's state
  void add(const PairOutcome& o, const char* what) {
    if (!o.in_view) return;
    ++pairs;
    const bool good = o.first_frame >= 0 && o.held;
    told += good;
    if (good) first_frames.push_back(o.first_frame);
    if (good) return;
    misses.push_back(std::string(what) + ": first " + std::to_string(o.first_frame) + ", last frame " +
                     o.last);
    std::printf("standing: MISSED %s\n", misses.back().c_str());
  }
};

std::string json_string(const std::string& s) {
  std::string o = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') o += '\\';
    o += c;
  }
  return o + "\"";
}

/// The figure as JSON (tools/figures stores it in docs/figures/standing-wearer.json).
void write_json(const Tally& t, const char* path) {
  std::vector<int> f = t.first_frames;
  std::sort(f.begin(), f.end());
  std::FILE* out = std::fopen(path, "w");
  ASSERT_NE(out, nullptr) << "cannot write " << path;
  std::fprintf(out, "{\"pairs\": %d, \"told\": %d, \"told_share\": %.4f, \"frames\": %ld, ", t.pairs, t.told,
               t.pairs ? static_cast<double>(t.told) / t.pairs : 0.0, kFrames);
  std::fprintf(out, "\"first_frame_median\": %d, \"first_frame_max\": %d, \"misses\": [",
               f.empty() ? -1 : f[f.size() / 2], f.empty() ? -1 : f.back());
  for (std::size_t i = 0; i < t.misses.size(); ++i)
    std::fprintf(out, "%s%s", i ? ", " : "", json_string(t.misses[i]).c_str());
  std::fprintf(out, "]}\n");
  std::fclose(out);
}

void run_grid(Tally& t, const std::vector<Rig>& rigs, const std::vector<std::uint32_t>& seeds, long views) {
  const PipelineConfig cfg;
  for (std::uint32_t seed : seeds)
    for (const Rig& rig : rigs)
      for (const char* preset : {"world_ascending_static", "world_descending_static", "world2_lowrig_static"})
        for (long v = 0; v < views; ++v) {
          const synth::RealSensor sensor =
              (v + seed) % 2 ? synth::RealSensor::kKinectV1 : synth::RealSensor::kKinectV2;
          const PairOutcome o = stand(cfg, preset, v, seed, rig, sensor);
          char what[160];
          std::snprintf(what, sizeof what, "rig %.1f m %.0f deg, %s #%ld seed %u", rig.height_m, rig.tilt_deg,
                        preset, v, seed);
          t.add(o, what);
        }
}

std::vector<std::uint32_t> env_seeds(const char* name, std::vector<std::uint32_t> dflt) {
  const char* s = std::getenv(name);
  if (!s) return dflt;
  std::vector<std::uint32_t> v;
  std::istringstream in(s);
  for (unsigned x; in >> x;) v.push_back(x);
  return v.empty() ? dflt : v;
}

TEST(StandingWearer, FloorAndStairsWithinASecond) {
  // Low and high rigs, shallow and steep tilts: the corners of the range and the waist rig.
  const std::vector<Rig> rigs = {{0.6f, 25.f}, {0.6f, 50.f}, {0.9f, 35.f},
                                 {1.3f, 45.f}, {1.8f, 20.f}, {1.8f, 70.f}};
  Tally t;
  run_grid(t, rigs, {4301u}, 1);
  std::printf(
      "standing wearer: %d of %d (rig, flight) pairs with the floor and the flight within %ld frames\n",
      t.told, t.pairs, kFrames);
  ASSERT_GE(t.pairs, 6) << "too few rigs see a flight: the grid tests nothing";
  EXPECT_GE(t.told, t.pairs - 1);
}

// A rig tilted steeply enough (80 deg) has the nadir in view: the floor is seen under the camera
// and behind its foot, however close the flight starts (a waist-camera flight seen from a chest
// rig fills the view; a descent may start at the user's toes). Before the floor detector took the
// level seen there for what the user stands on, the flight ahead made the floor a possible tread,
// or the treads nearer the nadir than the floor beside them "something below it": 3 of these
// pairs (seeds 4301-4302, the grid) were missed that way. Seed 4303 was never tuned on
// (16 of 16 here; rigs 1.1, 1.4 and 1.8 m on seeds 4301, 4302, 4305 and 4306 gave 27 of 27).
TEST(StandingWearer, SteepRigSeesTheFloorUnderItsFoot) {
  const std::vector<Rig> rigs = {{1.1f, 80.f}, {1.8f, 80.f}};
  Tally t;
  run_grid(t, rigs, {4301u, 4302u, 4303u}, 3);
  std::printf("steep rigs: %d of %d (rig, flight) pairs with the floor and the flight within %ld frames\n",
              t.told, t.pairs, kFrames);
  ASSERT_GE(t.pairs, 8) << "too few rigs see a flight: the grid tests nothing";
  EXPECT_EQ(t.told, t.pairs);
}

// A tall rig looking nearly level (1.8 m, 15 deg) at a flight 2.75 m ahead sees its floor as a strip
// of 0.03-0.09 m^2 before the first riser. Learned from the first clear views, the rig's height and
// tilt make that strip the floor tracked frame after frame although it is smaller than a tracked
// floor must otherwise be; before, the floor came and went with the noise (the strip refused as a
// sliver, then as a possible first tread), and the pair was lost on its last frame. Tuning pair
// (seed 4302, the grid).
TEST(StandingWearer, AStripOfFloorIsHeldOnceTheRigIsKnown) {
  Tally t;
  run_grid(t, {{1.8f, 15.f}}, {4302u}, 2);
  ASSERT_GE(t.pairs, 2) << "too few views see a flight: the test tests nothing";
  EXPECT_EQ(t.told, t.pairs);
}

TEST(StandingWearer, DISABLED_Measure) {
  std::vector<Rig> rigs;
  for (float h : {0.5f, 0.8f, 1.1f, 1.4f, 1.8f})
    for (float tilt : {15.f, 35.f, 55.f, 80.f}) rigs.push_back({h, tilt});
  const char* v = std::getenv("SG_STANDING_VIEWS");
  Tally t;
  run_grid(t, rigs, env_seeds("SG_STANDING_SEEDS", {4301u, 4302u}), v ? std::atol(v) : 3);
  std::printf(
      "standing wearer: %d of %d (rig, flight) pairs with the floor and the flight within %ld frames "
      "(%.1f%%)\n",
      t.told, t.pairs, kFrames, t.pairs ? 100.0 * t.told / t.pairs : 0.0);
  if (const char* path = std::getenv("SG_STANDING_JSON")) write_json(t, path);
}

}  // namespace
