// Drop-offs (issue 42 item 4, synth::drop_presets()): the floor the wearer stands on ends at an
// edge with nothing within a step below it: a railway platform's edge, a loading dock, a hole
// (an open pit or trapdoor), a sunken floor. Every range is the built world's, never the
// detector's: platform heights 0.55-1.3 m (low tram stops to high railway platforms), dock
// heights 0.9-1.4 m (truck beds), holes and pits 0.3-1.5 m deep and 0.6-2.5 m across, sunken
// floors 0.3-0.8 m (conversation pits, a lowered room without steps). The edge lies 0.5-4 m from
// the point under the camera, turned +-30 deg; the chest rig is the other presets' (1.0-1.6 m,
// 30-60 deg, +-3 deg roll, heading +-25 deg). Each scene labels its edges (Scene::drops); the
// truth (drop_truth) reads which of them the camera sees off the ideal render. These presets draw
// only from their own streams: no other preset's frames move.
#include <algorithm>
#include <cmath>
#include <limits>

#include "internal.hpp"

namespace stairguide::synth::detail {
namespace {

using V3 = Eigen::Vector3f;
constexpr float kPi = 3.14159265f;

float pick(float v, float fallback) { return std::isnan(v) ? fallback : v; }

// The wearer at the world origin facing `yaw`, a chest camera 0.12 m ahead of the body.
WalkerState chest_view(Rng& rng, const SynthOptions& o, float yaw) {
  const float h = pick(o.camera_height_m, rng.uniform(1.0f, 1.6f));
  const float tilt = deg2rad(pick(o.camera_tilt_deg, rng.uniform(30.f, 60.f)));
  const float roll = deg2rad(pick(o.camera_roll_deg, rng.uniform(-3.f, 3.f)));
  WalkerState st;
  st.yaw = yaw;
  const V3 cam = 0.12f * V3(std::cos(yaw), std::sin(yaw), 0.f) + V3(0.f, 0.f, h);
  st.T_world_camera = camera_pose(cam, yaw, tilt, roll);
  return st;
}

// The edge frame E: x_E towards the drop (horizontal), y_E along the edge, z up; origin on the
// edge at floor height.
Pose edge_frame(const V3& origin, float psi) {
  Pose T = Pose::Identity();
  T.linear() = Eigen::AngleAxisf(psi, V3::UnitZ()).toRotationMatrix();
  T.translation() = origin;
  return T;
}

// The edge a-b (in E) labelled: the lower level `depth` below, on the side `down_in_e` points to.
void label_edge(Scene& s, const Pose& E, const V3& a, const V3& b, const V3& down_in_e, float depth) {
  DropEdge d;
  d.a = E * a;
  d.b = E * b;
  d.down_dir = E.linear() * down_in_e;
  d.depth_m = depth;
  s.drops.push_back(d);
}

// The view and an edge frame whose edge line lies D m (0.5-4) from the point under the camera,
// its normal turned +-30 deg from the heading drawn.
Pose view_and_edge(Rng& rng, const SynthOptions& o, PresetBuild& b) {
  const float yaw = deg2rad(rng.uniform(-25.f, 25.f));
  b.view = chest_view(rng, o, yaw);
  const float psi = yaw + deg2rad(rng.uniform(-30.f, 30.f));
  const float D = rng.uniform(0.5f, 4.0f);
  const V3 foot = 0.12f * V3(std::cos(yaw), std::sin(yaw), 0.f);
  return edge_frame(foot + D * V3(std::cos(psi), std::sin(psi), 0.f), psi);
}

// Things standing on the floor before the edge, off the wearer's line (benches, bins, crates, a
// person): what a platform or a dock has about.
void clutter_before(Scene& s, Rng& rng, const Pose& E, float reach) {
  for (int i = 0, n = rng.integer(1, 4); i < n; ++i) {
    const float side = rng.chance(0.5f) ? 1.f : -1.f;
    const V3 c = E * V3(-rng.uniform(0.6f, reach), side * rng.uniform(1.0f, 3.5f), 0.f);
    const int k = rng.integer(0, 3);
    if (k == 0)
      add_person(s, c, rng.uniform(-kPi, kPi), rng.uniform(1.55f, 1.9f), rng);
    else if (k == 1)
      add_bench(s, c, rng.uniform(-kPi, kPi), rng.uniform(0.4f, 0.5f), rng.uniform(1.0f, 2.0f), rng);
    else
      add_crate(s, c, rng.uniform(-kPi, kPi),
                V3(rng.uniform(0.3f, 0.8f), rng.uniform(0.3f, 0.8f), rng.uniform(0.3f, 1.1f)),
                rng.chance(0.5f) ? wood_material(rng) : metal_material(rng), "clutter");
  }
}

// The upper floor (x_E < 0) standing `depth` above a lower ground (x_E > 0, `lower_far` m
// deep), both `half` m either side of the origin along the edge; the edge labelled.
void two_levels(Scene& s, const Pose& E, float depth, float half, float lower_far, const Material& top,
                const Material& low) {
  s.add_box_in(E, V3(-14.f, -half, -depth - 0.3f), V3(0.f, half, 0.f), top, "floor");
  s.add_box_in(E, V3(0.f, -half, -depth - 0.3f), V3(lower_far, half, -depth), low, "lower_floor");
  label_edge(s, E, V3(0.f, -half, 0.f), V3(0.f, half, 0.f), V3::UnitX(), depth);
}

// A railway or tram platform: the track bed 0.55-1.3 m below, two rails, the opposite platform
// 4-7 m across with a wall behind it (or a fence), people, benches and bins on the platform.
void platform_static(Rng& rng, const SynthOptions& o, PresetBuild& b) {
  const Pose E = view_and_edge(rng, o, b);
  const float H = rng.uniform(0.55f, 1.3f), gap = rng.uniform(4.f, 7.f);
  Material bed = concrete_material(rng);
  bed.albedo *= rng.uniform(0.5f, 0.9f);  // ballast and sleepers: darker than the platform
  two_levels(b.scene, E, H, 30.f, gap, concrete_material(rng), bed);
  const float r0 = rng.uniform(1.0f, 1.6f);
  for (float x : {r0, r0 + 1.435f})  // standard gauge
    b.scene.add_box_in(E, V3(x - 0.035f, -30.f, -H), V3(x + 0.035f, 30.f, -H + 0.15f), metal_material(rng),
                       "rail");
  b.scene.add_box_in(E, V3(gap, -30.f, -H - 0.3f), V3(gap + 5.f, 30.f, 0.f), concrete_material(rng),
                     "platform");
  b.scene.add_box_in(E, V3(gap + 4.f, -30.f, 0.f), V3(gap + 4.3f, 30.f, 3.f), wall_material(rng), "wall");
  b.scene.add_box_in(E, V3(-10.f, -30.f, 0.f), V3(-9.7f, 30.f, 3.f), wall_material(rng), "wall");
  clutter_before(b.scene, rng, E, 4.f);
}

// A loading dock: the yard 0.9-1.4 m below (asphalt or concrete), rubber bumpers on the dock's
// face, a trailer parked across the yard on some, pallets and crates on the dock.
void dock_static(Rng& rng, const SynthOptions& o, PresetBuild& b) {
  const Pose E = view_and_edge(rng, o, b);
  const float H = rng.uniform(0.9f, 1.4f);
  Material yard = concrete_material(rng);
  yard.albedo *= rng.uniform(0.35f, 0.8f);
  two_levels(b.scene, E, H, 20.f, 25.f, concrete_material(rng), yard);
  Material rubber = fabric_material(rng);
  rubber.albedo = V3(0.08f, 0.08f, 0.08f);
  for (float y = rng.uniform(-4.f, -2.f); y < 4.f; y += rng.uniform(2.5f, 3.5f))
    b.scene.add_box_in(E, V3(0.f, y - 0.12f, -0.45f), V3(0.1f, y + 0.12f, -0.05f), rubber, "bumper");
  if (rng.chance(0.4f)) {  // a trailer across the yard, its bed at about the dock's height
    const float x = rng.uniform(6.f, 10.f);
    b.scene.add_box_in(E, V3(x, -6.f, 0.f), V3(x + 2.5f, 6.f, 2.6f), metal_material(rng), "trailer");
  }
  b.scene.add_box_in(E, V3(-8.f, -20.f, 0.f), V3(-7.7f, 20.f, 4.f), wall_material(rng), "wall");
  for (int i = 0, n = rng.integer(0, 3); i < n; ++i) {  // pallets, 12-15 cm
    const V3 c = E * V3(-rng.uniform(0.8f, 5.f), rng.uniform(-4.f, 4.f), 0.f);
    add_crate(b.scene, c, rng.uniform(-kPi, kPi), V3(1.2f, 0.8f, rng.uniform(0.12f, 0.15f)),
              wood_material(rng), "pallet");
  }
  clutter_before(b.scene, rng, E, 5.f);
}

// A hole in the floor: an open service pit, a trapdoor or a manhole left open, 0.6-2.5 m across
// and 0.3-1.5 m deep, its near edge 0.5-4 m away, in a room or a workshop; its four edges
// labelled (the far one and the sides are drops only seen from beyond or beside them).
void hole_static(Rng& rng, const SynthOptions& o, PresetBuild& b) {
  const Pose E = view_and_edge(rng, o, b);
  const float depth = rng.uniform(0.3f, 1.5f), S = rng.uniform(0.6f, 2.5f), w = rng.uniform(0.6f, 2.5f);
  const float c = rng.uniform(-0.6f, 0.6f), y0 = c - 0.5f * w, y1 = c + 0.5f * w, lo = -depth - 0.3f;
  const Material fl = rng.chance(0.5f) ? floor_material(rng) : concrete_material(rng);
  b.scene.add_box_in(E, V3(-14.f, -20.f, lo), V3(0.f, 20.f, 0.f), fl, "floor");
  b.scene.add_box_in(E, V3(S, -20.f, lo), V3(20.f, 20.f, 0.f), fl, "floor");
  b.scene.add_box_in(E, V3(0.f, y1, lo), V3(S, 20.f, 0.f), fl, "floor");
  b.scene.add_box_in(E, V3(0.f, -20.f, lo), V3(S, y0, 0.f), fl, "floor");
  b.scene.add_box_in(E, V3(0.f, y0, lo), V3(S, y1, -depth), concrete_material(rng), "pit_floor");
  label_edge(b.scene, E, V3(0.f, y0, 0.f), V3(0.f, y1, 0.f), V3::UnitX(), depth);
  label_edge(b.scene, E, V3(S, y0, 0.f), V3(S, y1, 0.f), -V3::UnitX(), depth);
  label_edge(b.scene, E, V3(0.f, y0, 0.f), V3(S, y0, 0.f), V3::UnitY(), depth);
  label_edge(b.scene, E, V3(0.f, y1, 0.f), V3(S, y1, 0.f), -V3::UnitY(), depth);
  const Material wall = wall_material(rng);
  b.scene.add_box_in(E, V3(S + rng.uniform(1.f, 4.f), -20.f, 0.f), V3(S + 4.3f, 20.f, 2.8f), wall, "wall");
  if (rng.chance(0.5f))  // a traffic cone at a corner
    b.scene.add_cylinder(E * V3(-0.2f, y1 + 0.25f, 0.f), E * V3(-0.2f, y1 + 0.25f, 0.5f), 0.12f, 0.12f,
                         fabric_material(rng), "cone", 12);
  clutter_before(b.scene, rng, E, 3.f);
}

// A sunken floor: the room's floor ends and a lowered part 0.3-0.8 m below (a conversation pit,
// a lowered room reached by no step here) runs 2-5 m on to a wall or back up to the floor; a
// low table or a seat in it on some.
void sunken_static(Rng& rng, const SynthOptions& o, PresetBuild& b) {
  const Pose E = view_and_edge(rng, o, b);
  const float depth = rng.uniform(0.3f, 0.8f), P = rng.uniform(2.f, 5.f), half = rng.uniform(2.f, 6.f);
  const Material fl = floor_material(rng);
  b.scene.add_box_in(E, V3(-14.f, -20.f, -depth - 0.3f), V3(0.f, 20.f, 0.f), fl, "floor");
  b.scene.add_box_in(E, V3(0.f, -half, -depth - 0.3f), V3(P, half, -depth),
                     rng.chance(0.5f) ? fl : floor_material(rng), "lower_floor");
  for (float s : {-1.f, 1.f})  // the floor on either side of the pit, level with the wearer's
    b.scene.add_box_in(E, V3(0.f, s > 0 ? half : -20.f, -depth - 0.3f), V3(P, s > 0 ? 20.f : -half, 0.f), fl,
                       "floor");
  label_edge(b.scene, E, V3(0.f, -half, 0.f), V3(0.f, half, 0.f), V3::UnitX(), depth);
  const Material wall = wall_material(rng);
  if (rng.chance(0.5f))
    b.scene.add_box_in(E, V3(P, -20.f, -depth), V3(P + 0.3f, 20.f, 2.8f), wall, "wall");
  else
    b.scene.add_box_in(E, V3(P, -20.f, -depth - 0.3f), V3(P + 6.f, 20.f, 0.f), fl, "floor");
  if (rng.chance(0.5f))
    add_crate(b.scene, E * V3(rng.uniform(0.8f, P - 0.5f), rng.uniform(-1.f, 1.f), -depth),
              rng.uniform(-kPi, kPi),
              V3(rng.uniform(0.5f, 1.2f), rng.uniform(0.4f, 0.7f), rng.uniform(0.35f, 0.45f)),
              wood_material(rng), "table");
  clutter_before(b.scene, rng, E, 3.f);
}

// A walk of 4-5 m towards a platform edge ahead (turned +-10 deg) at 0.9-1.3 m/s, stopping with
// the body 0.45-0.7 m before it, standing 2 s, then turning 90 deg away along the platform.
void platform_walk(Rng& rng, const SynthOptions& o, PresetBuild& b) {
  const float edge_x = rng.uniform(4.5f, 5.5f), psi = deg2rad(rng.uniform(-10.f, 10.f));
  const Pose E = edge_frame(V3(edge_x, 0.f, 0.f), psi);
  const float H = rng.uniform(0.8f, 1.3f);
  Material bed = concrete_material(rng);
  bed.albedo *= rng.uniform(0.5f, 0.9f);
  two_levels(b.scene, E, H, 30.f, 5.f, concrete_material(rng), bed);
  b.scene.add_box_in(E, V3(5.f, -30.f, -H - 0.3f), V3(10.f, 30.f, 0.f), concrete_material(rng), "platform");
  b.scene.add_box_in(E, V3(9.f, -30.f, 0.f), V3(9.3f, 30.f, 3.f), wall_material(rng), "wall");
  for (float x : {1.3f, 2.735f})
    b.scene.add_box_in(E, V3(x - 0.035f, -30.f, -H), V3(x + 0.035f, 30.f, -H + 0.15f), metal_material(rng),
                       "rail");
  clutter_before(b.scene, rng, E, 4.f);
  b.sequence = true;
  WalkSpec& w = b.walk;
  w.camera_height_m = pick(o.camera_height_m, rng.uniform(1.1f, 1.5f));
  w.tilt_rad = deg2rad(pick(o.camera_tilt_deg, rng.uniform(35.f, 55.f)));
  w.roll_rad = deg2rad(pick(o.camera_roll_deg, rng.uniform(-2.f, 2.f)));
  w.support_step = [](float) { return 0.f; };
  w.support_smooth = [](float) { return 0.f; };
  w.stride_length = [](float) { return 0.55f; };
  const float stop = edge_x - rng.uniform(0.45f, 0.7f), speed = rng.uniform(0.9f, 1.3f);
  const double t0 = 0.5, t1 = t0 + 1.8 * stop / speed, t_turn = t1 + 2.0;
  w.duration_s = static_cast<float>(t_turn + 2.5);
  w.distance = [=](double t) {
    return stop * smooth_ramp(static_cast<float>(t), static_cast<float>(t0), static_cast<float>(t1));
  };
  const float away = rng.chance(0.5f) ? 1.f : -1.f;
  w.heading = [=](double t) {
    const float tt = static_cast<float>(t);
    return deg2rad(3.f) * std::sin(0.6f * tt) +
           away * 0.5f * kPi * smooth_ramp(tt, static_cast<float>(t_turn), static_cast<float>(t_turn + 1.2));
  };
}

using Fn = void (*)(Rng&, const SynthOptions&, PresetBuild&);

PresetDef def(const char* name, const char* summary, Fn fn, long frames = 1) {
  PresetDef d;
  d.info.name = name;
  d.info.summary = summary;
  d.info.default_frames = frames;
  d.sequence = frames > 1;
  d.build = fn;
  return d;
}

// m, spacing of the samples along an edge; an edge in view has at least kMinSeen m of it seen.
constexpr float kEdgeSpacing = 0.02f;
constexpr float kMinSeen = 0.3f;

}  // namespace

const std::vector<PresetDef>& drop_defs() {
  static const std::vector<PresetDef> defs = {
      def("drop_platform_static",
          "a railway or tram platform's edge 0.5-4 m ahead: the track bed 0.55-1.3 m below, rails, the "
          "opposite "
          "platform; people, benches, bins",
          platform_static),
      def("drop_dock_static",
          "a loading dock's edge 0.5-4 m ahead, the yard 0.9-1.4 m below; bumpers, pallets, a trailer",
          dock_static),
      def("drop_hole_static",
          "a hole in the floor (open pit, trapdoor) 0.6-2.5 m across and 0.3-1.5 m deep, 0.5-4 m ahead",
          hole_static),
      def("drop_sunken_static",
          "a sunken floor 0.3-0.8 m below the room's, its edge 0.5-4 m ahead, no step down", sunken_static),
      def("drop_platform_walk",
          "walk 4-5 m towards a platform edge (0.8-1.3 m drop), stop 0.45-0.7 m before it, stand, turn away",
          platform_walk, 460),
  };
  return defs;
}

// The nearest point of a drop edge the camera sees with the floor on the wearer's side of it:
// sampled every 2 cm; in view with at least 0.3 m of edge seen.
void drop_truth(const Scene& scene, const WalkerState& walker, const RenderBuffers& ideal,
                const CameraIntrinsics& K, const SynthOptions& o, FrameTruth& t) {
  if (scene.drops.empty()) return;
  const Pose T_cw = walker.T_world_camera.inverse();
  const V3 cam = walker.T_world_camera.translation();
  V3 fwd = walker.T_world_camera.linear().col(2);
  fwd.z() = 0.f;
  if (fwd.norm() < 1e-3f) return;
  fwd.normalize();
  const V3 right(fwd.y(), -fwd.x(), 0.f);  // world: z up, y to the left of +x
  float best = std::numeric_limits<float>::infinity(), bearing = 0.f, seen_m = 0.f;
  for (const DropEdge& e : scene.drops) {
    t.drop_depth_m = std::max(t.drop_depth_m, e.depth_m);
    const int n = std::max(2, static_cast<int>(std::ceil((e.b - e.a).norm() / kEdgeSpacing)) + 1);
    for (int j = 0; j < n; ++j) {
      const V3 p = e.a + (e.b - e.a) * (static_cast<float>(j) / static_cast<float>(n - 1));
      V3 v = p - cam;
      v.z() = 0.f;
      if (v.dot(e.down_dir) <= 0.f) continue;  // seen from the lower side or beside it: not ahead
      if (!point_seen(T_cw * p, ideal.depth, K, o)) continue;
      seen_m += kEdgeSpacing;
      if (v.norm() < best) {
        best = v.norm();
        bearing = std::atan2(v.dot(right), v.dot(fwd));
      }
    }
  }
  if (seen_m < kMinSeen) return;
  t.drop_in_view = true;
  t.drop_distance_m = best;
  t.drop_bearing_rad = bearing;
}

}  // namespace stairguide::synth::detail

namespace stairguide::synth {

const std::vector<PresetInfo>& drop_presets() {
  static const std::vector<PresetInfo> list = [] {
    std::vector<PresetInfo> l;
    for (const auto& d : detail::drop_defs()) l.push_back(d.info);
    return l;
  }();
  return list;
}

}  // namespace stairguide::synth
