// Views from any chest or waist rig (synth::rig_presets()): the camera anywhere in 0.5-1.8 m,
// tilted 15-80 deg, in an empty room or before furniture 0.4-0.8 m below it.
#include <algorithm>
#include <cmath>

#include "presets_internal.hpp"

namespace stairguide::synth::detail {

using namespace presets;

namespace {

// A view from a rig of any height and tilt: a waist-mounted camera at 0.5 m looking nearly level,
// a chest one at 1.8 m looking almost straight down. Drawn from the range the issue asks the
// floor to cope with, not from the floor detector's gate.
WalkerState rig_view(Rng& rng, const SynthOptions& o, float* height = nullptr, float* tilt_out = nullptr) {
  return view_from_origin(rng, o, 0.5f, 1.8f, 15.f, 80.f, 0.f, 25.f, height, tilt_out);
}

// A large horizontal surface 0.4-0.8 m below the camera (lower rigs: a low one, 0.25-0.45 m high),
// framed in the view with the floor around it: a table, a bed, a bench, or a raised landing (a
// closed box of concrete, a mezzanine seen from the floor).
void rig_furniture_static(Rng& rng, const SynthOptions& o, PresetBuild& b) {
  room(rng, b);
  float h = 1.f, tilt = 0.7f;
  b.view = rig_view(rng, o, &h, &tilt);
  float top = h - rng.uniform(0.4f, 0.8f);
  if (top < 0.25f) top = rng.uniform(0.25f, std::max(0.26f, std::min(0.45f, h - 0.1f)));
  // Where the optical axis meets the floor (far out for a nearly level camera): the surface's
  // near edge lies somewhere from under a third of that to past it.
  const float centre = std::min(3.5f, h / std::tan(std::max(tilt, 0.2f)));
  const float near_edge = std::clamp(rng.uniform(0.3f, 1.4f) * centre, 0.35f, 3.0f);
  const float lat = rng.uniform(-0.6f, 0.6f);
  const float yaw = b.view.yaw + rng.uniform(-0.4f, 0.4f);
  const V3 fwd(std::cos(b.view.yaw), std::sin(b.view.yaw), 0.f), left(-fwd.y(), fwd.x(), 0.f);
  const int kind = rng.integer(0, 3);
  if (kind == 0) {  // table
    const float len = rng.uniform(1.0f, 1.8f), dep = rng.uniform(0.6f, 0.9f);
    add_table(b.scene, (near_edge + 0.5f * dep) * fwd + lat * left, yaw + 1.5707963f, top, len, dep, rng);
  } else if (kind == 1) {  // bed
    const V3 size(rng.uniform(1.9f, 2.1f), rng.uniform(0.9f, 1.6f), top);
    add_crate(b.scene, (near_edge + 0.5f * size.x()) * fwd + lat * left, yaw, size, fabric_material(rng),
              "bed");
  } else if (kind == 2) {  // bench
    add_bench(b.scene, (near_edge + 0.2f) * fwd + lat * left, yaw + 1.5707963f, top, rng.uniform(1.2f, 2.0f),
              rng);
  } else {  // a raised landing
    const V3 size(rng.uniform(1.2f, 2.5f), rng.uniform(1.2f, 2.5f), top);
    add_crate(b.scene, (near_edge + 0.5f * size.x()) * fwd + lat * left, yaw, size, concrete_material(rng),
              "landing");
  }
}

}  // namespace

const std::vector<PresetDef>& rig_defs() {
  static const std::vector<PresetDef> defs = {
      def("rig_floor_static", "an empty room seen from any rig: camera 0.5-1.8 m high, tilted 15-80 deg", 1,
          false,
          [](Rng& rng, const SynthOptions& o, PresetBuild& b) {
            room(rng, b);
            b.view = rig_view(rng, o);
          }),
      def("rig_furniture_static",
          "any rig (0.5-1.8 m, 15-80 deg) before a table, bed, bench or raised landing 0.4-0.8 m below the "
          "camera",
          1, false, rig_furniture_static),
  };
  return defs;
}

}  // namespace stairguide::synth::detail
