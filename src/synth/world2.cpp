// The second synthetic world (issue 39, synth::world2_presets()): what real stairs have and the
// first world lacked, and stair-free furniture a looser decision could take for stairs. Every
// range is the real world's (docs/synthetic.md gives the sources), never the detector's: a
// flight or a piece of furniture is drawn as it is built, and the ground truth says what it is.
// These presets draw only from their own per-frame streams, so no figure of the other presets
// moves. This file: the views and rooms the presets share, the stairs, and the list (world2_defs);
// the furniture is in world2_furniture.cpp.
#include <algorithm>
#include <cmath>

#include "world2_internal.hpp"

namespace stairguide::synth::detail {
namespace world2 {

float pick(float v, float fallback) { return std::isnan(v) ? fallback : v; }

// The wearer standing at `body` (a point of the surface they stand on) facing `yaw`, the camera
// 0.12 m ahead of the body, h_lo..h_hi m above that surface, tilted tilt_lo..tilt_hi deg down,
// rolled +-3 deg (unless the options fix height, tilt or roll).
WalkerState view_at(Rng& rng, const SynthOptions& o, const V3& body, float yaw, float h_lo, float h_hi,
                    float tilt_lo, float tilt_hi) {
  const float h = pick(o.camera_height_m, rng.uniform(h_lo, h_hi));
  const float tilt = deg2rad(pick(o.camera_tilt_deg, rng.uniform(tilt_lo, tilt_hi)));
  const float roll = deg2rad(pick(o.camera_roll_deg, rng.uniform(-3.f, 3.f)));
  WalkerState st;
  st.body = body;
  st.yaw = yaw;
  st.support_z = body.z();
  const V3 cam = body + 0.12f * V3(std::cos(yaw), std::sin(yaw), 0.f) + V3(0.f, 0.f, h);
  st.T_world_camera = camera_pose(cam, yaw, tilt, roll);
  return st;
}

WalkerState view_at(Rng& rng, const SynthOptions& o, const V3& body, float yaw, const Rig& rig) {
  return view_at(rng, o, body, yaw, rig.h_lo, rig.h_hi, rig.tilt_lo, rig.tilt_hi);
}

// A chest camera (1.0-1.6 m, tilted 30-60 deg).
WalkerState chest_view(Rng& rng, const SynthOptions& o, const V3& body, float yaw) {
  return view_at(rng, o, body, yaw, kChest);
}

// A chest view from the world origin, heading within +-25 deg of +x.
WalkerState chest_view_ahead(Rng& rng, const SynthOptions& o) {
  return chest_view(rng, o, V3::Zero(), deg2rad(rng.uniform(-25.f, 25.f)));
}

// A floor slab and four walls 2.7 m high around [lo, hi].
void floor_and_walls(Scene& s, Rng& rng, const V2& lo, const V2& hi) {
  s.add_box_world(V3(lo.x() - 1.f, lo.y() - 1.f, -0.2f), V3(hi.x() + 1.f, hi.y() + 1.f, 0.f),
                  floor_material(rng), "floor");
  add_room_walls(s, lo, hi, 0.f, 2.7f, wall_material(rng));
}

// A living room or bedroom 9 x 7 m around the wearer at the origin.
void room(Scene& s, Rng& rng) { floor_and_walls(s, rng, V2(-3.f, -3.5f), V2(6.f, 3.5f)); }

// Pose of a frame at `p` whose x axis points along `yaw` (world), z up.
Pose yaw_frame(const V3& p, float yaw) {
  Pose T = Pose::Identity();
  T.linear() = Eigen::AngleAxisf(yaw, V3::UnitZ()).toRotationMatrix();
  T.translation() = p;
  return T;
}

// Riser and going drawn together from the building codes of the world (the first world's range,
// SOURCES.md: risers 10-22 cm, goings 20-45 cm, 2R+T 50-72 cm).
void code_riser_going(Rng& rng, float& riser, float& going) {
  for (int i = 0; i < 100; ++i) {
    riser = rng.uniform(0.10f, 0.22f);
    going = rng.uniform(0.20f, 0.45f);
    const float blondel = 2.f * riser + going;
    if (blondel >= 0.50f && blondel <= 0.72f) break;
  }
}

// Outdoor ground: paving or concrete.
Material ground_material(Rng& rng) { return rng.chance(0.5f) ? concrete_material(rng) : floor_material(rng); }

// A flight `p` whose first edge lies d_lo..d_hi m ahead of the wearer at the origin (lateral
// +-0.3 m), indoors (a room around it; a descending flight's walls go down to its foot) or
// outdoors (open ground, a facade far behind), and a view of it from `rig`, heading +-25 deg.
// Returns the flight's index in the scene's stairs.
int flight_ahead(Rng& rng, const SynthOptions& o, PresetBuild& b, StairParams p, bool outdoor,
                 float d_lo = 0.8f, float d_hi = 3.0f, const Rig& rig = kChest) {
  const bool down = p.kind == StairKind::kDescending;
  const float d = rng.uniform(d_lo, d_hi), lat = rng.uniform(-0.3f, 0.3f);
  p.T_world_stair = stair_pose(d, lat, 0.f, down ? 0.f : p.riser_m);
  const float N = static_cast<float>(p.steps);
  int id = 0;
  if (!down) {
    const float end = d + (N - 1.f) * p.tread_m + p.top_depth_m;
    if (outdoor) {
      b.scene.add_box_world(V3(-6.f, -8.f, -0.3f), V3(end + 6.f, 8.f, 0.f), ground_material(rng), "floor");
    } else {
      const float half = 0.5f * p.width_m + rng.uniform(0.2f, 2.5f);
      floor_and_walls(b.scene, rng, V2(-3.f, -half - 0.5f), V2(end + 0.2f, half + 0.5f));
    }
    id = add_staircase(b.scene, p, rng);
  } else {
    id = add_staircase(b.scene, p, rng);  // the upper floor and the lower one with it
    const float total = N * p.riser_m;
    if (outdoor)
      b.scene.add_box_world(V3(-3.5f, -6.f, -total - 0.3f), V3(-3.2f, 6.f, 3.f), wall_material(rng),
                            "facade");
    else
      add_room_walls(b.scene, V2(-3.f, -4.f), V2(d + N * p.tread_m + 5.f, 4.f), -total - 0.2f, 2.9f + total,
                     wall_material(rng));
  }
  b.view = view_at(rng, o, V3::Zero(), deg2rad(rng.uniform(-25.f, 25.f)), rig);
  return id;
}

Material cardboard(Rng& rng) {
  Material m;
  m.albedo = V3(0.35f, 0.52f, 0.68f) * rng.uniform(0.8f, 1.15f);
  m.texture = Texture::kPlain;
  m.contrast = 0.15f;
  m.texel_m = 0.01f;
  return m;
}

}  // namespace world2

using namespace world2;

namespace {

// ---- L- and U-shaped stairs seen from their landing ----

// The wearer stands on the landing between two flights: the lower one going down from it, the
// upper one rising from it to the side (L: a quarter turn, the upper flight leaves from a side of
// the landing; U: a half turn, the upper flight runs back beside the lower one past a central wall
// or an open well). World: the landing at z = 0, the lower flight arrives along +x at x = 0.
// Both flights are labelled (a descending and an ascending staircase). The wearer faces one of
// them (before its first edge) or looks at it from the side, turning on the landing.
void turn_static(Rng& rng, const SynthOptions& o, PresetBuild& b) {
  const bool u_shape = rng.chance(0.5f);
  const float s = rng.chance(0.5f) ? 1.f : -1.f;  // the side the upper flight turns to
  float R = 0.17f, T = 0.28f;
  code_riser_going(rng, R, T);
  const float W = rng.uniform(0.75f, 1.5f), hw = 0.5f * W;
  const float nosing = rng.chance(0.4f) ? rng.uniform(0.01f, 0.04f) : 0.f;
  const int n_lo = rng.integer(2, 10), n_up = rng.integer(2, 10);
  const float total_lo = static_cast<float>(n_lo) * R, total_up = static_cast<float>(n_up) * R;
  const float top = total_up + 2.4f;  // height of the walls above the landing
  bool central_wall = false;
  float gap = 0.f, D = 0.f, ylo = -hw, yhi = hw;
  if (!u_shape) {
    D = W + rng.uniform(0.f, 0.4f);  // a quarter landing: at least the flight's width
  } else {
    central_wall = rng.chance(0.6f);
    gap = central_wall ? rng.uniform(0.1f, 0.25f) : rng.uniform(0.05f, 0.4f);
    D = std::max(W, rng.uniform(0.9f, 1.6f));
    if (s > 0.f)
      yhi = hw + gap + W;
    else
      ylo = -(hw + gap + W);
  }
  const Material wall_m = wall_material(rng);

  // The lower flight, going down from the landing's edge at x = 0 towards -x.
  StairParams lo = flight_params(StairKind::kDescending, n_lo, R, T, W);
  lo.nosing_m = nosing;
  lo.build_floor = false;
  lo.side_walls = false;
  lo.handrails = !central_wall || rng.chance(0.5f);
  lo.T_world_stair = stair_pose(0.f, 0.f, kPi, 0.f);
  const int id_lo = add_staircase(b.scene, lo, rng);
  const float foot = static_cast<float>(n_lo - 1) * T;  // where the lower floor (its last tread) begins
  // The lower floor: the lower flight's last tread, under everything.
  b.scene.add_box_in(lo.T_world_stair, V3(-hw - 4.f, -total_lo - 0.2f, -8.f),
                     V3(hw + 4.f, -total_lo, foot + 6.f), floor_material(rng), "lower_floor", id_lo, n_lo);
  // The landing: with nosings, its edge overhangs the first riser below it like the treads'.
  const Material land_m = floor_material(rng);
  if (nosing > 0.f) {
    b.scene.add_box_world(V3(nosing, ylo, -total_lo), V3(D, yhi, -0.03f), wall_m, "landing_support");
    b.scene.add_box_world(V3(0.f, ylo, -0.03f), V3(D, yhi, 0.f), land_m, "landing");
  } else {
    b.scene.add_box_world(V3(0.f, ylo, -total_lo), V3(D, yhi, 0.f), land_m, "landing");
  }

  // The upper flight, rising from the landing.
  StairParams up = flight_params(StairKind::kAscending, n_up, R, T, W);
  up.nosing_m = nosing;
  up.top_depth_m = rng.uniform(1.2f, 2.5f);
  up.handrails = lo.handrails;
  up.wall_start_m = 0.f;
  const float len_lo = foot + 2.5f;  // the stairwell runs on 2.5 m past the lower flight's foot
  // A U's upper floor runs back over the whole stairwell (no void beside the lower flight).
  if (u_shape) up.top_depth_m = std::max(up.top_depth_m, len_lo + 0.2f - static_cast<float>(n_up - 1) * T);
  const float len_up = static_cast<float>(n_up - 1) * T + up.top_depth_m;
  if (!u_shape) {
    up.side_walls = true;
    up.T_world_stair = stair_pose(D - hw, s * hw, s * 0.5f * kPi, R);
    add_staircase(b.scene, up, rng);
    // The stairwell: walls along the lower flight, round the landing.
    for (float side : {-1.f, 1.f}) {
      const float y0 = side * hw, y1 = side * (hw + 0.12f);
      const float x1 = side == s ? std::max(0.f, D - W) : D + 0.12f;
      b.scene.add_box_world(V3(-len_lo, std::min(y0, y1), -total_lo), V3(x1, std::max(y0, y1), top), wall_m,
                            "wall");
    }
    b.scene.add_box_world(V3(D, std::min(-s * (hw + 0.12f), s * hw), -total_lo),
                          V3(D + 0.12f, std::max(-s * (hw + 0.12f), s * hw), top), wall_m, "wall");
    b.scene.add_box_world(V3(-len_lo - 0.12f, -hw - 0.12f, -total_lo), V3(-len_lo, hw + 0.12f, top), wall_m,
                          "wall");
  } else {
    const float yc = s * (W + gap);
    up.side_walls = false;
    up.T_world_stair = stair_pose(0.f, yc, kPi, R);
    add_staircase(b.scene, up, rng);
    // Under the upper flight: solid down to the lower floor.
    b.scene.add_box_world(V3(-len_up, yc - hw, -total_lo), V3(0.f, yc + hw, 0.f), wall_m, "stair_support");
    const float far = std::max(len_lo, len_up) + 0.2f;
    if (central_wall) {
      const float y0 = s * hw, y1 = s * (hw + gap);
      b.scene.add_box_world(V3(-far, std::min(y0, y1), -total_lo), V3(0.f, std::max(y0, y1), top), wall_m,
                            "wall");
    }
    b.scene.add_box_world(V3(-far, ylo - 0.12f, -total_lo), V3(D + 0.12f, ylo, top), wall_m, "wall");
    b.scene.add_box_world(V3(-far, yhi, -total_lo), V3(D + 0.12f, yhi + 0.12f, top), wall_m, "wall");
    b.scene.add_box_world(V3(D, ylo, -total_lo), V3(D + 0.12f, yhi, top), wall_m, "wall");
    b.scene.add_box_world(V3(-far - 0.12f, ylo - 0.12f, -total_lo), V3(-far, yhi + 0.12f, top), wall_m,
                          "wall");
  }

  // The view: on the landing, facing the upper or the lower flight, or turning towards it.
  const bool to_upper = rng.chance(0.5f);
  const Pose& Tf = to_upper ? up.T_world_stair : lo.T_world_stair;
  const V3 c(Tf.translation().x(), Tf.translation().y(), 0.f);
  const V3 t = Tf.linear().col(2);  // horizontal: the direction of travel
  const V3 l(-t.y(), t.x(), 0.f);
  const float margin = 0.2f;
  auto on_landing = [&](V3 p) {
    p.x() = std::clamp(p.x(), margin, std::max(margin, D - margin));
    p.y() = std::clamp(p.y(), ylo + margin, std::max(ylo + margin, yhi - margin));
    p.z() = 0.f;
    return p;
  };
  V3 body;
  float yaw = 0.f;
  if (rng.chance(0.5f)) {  // facing it, before its first edge
    body = on_landing(c - rng.uniform(0.25f, 1.3f) * t + rng.uniform(-0.3f, 0.3f) * W * l);
    yaw = std::atan2(t.y(), t.x()) + deg2rad(rng.uniform(-20.f, 20.f));
  } else {  // beside it: 35-80 deg off its axis, looking at its first treads
    const float phi = deg2rad(rng.uniform(35.f, 80.f)) * (rng.chance(0.5f) ? 1.f : -1.f);
    const V3 dir = -std::cos(phi) * t + std::sin(phi) * l;
    body = on_landing(c + rng.uniform(0.5f, 1.5f) * dir);
    const V3 aim = c + rng.uniform(0.1f, 0.8f) * t;
    yaw = std::atan2(aim.y() - body.y(), aim.x() - body.x()) + deg2rad(rng.uniform(-10.f, 10.f));
  }
  b.view = chest_view(rng, o, body, yaw);
}

// ---- low and steep flights ----

// Low risers (8-12 cm) with long goings (30-60 cm), 2R+T anything: rehabilitation training
// stairs (freestanding, open sides, handrails, a platform on top) and garden steps (outdoors,
// wide, paving or concrete); going down: a few low steps into a sunken room or down a garden.
void low_static(Rng& rng, const SynthOptions& o, PresetBuild& b) {
  const bool down = rng.chance(0.5f), garden = rng.chance(0.5f);
  StairParams p;
  p.kind = down ? StairKind::kDescending : StairKind::kAscending;
  p.steps = garden ? rng.integer(2, 6) : rng.integer(2, 5);
  p.riser_m = rng.uniform(0.08f, 0.12f);
  p.tread_m = garden ? rng.uniform(0.30f, 0.60f) : rng.uniform(0.30f, 0.40f);
  p.width_m = garden ? rng.uniform(0.9f, 3.0f) : rng.uniform(0.6f, 1.2f);
  p.nosing_m = rng.chance(0.3f) ? rng.uniform(0.01f, 0.03f) : 0.f;
  if (garden) {
    p.side_walls = down && rng.chance(0.5f);  // cut into the slope, or open
    p.handrails = rng.chance(0.3f);
    p.top_depth_m = rng.uniform(1.5f, 4.f);
  } else {
    p.side_walls = down;  // a sunken room's floor beside the steps
    p.handrails = !down || rng.chance(0.5f);
    p.top_depth_m = down ? rng.uniform(1.5f, 3.f) : rng.uniform(0.6f, 1.0f);  // a training stair's platform
  }
  p.wall_start_m = rng.uniform(-1.5f, 0.f);
  flight_ahead(rng, o, b, p, garden);
}

// Steep flights: goings 20-24 cm, risers 18-25 cm (cellar, attic and service stairs, old
// houses), narrow, often with open risers or nosings.
void steep_static(Rng& rng, const SynthOptions& o, PresetBuild& b) {
  StairParams p;
  p.kind = rng.chance(0.5f) ? StairKind::kDescending : StairKind::kAscending;
  p.steps = rng.integer(3, 14);
  p.riser_m = rng.uniform(0.18f, 0.25f);
  p.tread_m = rng.uniform(0.20f, 0.24f);
  p.width_m = rng.uniform(0.6f, 1.2f);
  p.open_risers = rng.chance(0.3f);
  p.nosing_m = !p.open_risers && rng.chance(0.5f) ? rng.uniform(0.02f, 0.04f) : 0.f;
  p.side_walls = !p.open_risers && rng.chance(0.7f);
  p.handrails = rng.chance(0.6f);
  p.wall_start_m = rng.uniform(-1.5f, 0.f);
  p.top_depth_m = rng.uniform(1.2f, 3.f);
  flight_ahead(rng, o, b, p, false);
}

// A flight from the codes of the world (riser 10-22 cm, going 20-45 cm, 2R+T 50-72 cm), 2-14
// steps, narrow (0.65-0.9 m), usual or wide (1.8-2.6 m), nosings on 40%, walls on 60%.
StairParams code_flight(Rng& rng, StairKind kind) {
  StairParams p;
  p.kind = kind;
  p.steps = rng.integer(2, 14);
  code_riser_going(rng, p.riser_m, p.tread_m);
  const float w = rng.uniform();
  p.width_m =
      w < 0.25f ? rng.uniform(0.65f, 0.9f) : (w < 0.45f ? rng.uniform(1.8f, 2.6f) : rng.uniform(0.9f, 1.8f));
  p.nosing_m = rng.chance(0.4f) ? rng.uniform(0.01f, 0.04f) : 0.f;
  p.side_walls = rng.chance(0.6f);
  p.handrails = rng.chance(0.5f);
  p.wall_start_m = rng.uniform(-1.5f, 0.f);
  p.top_depth_m = rng.uniform(1.2f, 3.f);
  return p;
}

// ---- dressed flights: carpet, nosings, and things standing on the steps ----

// Things left on a step (the heights the issue names, 10-40 cm): a pair of shoes or boots, a bag,
// a box. `k_top` is the tread's height (frame B of the flight), [z_lo, z_hi] its free depth.
void add_thing_on_tread(Scene& scene, Rng& rng, const Pose& T_wb, float hw, float k_top, float z_lo,
                        float z_hi, bool against_hi) {
  if (z_hi - z_lo < 0.08f) return;
  const int kind = rng.integer(0, 2);
  // A box w wide (along the step) and dp deep, against one end of [lo, hi] (a gap of 0-3 cm).
  auto place = [&](float w, float dp, float h, const Material& m, const char* label, float x, float lo,
                   float hi) {
    dp = std::min(dp, hi - lo);
    const float gap = std::min(rng.uniform(0.f, 0.03f), hi - lo - dp);
    const float z1 = against_hi ? hi - gap : lo + gap + dp;
    scene.add_box_in(T_wb, V3(x - 0.5f * w, k_top, z1 - dp), V3(x + 0.5f * w, k_top + h, z1), m, label);
  };
  auto lateral = [&](float w) { return std::max(0.f, hw - 0.5f * w) * rng.uniform(-1.f, 1.f); };
  if (kind == 0) {  // a pair of shoes (boots one time in three)
    const float len = rng.uniform(0.24f, 0.31f), wid = rng.uniform(0.08f, 0.11f);
    const float h = rng.chance(0.33f) ? rng.uniform(0.20f, 0.35f) : rng.uniform(0.10f, 0.14f);
    Material m = rng.chance(0.5f) ? fabric_material(rng) : wood_material(rng);
    m.albedo *= 0.5f;
    if (z_hi - z_lo < len + 0.02f || rng.chance(0.5f)) {  // lying along the step, one before the other
      const float x = lateral(len);
      place(len, wid, h, m, "shoe", x, z_lo, z_hi);
      if (z_hi - z_lo >= 2.f * wid + 0.03f) {
        const float shift = wid + 0.01f;
        place(len, wid, h, m, "shoe", x, against_hi ? z_lo : z_lo + shift, against_hi ? z_hi - shift : z_hi);
      }
    } else {  // side by side, pointing into the step
      const float x = lateral(2.f * wid + 0.03f);
      place(wid, len, h, m, "shoe", x - 0.5f * wid - 0.015f, z_lo, z_hi);
      place(wid, len, h, m, "shoe", x + 0.5f * wid + 0.015f, z_lo, z_hi);
    }
  } else if (kind == 1) {  // a bag
    const float w = rng.uniform(0.25f, 0.45f), dp = rng.uniform(0.10f, 0.25f), h = rng.uniform(0.20f, 0.40f);
    place(w, dp, h, fabric_material(rng), "bag", lateral(w), z_lo, z_hi);
  } else {  // a box
    const float w = rng.uniform(0.15f, 0.40f), dp = rng.uniform(0.15f, 0.35f), h = rng.uniform(0.10f, 0.40f);
    place(w, dp, h, cardboard(rng), "box", lateral(w), z_lo, z_hi);
  }
}

// A carpet of the palette of stair carpets, its pile a relief of 2-4 mm.
Material carpet_material(Rng& rng) {
  const V3 palettes[4] = {V3(0.30f, 0.25f, 0.40f), V3(0.25f, 0.30f, 0.25f), V3(0.45f, 0.45f, 0.50f),
                          V3(0.20f, 0.20f, 0.45f)};
  Material m;
  m.albedo = palettes[rng.integer(0, 3)] * rng.uniform(0.8f, 1.2f);
  m.texture = Texture::kCarpet;
  m.contrast = rng.uniform(0.3f, 0.5f);
  m.texel_m = rng.uniform(0.003f, 0.005f);
  m.relief_m = rng.uniform(0.002f, 0.004f);
  return m;
}

// Dressed flights, up or down, of the codes' range, indoors: on 60% a fitted carpet 8-15 mm thick
// (pile relief 2-4 mm) over the floor, the treads and the risers, wrapped round each nosing
// (1.5-3.5 cm) as a rounded bull nose of 2.3-3 cm radius; on 75% of the carpeted flights and on all
// the others, shoes, bags or boxes (10-40 cm high) standing on 1-3 treads. The labels keep the
// flight's riser and going; its first edge is the front of the first bull nose, at the carpet's
// height.
void dressed_static(Rng& rng, const SynthOptions& o, PresetBuild& b) {
  const bool down = rng.chance(0.5f);
  StairParams p = code_flight(rng, down ? StairKind::kDescending : StairKind::kAscending);
  p.steps = rng.integer(3, 14);
  p.open_risers = false;
  const bool carpet = rng.chance(0.6f);
  const bool things = !carpet || rng.chance(0.75f);
  if (carpet) p.nosing_m = rng.uniform(0.015f, 0.035f);
  const float c = carpet ? rng.uniform(0.008f, 0.015f) : 0.f;
  const Material cm = carpet_material(rng);
  const float d = rng.uniform(0.8f, 3.0f), lat = rng.uniform(-0.3f, 0.3f);
  const float R = p.riser_m, T = p.tread_m, n = p.nosing_m, hw = 0.5f * p.width_m;
  const int N = p.steps;
  p.T_world_stair = stair_pose(d, lat, 0.f, down ? 0.f : R);
  const float top_z0 = static_cast<float>(N - 1) * T, top_end = top_z0 + p.top_depth_m;
  int id = 0;
  if (!down) {
    const float half = 0.5f * p.width_m + rng.uniform(0.2f, 2.5f), end = d + top_end;
    floor_and_walls(b.scene, rng, V2(-3.f, -half - 0.5f), V2(end + 0.2f, half + 0.5f));
    id = add_staircase(b.scene, p, rng);
    if (carpet)
      b.scene.add_box_world(V3(-3.f, -half - 0.5f, 0.f), V3(end + 0.2f, half + 0.5f, c), cm, "carpet");
  } else {
    id = add_staircase(b.scene, p, rng);
    add_room_walls(b.scene, V2(-3.f, -4.f), V2(d + static_cast<float>(N) * T + 5.f, 4.f),
                   -static_cast<float>(N) * R - 0.2f, 2.9f + static_cast<float>(N) * R, wall_material(rng));
  }
  // Frame B of the flight: the stair frame moved down to the floor before its first edge.
  Pose T_wb = p.T_world_stair;
  T_wb.translation() = p.T_world_stair * V3(0.f, down ? 0.f : -R, 0.f);
  const float rn = 0.015f + c;  // the bull nose's radius, round the 3 cm nosing slab's mid line
  auto nose = [&](float y_top, float z, float half_w) {
    b.scene.add_cylinder(T_wb * V3(-half_w, y_top - 0.015f, z), T_wb * V3(half_w, y_top - 0.015f, z), rn, rn,
                         cm, "carpet", 16);
  };
  if (carpet && !down) {
    for (int k = 1; k <= N; ++k) {
      const float z0 = static_cast<float>(k - 1) * T, z1 = k < N ? static_cast<float>(k) * T : top_end;
      const float y = static_cast<float>(k) * R;
      b.scene.add_box_in(T_wb, V3(-hw, y, z0 + 0.015f), V3(hw, y + c, z1 + n), cm, "carpet", id, k);
      nose(y, z0 + 0.015f, hw);
      b.scene.add_box_in(T_wb, V3(-hw, y - R + c, z0 + n - c), V3(hw, y - 0.03f, z0 + n), cm, "carpet");
    }
  } else if (carpet) {
    const float total = static_cast<float>(N) * R, side = p.side_walls ? hw : 6.f;
    b.scene.add_box_in(T_wb, V3(-6.f, 0.f, -8.f), V3(6.f, c, -0.015f), cm, "carpet");
    nose(0.f, -0.015f, side);
    for (int k = 1; k < N; ++k) {
      const float z0 = static_cast<float>(k - 1) * T, y = -static_cast<float>(k) * R;
      b.scene.add_box_in(T_wb, V3(-hw, y, z0 - n), V3(hw, y + c, z0 + T - 0.015f), cm, "carpet", id, k);
      nose(y, z0 + T - 0.015f, hw);
    }
    b.scene.add_box_in(T_wb, V3(-6.f, -total, top_z0 - n), V3(6.f, -total + c, top_z0 + 8.f), cm, "carpet",
                       id, N);
    if (p.side_walls)  // the upper floor beside the flight
      for (float sd : {-1.f, 1.f})
        b.scene.add_box_in(T_wb, V3(sd > 0 ? hw : -6.f, 0.f, -0.015f),
                           V3(sd > 0 ? 6.f : -hw, c, top_z0 + 4.f), cm, "carpet");
  }
  if (carpet) {  // the labels: every level is c higher, the first edge is the bull nose's front
    StairSpec& sp = b.scene.stairs[static_cast<std::size_t>(id)];
    sp.base_z += c;
    sp.T_world_stair.translation() += V3(0.f, 0.f, c) + (down ? c : -c) * sp.T_world_stair.linear().col(2);
  }
  if (things) {
    std::vector<int> treads;
    for (int k = 1; k < N; ++k) treads.push_back(k);
    for (int i = 0, m = rng.integer(1, std::min(3, N - 1)); i < m && !treads.empty(); ++i) {
      const std::size_t j = static_cast<std::size_t>(rng.integer(0, static_cast<int>(treads.size()) - 1));
      const int k = treads[j];
      treads.erase(treads.begin() + static_cast<std::ptrdiff_t>(j));
      const float z0 = static_cast<float>(k - 1) * T;
      for (int q = 0, per = rng.integer(1, 2); q < per; ++q) {
        if (!down)  // from the nose to the next riser, against the riser
          add_thing_on_tread(b.scene, rng, T_wb, hw, static_cast<float>(k) * R + c, z0 + 0.03f + c,
                             z0 + T + n - c, true);
        else  // from the riser above to the nose, against the riser
          add_thing_on_tread(b.scene, rng, T_wb, hw, -static_cast<float>(k) * R + c, z0 - n,
                             z0 + T - 0.03f - c, false);
      }
    }
  }
  b.view = chest_view(rng, o, V3(0.f, 0.f, c), deg2rad(rng.uniform(-25.f, 25.f)));
}

// ---- the wearer's own legs ----

// The wearer's legs and feet, standing at the body point `body` facing `yaw`: hips at 0.74 of
// the camera's height (a chest camera sits at about 0.72 of the stature, the hip joint at 0.53),
// thighs 7-9 cm and shanks 5-6 cm in radius, shoes 26-31 cm long, 9-11 cm wide, 7-11 cm high;
// feet 15-30 cm apart, one 0-45 cm ahead of the other (standing, or mid-step).
void add_wearer_legs(Scene& scene, Rng& rng, const V3& body, float yaw, float camera_h) {
  const V3 fwd(std::cos(yaw), std::sin(yaw), 0.f), left(-fwd.y(), fwd.x(), 0.f);
  Material trousers = fabric_material(rng);
  trousers.albedo *= rng.uniform(0.4f, 0.9f);
  Material shoe = rng.chance(0.5f) ? fabric_material(rng) : metal_material(rng);
  shoe.albedo *= rng.uniform(0.3f, 0.8f);
  const float hip_z = 0.74f * camera_h, spread = rng.uniform(0.15f, 0.30f), ahead = rng.uniform(0.f, 0.45f);
  const float lead = rng.chance(0.5f) ? 1.f : -1.f;  // the foot ahead: left or right
  const float r_thigh = rng.uniform(0.07f, 0.09f), r_shank = rng.uniform(0.05f, 0.06f);
  const float len = rng.uniform(0.26f, 0.31f), wid = rng.uniform(0.09f, 0.11f),
              hgt = rng.uniform(0.07f, 0.11f);
  for (float side : {-1.f, 1.f}) {
    // The ankle 5 cm ahead of the heel; the foot ahead reaches `ahead` further, the other as far
    // back.
    const float a = side == lead ? 0.5f * ahead : -0.5f * ahead;
    const V3 ankle = body + a * fwd + side * 0.5f * spread * left + V3(0.f, 0.f, 0.8f * hgt);
    const V3 hip = body + side * rng.uniform(0.08f, 0.10f) * left + V3(0.f, 0.f, hip_z);
    const V3 knee = 0.5f * (hip + ankle) + rng.uniform(0.02f, 0.06f) * fwd;
    scene.add_cylinder(hip, knee, r_thigh, r_thigh, trousers, "wearer_leg", 12);
    scene.add_cylinder(knee, ankle, r_shank, r_shank, trousers, "wearer_leg", 10);
    const float toe_out = deg2rad(rng.uniform(0.f, 15.f)) * side;
    const float fy = yaw + toe_out;
    const V3 heel =
        body + a * fwd + side * 0.5f * spread * left - 0.05f * V3(std::cos(fy), std::sin(fy), 0.f);
    scene.add_box_in(yaw_frame(heel, fy), V3(0.f, -0.5f * wid, 0.f), V3(len, 0.5f * wid, hgt), shoe,
                     "wearer_foot");
  }
}

// The wearer's own legs and feet at the bottom of the view, in front of a flight up or down
// (codes' range) whose first edge is 2-100 cm beyond the toes; the chest camera tilted 50-80 deg
// (steeply, as when looking down at the first step: the legs come into view).
void legs_static(Rng& rng, const SynthOptions& o, PresetBuild& b) {
  StairParams p = code_flight(rng, rng.chance(0.5f) ? StairKind::kDescending : StairKind::kAscending);
  const bool down = p.kind == StairKind::kDescending;
  // The view first (the legs hang from it), then the flight beyond the toes.
  const Rig rig{1.0f, 1.6f, 50.f, 80.f};
  b.view = view_at(rng, o, V3::Zero(), 0.f, rig);
  const float h = b.view.T_world_camera.translation().z();
  add_wearer_legs(b.scene, rng, V3::Zero(), 0.f, h);
  const float gap = rng.uniform(0.02f, 1.0f), lat = rng.uniform(-0.2f, 0.2f),
              psi = deg2rad(rng.uniform(-15.f, 15.f));
  // The first edge `gap` beyond the foremost point of either shoe, measured along the flight.
  const V3 n(std::cos(psi), std::sin(psi), 0.f);
  float d = 0.f;
  for (const Solid& so : b.scene.solids())
    if (so.label == "wearer_foot")
      for (int f = so.first_face; f < so.first_face + so.face_count; ++f)
        for (const V3& q : b.scene.faces()[static_cast<std::size_t>(f)].vertices)
          d = std::max(d, (q.dot(n) - lat * n.y() + gap) / n.x());
  p.T_world_stair = stair_pose(d, lat, psi, down ? 0.f : p.riser_m);
  const float N = static_cast<float>(p.steps);
  if (!down) {
    const float end = d + (N - 1.f) * p.tread_m + p.top_depth_m;
    const float half = 0.5f * p.width_m + rng.uniform(0.2f, 2.0f);
    floor_and_walls(b.scene, rng, V2(-3.f, -half - 0.5f), V2(end + 0.5f, half + 0.5f));
    add_staircase(b.scene, p, rng);
  } else {
    add_staircase(b.scene, p, rng);
    const float total = N * p.riser_m;
    add_room_walls(b.scene, V2(-3.f, -4.f), V2(d + N * p.tread_m + 5.f, 4.f), -total - 0.2f, 2.9f + total,
                   wall_material(rng));
  }
}

// ---- low rigs: a waist or hip camera ----

// A camera 0.5-0.8 m high (on a belt, a hip, a bag strap), tilted 15-60 deg, looking at a flight
// up or down drawn from the codes: its first edge 0.4-1.2 times as far as the optical axis meets
// the floor (0.3-3.0 m), turned +-10 deg from the heading.
void lowrig_static(Rng& rng, const SynthOptions& o, PresetBuild& b) {
  StairParams p = code_flight(rng, rng.chance(0.5f) ? StairKind::kDescending : StairKind::kAscending);
  p.open_risers = p.kind == StairKind::kAscending && rng.chance(0.2f);
  if (p.open_risers) {
    p.nosing_m = 0.f;
    p.side_walls = false;
  }
  const bool down = p.kind == StairKind::kDescending;
  b.view = view_at(rng, o, V3::Zero(), deg2rad(rng.uniform(-25.f, 25.f)), Rig{0.5f, 0.8f, 15.f, 60.f});
  const float h = b.view.T_world_camera.translation().z(),
              tilt = std::max(0.2f, pose_tilt(b.view.T_world_camera));
  const float d = std::clamp(rng.uniform(0.4f, 1.2f) * h / std::tan(tilt), 0.3f, 3.0f);
  const float yaw = b.view.yaw + deg2rad(rng.uniform(-10.f, 10.f)), lat = rng.uniform(-0.2f, 0.2f);
  const V3 at = d * V3(std::cos(b.view.yaw), std::sin(b.view.yaw), 0.f) +
                lat * V3(-std::sin(b.view.yaw), std::cos(b.view.yaw), 0.f);
  p.T_world_stair = stair_pose(at.x(), at.y(), yaw, down ? 0.f : p.riser_m);
  const float N = static_cast<float>(p.steps);
  const float ext = d + N * p.tread_m + p.top_depth_m + 1.5f;  // a room round all of it, whatever the turn
  if (!down) {
    floor_and_walls(b.scene, rng, V2(-3.f, -ext), V2(ext, ext));
    add_staircase(b.scene, p, rng);
  } else {
    add_staircase(b.scene, p, rng);
    const float total = N * p.riser_m;
    add_room_walls(b.scene, V2(-3.f, -ext - 4.f), V2(ext + 4.f, ext + 4.f), -total - 0.2f, 2.9f + total,
                   wall_material(rng));
  }
}

using Fn = void (*)(Rng&, const SynthOptions&, PresetBuild&);

// A static view: one frame, drawn anew for every index.
PresetDef def(const char* name, const char* summary, Fn fn) {
  return detail::def(name, summary, 1, false, fn);
}

}  // namespace

const std::vector<PresetDef>& world2_defs() {
  static const std::vector<PresetDef> defs = {
      def("world2_turn_static",
          "L- and U-shaped stairs seen from their landing: the flight up rising to the side, the flight "
          "down, the "
          "wearer facing one or turning to it (both labelled; codes' riser and going)",
          turn_static),
      def("world2_low_static",
          "low-riser flights up or down: risers 8-12 cm, goings 30-60 cm, any 2R+T (training stairs, garden "
          "steps)",
          low_static),
      def("world2_steep_static", "steep flights up or down: goings 20-24 cm, risers 18-25 cm, narrow",
          steep_static),
      def("world2_dressed_static",
          "carpeted flights (bull-nosed, pile relief) and shoes, bags and boxes (10-40 cm) on 1-3 treads, up "
          "or down",
          dressed_static),
      def("world2_legs_static",
          "the wearer's own legs and feet at the bottom of a steep view (tilt 50-80 deg) before a flight up "
          "or down",
          legs_static),
      def("world2_lowrig_static",
          "a waist or hip camera (0.5-0.8 m, tilt 15-60 deg) before a flight up or down", lowrig_static),
      def("world2_shelves_static",
          "bookcases and shelving 0.8-2.0 m high, boards every 25-40 cm, ladder shelves; no stairs",
          shelves_static),
      def("world2_boxes_static",
          "2-3 stacked boxes, each smaller than the one below (a stair of boxes); no stairs", boxes_static),
      def("world2_sofa_static",
          "a sofa (seat 38-48 cm, back 75-95 cm) with a coffee table or ottoman; no stairs", sofa_static),
      def("world2_bench_static",
          "a bench 40-50 cm high (slab, block or shoe bench with a low shelf); no stairs", bench_static),
      def("world2_lowtable_static",
          "a low table 35-50 cm (legs, block or a low shelf), rugs, nesting tables; no stairs",
          lowtable_static),
      def("world2_bed_static",
          "a bed (mattress top 30-65 cm), headboard, a bench at the foot on some; no stairs", bed_static),
  };
  return defs;
}

}  // namespace stairguide::synth::detail
