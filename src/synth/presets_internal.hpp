#pragma once
// What the first world's preset files share (not part of the public API): views from the origin,
// rooms, a staircase ahead, a walk's camera and its support along a flight. presets.cpp defines
// them (with the paper's presets and the registry); presets_world.cpp,
// presets_rig.cpp and walks.cpp use them.
#include "internal.hpp"

namespace stairguide::synth::detail::presets {

using V3 = Eigen::Vector3f;
using V2 = Eigen::Vector2f;

// A view from the world origin (the user stands at the origin on the floor) looking roughly along
// `heading` (rad), the camera h_lo..h_hi m high and tilted tilt_lo..tilt_hi deg down unless the
// options fix them; the height and tilt drawn are returned through `height` / `tilt_out`.
WalkerState view_from_origin(Rng& rng, const SynthOptions& o, float h_lo, float h_hi, float tilt_lo,
                             float tilt_hi, float heading, float yaw_range_deg, float* height = nullptr,
                             float* tilt_out = nullptr);
// A random chest-camera view from the world origin, looking roughly along `heading` (rad).
WalkerState random_view(Rng& rng, const SynthOptions& o, float heading = 0.f, float yaw_range_deg = 25.f);
// A floor slab at floor_z and walls around [lo, hi] from wall_bottom up to 2.7 m above the floor.
void floor_and_room(Scene& s, Rng& rng, const V2& lo, const V2& hi, float floor_z = 0.f,
                    float wall_bottom = 0.f);
// Staircase 0.8-3.0 m ahead of the user at the origin, travel direction `yaw`.
Pose stair_ahead(Rng& rng, float yaw, float edge_z, float* dist = nullptr);
// A descending flight ahead in a room of walls down to its foot.
void descending_in_room(Rng& rng, const SynthOptions& o, PresetBuild& b, StairParams p);
// A room 9 x 7 m around the user at the origin.
void room(Rng& rng, PresetBuild& b);
// Makes `b` a sequence and gives its walk a camera 1.2-1.45 m high, tilted 40-50 deg, rolled
// +-2 deg (unless the options fix them); returns the walk.
WalkSpec& start_walk(Rng& rng, const SynthOptions& o, PresetBuild& b);
// Walk geometry along +x through a staircase whose first edge is at x = edge_x.
void stair_walk(WalkSpec& w, const StairSpec& st, float edge_x);

}  // namespace stairguide::synth::detail::presets
