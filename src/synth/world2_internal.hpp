#pragma once
// What the second world's files share (not part of the public API): the wearer's views, the room
// around them, and the builders of the stair-free furniture (world2_furniture.cpp), which
// world2.cpp registers with its stairs in world2_defs().
#include "internal.hpp"

namespace stairguide::synth::detail::world2 {

using V3 = Eigen::Vector3f;
using V2 = Eigen::Vector2f;
constexpr float kPi = 3.14159265f;

// A camera mounting range: height above the surface stood on (m) and tilt below horizontal (deg).
struct Rig {
  float h_lo, h_hi, tilt_lo, tilt_hi;
};
constexpr Rig kChest{1.0f, 1.6f, 30.f, 60.f};  // the first world's chest range

// The wearer standing at `body` (a point of the surface they stand on) facing `yaw`, the camera
// 0.12 m ahead of the body, h_lo..h_hi m above that surface, tilted tilt_lo..tilt_hi deg down,
// rolled +-3 deg (unless the options fix height, tilt or roll).
WalkerState view_at(Rng& rng, const SynthOptions& o, const V3& body, float yaw, float h_lo, float h_hi,
                    float tilt_lo, float tilt_hi);
WalkerState view_at(Rng& rng, const SynthOptions& o, const V3& body, float yaw, const Rig& rig);
// A chest camera (1.0-1.6 m, tilted 30-60 deg).
WalkerState chest_view(Rng& rng, const SynthOptions& o, const V3& body, float yaw);
// A chest view from the world origin, heading within +-25 deg of +x.
WalkerState chest_view_ahead(Rng& rng, const SynthOptions& o);
// A floor slab and four walls 2.7 m high around [lo, hi].
void floor_and_walls(Scene& s, Rng& rng, const V2& lo, const V2& hi);
// A living room or bedroom 9 x 7 m around the wearer at the origin.
void room(Scene& s, Rng& rng);
// Pose of a frame at `p` whose x axis points along `yaw` (world), z up.
Pose yaw_frame(const V3& p, float yaw);
// Cardboard: a box's plain, light brown-blue faces.
Material cardboard(Rng& rng);

// ---- stair-free furniture (labels: none), world2_furniture.cpp ----
void shelves_static(Rng& rng, const SynthOptions& o, PresetBuild& b);
void boxes_static(Rng& rng, const SynthOptions& o, PresetBuild& b);
void sofa_static(Rng& rng, const SynthOptions& o, PresetBuild& b);
void bench_static(Rng& rng, const SynthOptions& o, PresetBuild& b);
void lowtable_static(Rng& rng, const SynthOptions& o, PresetBuild& b);
void bed_static(Rng& rng, const SynthOptions& o, PresetBuild& b);

}  // namespace stairguide::synth::detail::world2
