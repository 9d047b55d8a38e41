// The world's stairs (synth::world_presets()): flights drawn from the range of the building
// codes of the world (../shared/data/SOURCES.md), not from the paper's.
#include <algorithm>
#include <cmath>

#include "presets_internal.hpp"

namespace stairguide::synth::detail {

using namespace presets;

namespace {

// Riser, tread, width, nosing and length from the codes of the world (SOURCES.md): risers 10-22
// cm, treads 20-45 cm, 2R+T 50-72 cm (riser and tread drawn together until they satisfy it), narrow
// flights (0.65-0.9 m) and wide ones (1.8-2.6 m) as well as the usual, nosings on 40%.
StairParams world_stair(Rng& rng, StairKind kind) {
  StairParams p;
  p.kind = kind;
  p.steps = rng.integer(2, 14);
  for (int i = 0; i < 100; ++i) {
    p.riser_m = rng.uniform(0.10f, 0.22f);
    p.tread_m = rng.uniform(0.20f, 0.45f);
    const float blondel = 2.f * p.riser_m + p.tread_m;
    if (blondel >= 0.50f && blondel <= 0.72f) break;
  }
  const float w = rng.uniform();
  p.width_m =
      w < 0.25f ? rng.uniform(0.65f, 0.9f) : (w < 0.45f ? rng.uniform(1.8f, 2.6f) : rng.uniform(0.9f, 1.8f));
  p.nosing_m = rng.chance(0.4f) ? rng.uniform(0.01f, 0.04f) : 0.f;
  p.wall_start_m = rng.uniform(-1.5f, 0.f);
  p.top_depth_m = rng.uniform(1.2f, 3.f);
  return p;
}

void world_ascending_static(Rng& rng, const SynthOptions& o, PresetBuild& b) {
  StairParams p = world_stair(rng, StairKind::kAscending);
  float d = 0.f;
  p.T_world_stair = stair_ahead(rng, 0.f, p.riser_m, &d);
  p.open_risers = rng.chance(0.2f);
  if (p.open_risers) p.nosing_m = 0.f;
  p.side_walls = !p.open_risers && rng.chance(0.6f);
  p.handrails = rng.chance(0.5f);
  const bool landing = p.steps >= 3 && rng.chance(0.25f);
  if (landing) p.top_depth_m = rng.uniform(0.9f, 1.5f);
  float end = d + static_cast<float>(p.steps - 1) * p.tread_m + p.top_depth_m;
  StairParams q = p;
  if (landing) {  // a landing, then a second flight of the same steps
    const float landing_z = static_cast<float>(p.steps) * p.riser_m;
    q.steps = rng.integer(2, 6);
    q.base_z = landing_z;
    q.wall_start_m = 0.f;
    q.top_depth_m = 2.f;
    q.T_world_stair.translation() =
        p.T_world_stair * Eigen::Vector3f(0.f, landing_z - p.riser_m + q.riser_m, end - d);
    end += static_cast<float>(q.steps - 1) * q.tread_m + q.top_depth_m;
  }
  const float half = 0.5f * p.width_m + rng.uniform(0.2f, 2.5f);
  floor_and_room(b.scene, rng, V2(-3.f, -half - 0.5f), V2(end + 0.2f, half + 0.5f));
  add_staircase(b.scene, p, rng);
  if (landing) add_staircase(b.scene, q, rng);
  b.view = random_view(rng, o);
}

void world_descending_static(Rng& rng, const SynthOptions& o, PresetBuild& b) {
  descending_in_room(rng, o, b, world_stair(rng, StairKind::kDescending));
}

}  // namespace

const std::vector<PresetDef>& world_preset_defs() {
  static const std::vector<PresetDef> defs = {
      def("world_ascending_static",
          "random views of an ascending flight drawn from the world's codes (riser 10-22, tread 20-45 cm, "
          "2R+T "
          "50-72 cm, width 0.65-2.6 m, 2-14 steps; nosings, open risers, landings)",
          1, false, world_ascending_static),
      def("world_descending_static", "random views of a descending flight drawn from the world's codes", 1,
          false, world_descending_static),
  };
  return defs;
}

}  // namespace stairguide::synth::detail
