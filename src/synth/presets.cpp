// The presets of the synthetic world (names fixed by the project's presets brief). Static presets
// draw every frame as an independent random view; sequences walk a trajectory through one scene.
// Distributions follow the brief: camera height 1.0-1.6 m, tilt 30-60 deg, roll +-3 deg, the
// staircase 0.8-3.0 m ahead, heading +-25 deg; riser 15-18 cm, tread 28-32 cm, width 0.9-1.6 m,
// 4-12 steps. The world's stairs (presets_world.cpp) draw from the building codes of the world
// instead; the rig views are in presets_rig.cpp, the traversal walks in walks.cpp. This file also
// holds the registry of every preset (find_preset).
#include <algorithm>
#include <cmath>

#include "presets_internal.hpp"

namespace stairguide::synth::detail {
namespace presets {

float pick(float v, float fallback) { return std::isnan(v) ? fallback : v; }

// A view from the world origin (the user stands at the origin on the floor) looking roughly along
// `heading` (rad), the camera h_lo..h_hi m high and tilted tilt_lo..tilt_hi deg down unless the
// options fix them; the height and tilt drawn are returned through `height` / `tilt_out`.
WalkerState view_from_origin(Rng& rng, const SynthOptions& o, float h_lo, float h_hi, float tilt_lo,
                             float tilt_hi, float heading, float yaw_range_deg, float* height,
                             float* tilt_out) {
  const float h = pick(o.camera_height_m, rng.uniform(h_lo, h_hi));
  const float tilt = deg2rad(pick(o.camera_tilt_deg, rng.uniform(tilt_lo, tilt_hi)));
  const float roll = deg2rad(pick(o.camera_roll_deg, rng.uniform(-3.f, 3.f)));
  const float yaw = heading + deg2rad(rng.uniform(-yaw_range_deg, yaw_range_deg));
  if (height) *height = h;
  if (tilt_out) *tilt_out = tilt;
  WalkerState st;
  st.body = V3(0.f, 0.f, 0.f);
  st.yaw = yaw;
  st.support_z = 0.f;
  const V3 cam = st.body + 0.12f * V3(std::cos(yaw), std::sin(yaw), 0.f) + V3(0.f, 0.f, h);
  st.T_world_camera = camera_pose(cam, yaw, tilt, roll);
  return st;
}

// A random chest-camera view from the world origin, looking roughly along `heading` (rad).
WalkerState random_view(Rng& rng, const SynthOptions& o, float heading, float yaw_range_deg) {
  return view_from_origin(rng, o, 1.0f, 1.6f, 30.f, 60.f, heading, yaw_range_deg);
}

StairParams random_stair(Rng& rng, StairKind kind) {
  StairParams p;
  p.kind = kind;
  p.steps = rng.integer(4, 12);
  p.riser_m = rng.uniform(0.15f, 0.18f);
  p.tread_m = rng.uniform(0.28f, 0.32f);
  p.width_m = rng.uniform(0.9f, 1.6f);
  p.wall_start_m = rng.uniform(-1.5f, 0.f);
  p.top_depth_m = rng.uniform(1.5f, 3.f);
  return p;
}

void floor_and_room(Scene& s, Rng& rng, const V2& lo, const V2& hi, float floor_z, float wall_bottom) {
  s.add_box_world(V3(lo.x() - 1.f, lo.y() - 1.f, floor_z - 0.2f), V3(hi.x() + 1.f, hi.y() + 1.f, floor_z),
                  floor_material(rng), "floor");
  add_room_walls(s, lo, hi, wall_bottom, 2.7f - wall_bottom + floor_z, wall_material(rng));
}

// Staircase 0.8-3.0 m ahead of the user at the origin, travel direction `yaw`.
Pose stair_ahead(Rng& rng, float yaw, float edge_z, float* dist) {
  const float d = rng.uniform(0.8f, 3.0f);
  const float lat = rng.uniform(-0.3f, 0.3f);
  if (dist) *dist = d;
  const V3 fwd(std::cos(yaw), std::sin(yaw), 0.f), left(-std::sin(yaw), std::cos(yaw), 0.f);
  const V3 p = d * fwd + lat * left;
  return stair_pose(p.x(), p.y(), yaw, edge_z);
}

void add_door_somewhere(Scene& s, Rng& rng, float wall_y, float x0, float x1, bool facing_minus_y) {
  const float x = rng.uniform(x0, x1);
  add_door(s, V3(x, wall_y, 0.f), facing_minus_y ? -1.5707963f : 1.5707963f, rng);
}

// ---- static presets with stairs ----

void ascending_static(Rng& rng, const SynthOptions& o, PresetBuild& b, int min_steps = 4,
                      int max_steps = 12) {
  StairParams p = random_stair(rng, StairKind::kAscending);
  p.steps = rng.integer(min_steps, max_steps);
  float d = 0.f;
  p.T_world_stair = stair_ahead(rng, 0.f, p.riser_m, &d);
  p.side_walls = true;
  p.handrails = rng.chance(0.4f);
  const float end = d + static_cast<float>(p.steps - 1) * p.tread_m + p.top_depth_m;
  const float half = 0.5f * p.width_m + rng.uniform(0.2f, 2.5f);
  floor_and_room(b.scene, rng, V2(-3.f, -half - 0.5f), V2(end + 0.2f, half + 0.5f));
  add_staircase(b.scene, p, rng);
  if (rng.chance(0.5f)) add_door_somewhere(b.scene, rng, half + 0.5f, -2.f, d - 0.8f, true);
  b.view = random_view(rng, o);
}

// A descending flight ahead in a room of walls down to its foot (descending_static and the
// world's descending flight: they differ in how the flight's dimensions are drawn).
void descending_in_room(Rng& rng, const SynthOptions& o, PresetBuild& b, StairParams p) {
  float d = 0.f;
  p.T_world_stair = stair_ahead(rng, 0.f, 0.f, &d);
  p.side_walls = rng.chance(0.7f);
  p.handrails = !p.side_walls || rng.chance(0.3f);
  const float total = static_cast<float>(p.steps) * p.riser_m;
  add_staircase(b.scene, p, rng);
  add_room_walls(b.scene, V2(-3.f, -4.f), V2(d + static_cast<float>(p.steps) * p.tread_m + 5.f, 4.f),
                 -total - 0.2f, 2.7f + total + 0.2f, wall_material(rng));
  b.view = random_view(rng, o);
}

void descending_static(Rng& rng, const SynthOptions& o, PresetBuild& b) {
  descending_in_room(rng, o, b, random_stair(rng, StairKind::kDescending));
}

void open_risers_static(Rng& rng, const SynthOptions& o, PresetBuild& b) {
  StairParams p = random_stair(rng, StairKind::kAscending);
  float d = 0.f;
  p.T_world_stair = stair_ahead(rng, 0.f, p.riser_m, &d);
  p.open_risers = true;
  p.side_walls = false;
  p.handrails = rng.chance(0.5f);
  const float end = d + static_cast<float>(p.steps - 1) * p.tread_m + p.top_depth_m;
  floor_and_room(b.scene, rng, V2(-3.f, -3.5f), V2(end + 1.5f, 3.5f));
  add_staircase(b.scene, p, rng);
  b.view = random_view(rng, o);
}

void nosing_landing_static(Rng& rng, const SynthOptions& o, PresetBuild& b) {
  StairParams p = random_stair(rng, StairKind::kAscending);
  p.steps = rng.integer(3, 6);
  p.nosing_m = rng.uniform(0.02f, 0.04f);
  p.top_depth_m = rng.uniform(1.0f, 1.5f);  // the landing
  float d = 0.f;
  p.T_world_stair = stair_ahead(rng, 0.f, p.riser_m, &d);
  p.side_walls = true;
  const float landing_z = static_cast<float>(p.steps) * p.riser_m;
  const float flight2_x = d + static_cast<float>(p.steps - 1) * p.tread_m + p.top_depth_m;
  StairParams q = p;
  q.steps = rng.integer(3, 6);
  q.base_z = landing_z;
  q.wall_start_m = 0.f;
  q.top_depth_m = 2.f;
  q.T_world_stair = p.T_world_stair;
  q.T_world_stair.translation() = p.T_world_stair * V3(0.f, landing_z - p.riser_m + q.riser_m, flight2_x - d);
  const float end = flight2_x + static_cast<float>(q.steps - 1) * q.tread_m + q.top_depth_m;
  floor_and_room(b.scene, rng, V2(-3.f, -0.5f * p.width_m - 1.5f), V2(end + 0.2f, 0.5f * p.width_m + 1.5f));
  add_staircase(b.scene, p, rng);
  add_staircase(b.scene, q, rng);
  b.view = random_view(rng, o);
}

void rotated_static(Rng& rng, const SynthOptions& o, PresetBuild& b) {
  StairParams p = random_stair(rng, StairKind::kAscending);
  const float rot = deg2rad(rng.uniform(15.f, 35.f)) * (rng.chance(0.5f) ? 1.f : -1.f);
  float d = 0.f;
  p.T_world_stair = stair_ahead(rng, rot, p.riser_m, &d);
  p.side_walls = false;
  p.handrails = rng.chance(0.5f);
  const float end = d + static_cast<float>(p.steps) * p.tread_m + p.top_depth_m;
  // Room walls stay aligned with the world axes (and the floor tiles), the staircase does not.
  floor_and_room(b.scene, rng, V2(-3.f, -end - 1.f), V2(end + 1.5f, end + 1.f));
  add_staircase(b.scene, p, rng);
  add_crate(b.scene, V3(d * 0.6f, -1.8f, 0.f), 0.f, V3(0.5f, 0.4f, 0.6f), wood_material(rng), "box");
  b.view = random_view(rng, o, rot);
}

void people_static(Rng& rng, const SynthOptions& o, PresetBuild& b) {
  const bool down = rng.chance(0.5f);
  if (down) {
    descending_static(rng, o, b);
  } else {
    ascending_static(rng, o, b);
  }
  const StairSpec& st = b.scene.stairs[0];
  const int people = rng.integer(1, 2);
  for (int i = 0; i < people; ++i) {
    const int k = rng.integer(1, std::max(1, st.steps - 1));
    const float x = rng.uniform(-0.3f, 0.3f) * st.width_m;
    const float z = (static_cast<float>(k) - 0.5f) * st.tread_m;
    const V3 feet = st.T_world_stair * V3(x, st.tread_height(k) - st.T_world_stair.translation().z(), z);
    const float yaw = std::atan2(st.T_world_stair.linear()(1, 2), st.T_world_stair.linear()(0, 2)) +
                      (rng.chance(0.5f) ? 3.14159265f : 0.f) + rng.uniform(-0.4f, 0.4f);
    add_person(b.scene, feet, yaw, rng.uniform(1.55f, 1.9f), rng);
  }
}

void handrails_open_sides_static(Rng& rng, const SynthOptions& o, PresetBuild& b) {
  StairParams p = random_stair(rng, StairKind::kAscending);
  p.width_m = rng.uniform(1.8f, 2.6f);
  float d = 0.f;
  p.T_world_stair = stair_ahead(rng, 0.f, p.riser_m, &d);
  p.side_walls = false;
  p.handrails = true;
  const float end = d + static_cast<float>(p.steps - 1) * p.tread_m + p.top_depth_m;
  floor_and_room(b.scene, rng, V2(-3.f, -4.f), V2(end + 1.5f, 4.f));
  add_staircase(b.scene, p, rng);
  b.view = random_view(rng, o);
}

void single_step_static(Rng& rng, const SynthOptions& o, PresetBuild& b) {
  StairParams p;
  p.kind = StairKind::kSingleStep;
  p.riser_m = rng.uniform(0.15f, 0.18f);
  p.tread_m = rng.uniform(1.2f, 2.5f);
  p.width_m = rng.uniform(1.0f, 3.0f);
  p.T_world_stair = stair_ahead(rng, 0.f, p.riser_m);
  floor_and_room(b.scene, rng, V2(-3.f, -4.f), V2(7.f, 4.f));
  add_staircase(b.scene, p, rng);
  b.view = random_view(rng, o);
}

void curb_static(Rng& rng, const SynthOptions& o, PresetBuild& b) {
  StairParams p;
  p.kind = StairKind::kCurb;
  p.down = rng.chance(0.5f);
  p.riser_m = rng.uniform(0.12f, 0.18f);
  p.tread_m = rng.uniform(4.f, 6.f);
  p.width_m = rng.uniform(8.f, 12.f);
  p.T_world_stair = stair_ahead(rng, 0.f, p.down ? 0.f : p.riser_m);
  if (!p.down)
    b.scene.add_box_world(V3(-8.f, -8.f, -0.3f), V3(12.f, 8.f, 0.f), concrete_material(rng), "floor");
  add_staircase(b.scene, p, rng);
  // Outdoors: a building facade far behind and a couple of bollards beside the curb.
  const float fz = p.down ? -p.riser_m - 0.3f : 0.f;
  b.scene.add_box_world(V3(-3.5f, -6.f, fz), V3(-3.2f, 6.f, 4.f), wall_material(rng), "facade");
  for (int i = 0; i < 2; ++i)
    if (rng.chance(0.6f)) {
      const V3 base(rng.uniform(0.3f, 1.5f), rng.uniform(1.2f, 2.5f) * (i ? 1.f : -1.f), 0.f);
      b.scene.add_cylinder(base, base + V3(0.f, 0.f, 0.9f), 0.06f, 0.06f, metal_material(rng), "bollard", 10);
    }
  b.view = random_view(rng, o);
}

// ---- static presets without stairs (distractors) ----

void room(Rng& rng, PresetBuild& b) { floor_and_room(b.scene, rng, V2(-3.f, -3.5f), V2(6.f, 3.5f)); }

V3 ahead(Rng& rng, float dmin = 0.9f, float dmax = 2.6f) {
  return V3(rng.uniform(dmin, dmax), rng.uniform(-0.4f, 0.4f), 0.f);
}

void table_static(Rng& rng, const SynthOptions& o, PresetBuild& b) {
  room(rng, b);
  const V3 c = ahead(rng, 1.2f, 2.6f);
  const float yaw = rng.uniform(-0.3f, 0.3f);
  add_table(b.scene, c, yaw, rng.uniform(0.70f, 0.80f), rng.uniform(1.0f, 1.6f), rng.uniform(0.7f, 0.9f),
            rng);
  for (int i = 0, n = rng.integer(1, 3); i < n; ++i)
    add_chair(b.scene, c + V3(rng.uniform(-0.5f, 0.5f), (i % 2 ? 1.f : -1.f) * 0.65f, 0.f),
              (i % 2 ? -1.5707963f : 1.5707963f) + rng.uniform(-0.3f, 0.3f), rng);
  b.view = random_view(rng, o);
}

void bench_static(Rng& rng, const SynthOptions& o, PresetBuild& b) {
  room(rng, b);
  add_bench(b.scene, ahead(rng), rng.uniform(-0.5f, 0.5f) + 1.5707963f, rng.uniform(0.40f, 0.50f),
            rng.uniform(1.2f, 2.0f), rng);
  b.view = random_view(rng, o);
}

void shelves_static(Rng& rng, const SynthOptions& o, PresetBuild& b) {
  room(rng, b);
  std::vector<float> boards;
  float h = rng.uniform(0.05f, 0.2f);
  while (h < 1.6f) {
    boards.push_back(h);
    h += rng.uniform(0.15f, 0.40f);
  }
  const V3 c = ahead(rng, 1.0f, 2.4f);
  add_shelves(b.scene, c, 3.14159265f + rng.uniform(-0.3f, 0.3f), rng.uniform(0.8f, 1.4f),
              rng.uniform(0.3f, 0.45f), boards, rng);
  b.view = random_view(rng, o);
}

void low_platform_static(Rng& rng, const SynthOptions& o, PresetBuild& b) {
  room(rng, b);
  const V3 size(rng.uniform(0.3f, 0.6f), rng.uniform(0.3f, 0.6f), rng.uniform(0.15f, 0.18f));
  add_crate(b.scene, ahead(rng), rng.uniform(-0.8f, 0.8f), size,
            rng.chance(0.5f) ? wood_material(rng) : concrete_material(rng), "low_platform");
  b.view = random_view(rng, o);
}

void sofa_static(Rng& rng, const SynthOptions& o, PresetBuild& b) {
  room(rng, b);
  const V3 c = ahead(rng, 1.8f, 2.8f);
  add_sofa(b.scene, c, 3.14159265f + rng.uniform(-0.3f, 0.3f), rng.uniform(0.42f, 0.48f), rng);
  add_table(b.scene, c - V3(rng.uniform(0.8f, 1.0f), 0.f, 0.f), 0.f, rng.uniform(0.38f, 0.45f),
            rng.uniform(0.8f, 1.1f), rng.uniform(0.5f, 0.6f), rng);
  b.view = random_view(rng, o);
}

void corridor_static(Rng& rng, const SynthOptions& o, PresetBuild& b) {
  const float hw = rng.uniform(0.9f, 1.3f);
  floor_and_room(b.scene, rng, V2(-2.f, -hw), V2(rng.uniform(8.f, 14.f), hw));
  for (float x = rng.uniform(0.f, 2.f); x < 10.f; x += rng.uniform(2.f, 4.f)) {
    const bool plus_side = rng.chance(0.5f);
    add_door_somewhere(b.scene, rng, plus_side ? hw : -hw, x, x + 0.1f, plus_side);
  }
  for (int i = 0, n = rng.integer(1, 3); i < n; ++i) {
    const float side = rng.chance(0.5f) ? 1.f : -1.f;
    const V3 size(rng.uniform(0.3f, 0.6f), rng.uniform(0.3f, 0.5f), rng.uniform(0.2f, 0.8f));
    add_crate(b.scene, V3(rng.uniform(0.8f, 6.f), side * (hw - 0.5f * size.y() - 0.02f), 0.f), 0.f, size,
              i % 2 ? wood_material(rng) : fabric_material(rng), "clutter");
  }
  if (rng.chance(0.4f)) {
    const V3 base(rng.uniform(1.f, 5.f), -hw + 0.2f, 0.f);
    b.scene.add_cylinder(base, base + V3(0.f, 0.f, 0.6f), 0.15f, 0.15f, metal_material(rng), "bin", 12);
  }
  b.view = random_view(rng, o, 0.f, 15.f);
}

void room_clutter_static(Rng& rng, const SynthOptions& o, PresetBuild& b) {
  room(rng, b);
  for (int i = 0, n = rng.integer(2, 5); i < n; ++i) {
    const V3 size(rng.uniform(0.25f, 0.7f), rng.uniform(0.25f, 0.7f), rng.uniform(0.2f, 0.9f));
    add_crate(b.scene, V3(rng.uniform(0.8f, 4.f), rng.uniform(-2.5f, 2.5f), 0.f), rng.uniform(-0.8f, 0.8f),
              size, rng.chance(0.5f) ? wood_material(rng) : fabric_material(rng), "clutter");
  }
  add_person(b.scene, V3(rng.uniform(1.2f, 3.5f), rng.uniform(-1.f, 1.f), 0.f), rng.uniform(-3.1f, 3.1f),
             rng.uniform(1.55f, 1.9f), rng);
  if (rng.chance(0.5f))
    add_chair(b.scene, V3(rng.uniform(1.f, 3.f), rng.uniform(-2.f, 2.f), 0.f), rng.uniform(-3.f, 3.f), rng);
  if (rng.chance(0.5f))
    add_table(b.scene, V3(rng.uniform(2.f, 4.f), rng.uniform(-2.f, 2.f), 0.f), rng.uniform(-0.5f, 0.5f),
              0.75f, 1.2f, 0.8f, rng);
  b.view = random_view(rng, o);
}

void floor_only_static(Rng& rng, const SynthOptions& o, PresetBuild& b) {
  room(rng, b);
  b.view = random_view(rng, o);
}

// ---- sequences ----

// Walk geometry along +x through a staircase whose first edge is at x = edge_x.
void stair_walk(WalkSpec& w, const StairSpec& st, float edge_x) {
  const float r = st.riser_m, t = st.tread_m, sign = st.down ? -1.f : 1.f;
  const int N = st.steps;
  w.support_step = [=](float s) {
    const float z = s - edge_x;
    if (z < 0.f) return 0.f;
    const int k = std::min(N, static_cast<int>(std::floor(z / t)) + 1);
    return sign * r * static_cast<float>(k);
  };
  // The chest follows the stair slope: it starts rising (or sinking) half a tread before the edge.
  w.support_smooth = [=](float s) {
    const float z = s - edge_x;
    return sign * r * std::clamp((z + 0.5f * t) / t, 0.f, static_cast<float>(N));
  };
  w.stride_length = [=](float s) {
    const float z = s - edge_x;
    return (z > -0.3f && z < static_cast<float>(N - 1) * t + 0.3f) ? t : 0.55f;
  };
}

// Distance profile: stand, approach to `stop`, pause, cross the staircase at one tread per
// `step_s`, walk `after` m further, stand.
std::function<float(double)> approach_and_cross(float stop, float cross_to, float after, double t_walk0,
                                                double t_walk1, double pause, double step_s, int steps) {
  const double t_cross0 = t_walk1 + pause;
  const double t_cross1 = t_cross0 + step_s * steps;
  const double t_after1 = t_cross1 + 2.0;
  return [=](double t) -> float {
    if (t < t_walk1)
      return stop *
             smooth_ramp(static_cast<float>(t), static_cast<float>(t_walk0), static_cast<float>(t_walk1));
    if (t < t_cross0) return stop;
    if (t < t_cross1)
      return stop + (cross_to - stop) * static_cast<float>((t - t_cross0) / (t_cross1 - t_cross0));
    return cross_to + after * smooth_ramp(static_cast<float>(t), static_cast<float>(t_cross1),
                                          static_cast<float>(t_after1));
  };
}

WalkSpec& start_walk(Rng& rng, const SynthOptions& o, PresetBuild& b) {
  b.sequence = true;
  WalkSpec& w = b.walk;
  w.camera_height_m = pick(o.camera_height_m, rng.uniform(1.2f, 1.45f));
  w.tilt_rad = deg2rad(pick(o.camera_tilt_deg, rng.uniform(40.f, 50.f)));
  w.roll_rad = deg2rad(pick(o.camera_roll_deg, rng.uniform(-2.f, 2.f)));
  return w;
}

// The demonstration walks' flight: 8 steps, risers 16-17.5 cm, treads 28-31 cm, 1.1-1.4 m wide,
// side walls and handrails.
StairParams walk_flight(Rng& rng, StairKind kind) {
  StairParams p;
  p.kind = kind;
  p.steps = 8;
  p.riser_m = rng.uniform(0.16f, 0.175f);
  p.tread_m = rng.uniform(0.28f, 0.31f);
  p.width_m = rng.uniform(1.1f, 1.4f);
  p.side_walls = true;
  p.handrails = true;
  return p;
}

void ascending_approach_climb(Rng& rng, const SynthOptions& o, PresetBuild& b) {
  StairParams p = walk_flight(rng, StairKind::kAscending);
  p.wall_start_m = -0.8f;
  p.top_depth_m = 3.f;
  const float edge_x = 3.3f;
  p.T_world_stair = stair_pose(edge_x, 0.f, 0.f, p.riser_m);
  const float end = edge_x + 7.f * p.tread_m + p.top_depth_m;
  floor_and_room(b.scene, rng, V2(-2.f, -2.2f), V2(end + 0.1f, 2.2f));
  add_door_somewhere(b.scene, rng, 2.2f, -1.5f, 1.5f, true);
  add_crate(b.scene, V3(1.5f, -1.7f, 0.f), 0.2f, V3(0.5f, 0.4f, 0.45f), wood_material(rng), "clutter");
  add_staircase(b.scene, p, rng);
  WalkSpec& w = start_walk(rng, o, b);
  w.duration_s = 20.f;
  const StairSpec& st = b.scene.stairs[0];
  stair_walk(w, st, edge_x);
  const float stop = edge_x - 0.35f, top = edge_x + 7.f * p.tread_m + 0.35f;
  w.distance = approach_and_cross(stop, top, 1.0f, 0.5, 5.5, 0.8, 0.75, 8);
  w.heading = [](double t) { return deg2rad(3.f) * static_cast<float>(std::sin(0.6 * t)); };
}

void descending_approach_descend(Rng& rng, const SynthOptions& o, PresetBuild& b) {
  StairParams p = walk_flight(rng, StairKind::kDescending);
  const float edge_x = 3.3f;
  p.T_world_stair = stair_pose(edge_x, 0.f, 0.f, 0.f);
  const float total = 8.f * p.riser_m;
  add_staircase(b.scene, p, rng);
  add_room_walls(b.scene, V2(-2.f, -2.5f), V2(edge_x + 7.f * p.tread_m + 6.f, 2.5f), -total - 0.2f,
                 2.9f + total, wall_material(rng));
  add_crate(b.scene, V3(1.2f, 1.9f, 0.f), 0.1f, V3(0.5f, 0.4f, 0.45f), wood_material(rng), "clutter");
  WalkSpec& w = start_walk(rng, o, b);
  w.duration_s = 20.f;
  stair_walk(w, b.scene.stairs[0], edge_x);
  const float stop = edge_x - 0.25f, bottom = edge_x + 7.f * p.tread_m + 0.35f;
  w.distance = approach_and_cross(stop, bottom, 1.5f, 0.5, 5.5, 1.0, 0.8, 8);
  w.heading = [](double t) { return deg2rad(3.f) * static_cast<float>(std::sin(0.5 * t + 1.0)); };
}

void ascending_turn_fast(Rng& rng, const SynthOptions& o, PresetBuild& b) {
  StairParams p = random_stair(rng, StairKind::kAscending);
  p.steps = 8;
  p.width_m = rng.uniform(1.1f, 1.5f);
  p.side_walls = true;
  const float edge_x = 4.0f;
  p.T_world_stair = stair_pose(edge_x, 0.f, 0.f, p.riser_m);
  const float end = edge_x + 7.f * p.tread_m + p.top_depth_m;
  floor_and_room(b.scene, rng, V2(-2.5f, -3.f), V2(end + 0.1f, 3.f));
  add_door_somewhere(b.scene, rng, 3.f, -1.5f, 2.5f, true);
  add_table(b.scene, V3(1.0f, 2.2f, 0.f), 0.f, 0.75f, 1.2f, 0.7f, rng);
  add_crate(b.scene, V3(2.5f, -2.4f, 0.f), 0.3f, V3(0.6f, 0.5f, 0.5f), wood_material(rng), "clutter");
  add_staircase(b.scene, p, rng);
  WalkSpec& w = start_walk(rng, o, b);
  w.duration_s = 10.f;
  stair_walk(w, b.scene.stairs[0], edge_x);
  const float stop = edge_x - 0.4f;
  w.distance = [=](double t) { return stop * smooth_ramp(static_cast<float>(t), 1.5f, 8.0f); };
  // Facing 80 deg left, a fast turn to the stairs (160 deg/s), a glance right and back.
  w.heading = [](double t) {
    const float tt = static_cast<float>(t);
    return deg2rad(80.f) * (1.f - smooth_ramp(tt, 1.0f, 1.5f)) - deg2rad(45.f) * smooth_ramp(tt, 4.0f, 4.4f) +
           deg2rad(45.f) * smooth_ramp(tt, 4.8f, 5.2f);
  };
}

void descending_people_approach(Rng& rng, const SynthOptions& o, PresetBuild& b) {
  StairParams p = random_stair(rng, StairKind::kDescending);
  p.steps = rng.integer(8, 10);
  p.width_m = rng.uniform(1.2f, 1.6f);
  p.side_walls = true;
  p.handrails = true;
  const float edge_x = 3.8f;
  p.T_world_stair = stair_pose(edge_x, 0.f, 0.f, 0.f);
  const float total = static_cast<float>(p.steps) * p.riser_m;
  const int id = add_staircase(b.scene, p, rng);
  add_room_walls(b.scene, V2(-2.f, -2.5f), V2(edge_x + static_cast<float>(p.steps) * p.tread_m + 6.f, 2.5f),
                 -total - 0.2f, 2.9f + total, wall_material(rng));
  const StairSpec& st = b.scene.stairs[static_cast<std::size_t>(id)];
  const int k = rng.integer(3, 5);
  const V3 feet(edge_x + (static_cast<float>(k) - 0.5f) * st.tread_m, rng.uniform(-0.2f, 0.2f) * st.width_m,
                st.tread_height(k));
  add_person(b.scene, feet, 3.14159265f + rng.uniform(-0.3f, 0.3f), rng.uniform(1.6f, 1.85f), rng);
  WalkSpec& w = start_walk(rng, o, b);
  w.duration_s = 10.f;
  stair_walk(w, st, edge_x);
  const float stop = edge_x - 0.3f;
  w.distance = [=](double t) { return stop * smooth_ramp(static_cast<float>(t), 0.5f, 7.5f); };
  w.heading = [](double t) { return deg2rad(4.f) * static_cast<float>(std::sin(0.7 * t)); };
}

}  // namespace presets

using namespace presets;

const std::vector<PresetDef>& preset_defs() {
  static const std::vector<PresetDef> defs = {
      def("ascending_approach_climb",
          "walk ~3 m toward an 8-step ascending staircase between side walls and climb it", 600, true,
          ascending_approach_climb),
      def("descending_approach_descend",
          "walk toward a descending staircase (floor ends at its top) and go down it", 600, true,
          descending_approach_descend),
      def("ascending_static", "random views of an ascending staircase with side walls", 1, false,
          [](Rng& r, const SynthOptions& o, PresetBuild& b) { ascending_static(r, o, b); }),
      def("descending_static", "random views of a descending staircase", 1, false, descending_static),
      def("open_risers_static", "ascending staircase without risers (open stairs), open sides", 1, false,
          open_risers_static),
      def("nosing_landing_static",
          "ascending stairs with nosings and a landing after N steps, then a second flight", 1, false,
          nosing_landing_static),
      def("rotated_static", "staircase rotated 15-35 deg against the room walls (non-Manhattan)", 1, false,
          rotated_static),
      def("people_static", "ascending or descending staircase with 1-2 people standing on it (occluders)", 1,
          false, people_static),
      def("handrails_open_sides_static", "wide staircase, open sides, handrails", 1, false,
          handrails_open_sides_static),
      def("single_step_static", "one isolated step up (platform 15-18 cm high, >= 1.2 m deep)", 1, false,
          single_step_static),
      def("curb_static", "a curb: the ground steps down (or up) 12-18 cm to a large other level", 1, false,
          curb_static),
      def("table_static", "a table (70-80 cm) and chairs, no stairs", 1, false, table_static),
      def("bench_static", "a bench 40-50 cm high, no stairs", 1, false, bench_static),
      def("shelves_static", "open shelves with horizontal boards at 15-40 cm spacing, no stairs", 1, false,
          shelves_static),
      def("low_platform_static", "a small low platform/box at step height, too small to be a step (obstacle)",
          1, false, low_platform_static),
      def("sofa_static", "a sofa (seat ~45 cm) and a coffee table, no stairs", 1, false, sofa_static),
      def("corridor_static", "corridor with walls, doors and clutter, no stairs", 1, false, corridor_static),
      def("room_clutter_static", "room with boxes, a person, furniture, no stairs", 1, false,
          room_clutter_static),
      def("ascending_turn_fast",
          "walking toward stairs with a fast turn (large inter-frame motion for odometry)", 300, true,
          ascending_turn_fast),
      def("descending_people_approach", "approach a descending staircase with a person on it", 300, true,
          descending_people_approach),
      def("ascending_short_static", "random views of a short ascending flight (2-3 steps) with side walls", 1,
          false, [](Rng& r, const SynthOptions& o, PresetBuild& b) { ascending_static(r, o, b, 2, 3); }),
      def("floor_only_static", "an empty room: floor and walls only (negative control)", 1, false,
          floor_only_static),
  };
  return defs;
}

PresetDef def(const char* name, const char* summary, long frames, bool sequence,
              std::function<void(Rng& rng, const SynthOptions& o, PresetBuild& out)> build) {
  PresetDef d;
  d.info.name = name;
  d.info.summary = summary;
  d.info.default_frames = frames;
  d.sequence = sequence;
  d.build = std::move(build);
  return d;
}

const PresetDef* find_preset(const std::string& name) {
  for (const auto& d : preset_defs())
    if (d.info.name == name) return &d;
  for (const auto& d : world_preset_defs())
    if (d.info.name == name) return &d;
  for (const auto& d : walk_defs())
    if (d.info.name == name) return &d;
  for (const auto& d : rig_defs())
    if (d.info.name == name) return &d;
  for (const auto& d : world2_defs())
    if (d.info.name == name) return &d;
  for (const auto& d : drop_defs())
    if (d.info.name == name) return &d;
  return nullptr;
}

std::uint64_t name_hash(const std::string& s) {
  std::uint64_t h = 1469598103934665603ull;  // FNV-1a
  for (unsigned char c : s) h = (h ^ c) * 1099511628211ull;
  return h;
}

}  // namespace stairguide::synth::detail
