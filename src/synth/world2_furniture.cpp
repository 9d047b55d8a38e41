// The second synthetic world's stair-free furniture (issue 39, labels: none): shelves, stacked
// boxes, a sofa, a bench, a low table and a bed, each drawn from the real range of its kind
// (docs/synthetic.md) and seen by a wearer walking in a room. Registered in world2.cpp.
#include <algorithm>
#include <cmath>

#include "world2_internal.hpp"

namespace stairguide::synth::detail::world2 {
namespace {

// Where a piece of furniture stands, seen by a wearer walking in a room (`view`, drawn first):
// its centre along the heading, 0.6-1.3 times as far as the optical axis meets the floor (at least
// `radius` + 0.4 m, so that it never reaches the wearer, at most 4 m), +-0.3 m to the side.
V3 furniture_in_view(Rng& rng, const WalkerState& view, float radius) {
  const float h = view.T_world_camera.translation().z(),
              tilt = std::max(0.2f, pose_tilt(view.T_world_camera));
  const float d = std::clamp(rng.uniform(0.6f, 1.3f) * h / std::tan(tilt), radius + 0.4f, 4.f);
  const V3 fwd(std::cos(view.yaw), std::sin(view.yaw), 0.f), left(-fwd.y(), fwd.x(), 0.f);
  return view.body + d * fwd + rng.uniform(-0.3f, 0.3f) * left;
}

// Facing the wearer (its front, +x of its frame, turned back along the view's heading) within
// +-`spread` rad.
float facing_wearer(Rng& rng, const WalkerState& view, float spread) {
  return view.yaw + kPi + rng.uniform(-spread, spread);
}

}  // namespace

// Bookcases and open shelving: 0.6-1.2 m wide, 0.25-0.45 m deep, 0.8-2.0 m high, boards every
// 25-40 cm (a book's height and a hand), books on some; one in four a ladder shelf whose boards
// get shallower upwards (a stair's profile, with rises of a shelf's height and floor seen under
// each board).
void shelves_static(Rng& rng, const SynthOptions& o, PresetBuild& b) {
  room(b.scene, rng);
  b.view = chest_view_ahead(rng, o);
  const float W = rng.uniform(0.6f, 1.2f), Dp = rng.uniform(0.25f, 0.45f), H = rng.uniform(0.8f, 2.0f);
  const bool ladder = rng.chance(0.25f);
  std::vector<float> boards;
  for (float h = rng.uniform(0.03f, 0.12f); h < H - 0.15f; h += rng.uniform(0.25f, 0.40f))
    boards.push_back(h);
  boards.push_back(H);
  const Pose T =
      yaw_frame(furniture_in_view(rng, b.view, 0.5f * std::hypot(W, Dp)), facing_wearer(rng, b.view, 0.6f));
  const Material m = rng.chance(0.6f) ? wood_material(rng) : wall_material(rng);
  const float hd = 0.5f * Dp, hw = 0.5f * W, th = rng.uniform(0.018f, 0.025f);
  const std::size_t n = boards.size();
  for (std::size_t i = 0; i < n; ++i) {
    // A ladder shelf's board i is 1 - 0.55 i/(n-1) of the full depth, flush at the back.
    const float dep =
        ladder && n > 1 ? Dp * (1.f - 0.55f * static_cast<float>(i) / static_cast<float>(n - 1)) : Dp;
    b.scene.add_box_in(T, V3(-hd, -hw, boards[i] - th), V3(-hd + dep, hw, boards[i]), m, "shelf_board");
    if (i + 1 < n && rng.chance(0.6f)) {  // a row of books
      const float gap = boards[i + 1] - th - boards[i];
      const float bh = std::min(rng.uniform(0.15f, 0.33f), gap - 0.02f);
      const float y0 = rng.uniform(-hw, hw - 0.1f), y1 = std::min(hw, y0 + rng.uniform(0.1f, 0.6f));
      if (bh > 0.05f)
        b.scene.add_box_in(T, V3(-hd + 0.01f, y0, boards[i]),
                           V3(-hd + std::min(dep, rng.uniform(0.15f, 0.25f)), y1, boards[i] + bh),
                           fabric_material(rng), "books");
    }
  }
  if (ladder) {  // two uprights per side: one at the back, one leaning along the boards' fronts
    for (float side : {-1.f, 1.f}) {
      const float y = side * (hw + 0.015f);
      b.scene.add_box_in(T, V3(-hd, y - 0.015f, 0.f), V3(-hd + 0.04f, y + 0.015f, H), m, "shelf_side");
      b.scene.add_cylinder(T * V3(hd - 0.02f, y, 0.f), T * V3(-hd + 0.45f * Dp, y, H), 0.02f, 0.015f, m,
                           "shelf_side", 8);
    }
  } else {
    for (float side : {-1.f, 1.f})
      b.scene.add_box_in(T, V3(-hd, side * hw, 0.f), V3(hd, side * (hw + th), H), m, "shelf_side");
    if (rng.chance(0.7f)) b.scene.add_box_in(T, V3(-hd - 0.01f, -hw, 0.f), V3(-hd, hw, H), m, "shelf_back");
  }
}

// Stacked boxes in steps: 2-3 moving or storage boxes, each smaller than the one under it, flush
// at the back (a stair of boxes) or centred (a pyramid); a few loose boxes about. Box sizes of
// moving and storage boxes: 30-70 cm wide, 25-60 cm deep, 15-45 cm high.
void boxes_static(Rng& rng, const SynthOptions& o, PresetBuild& b) {
  room(b.scene, rng);
  b.view = chest_view_ahead(rng, o);
  const int n = rng.integer(2, 3);
  float w = rng.uniform(0.35f, 0.7f), d = rng.uniform(0.3f, 0.6f), h = rng.uniform(0.2f, 0.45f);
  const bool flush_back = rng.chance(0.6f);
  const Pose T =
      yaw_frame(furniture_in_view(rng, b.view, 0.5f * std::hypot(w, d)), facing_wearer(rng, b.view, 0.8f));
  const float back = -0.5f * d;  // the bottom box is centred on the frame; its front faces +x
  float z = 0.f;
  for (int i = 0; i < n; ++i) {
    const float x0 = flush_back ? back : -0.5f * d + rng.uniform(-0.02f, 0.02f);
    b.scene.add_box_in(T, V3(x0, -0.5f * w, z), V3(x0 + d, 0.5f * w, z + h), cardboard(rng), "box");
    z += h;
    // The next one up: smaller, and its own height.
    d *= rng.uniform(0.5f, 0.85f);
    w *= rng.uniform(0.7f, 1.0f);
    h = rng.uniform(0.15f, 0.40f);
  }
  for (int i = 0, loose = rng.integer(0, 2); i < loose; ++i) {
    const V3 size(rng.uniform(0.25f, 0.5f), rng.uniform(0.25f, 0.5f), rng.uniform(0.15f, 0.45f));
    add_crate(b.scene, V3(rng.uniform(0.8f, 3.5f), rng.uniform(-2.5f, 2.5f), 0.f), rng.uniform(-kPi, kPi),
              size, cardboard(rng), "box");
  }
}

// A sofa from the ranges of real ones: 1.5-2.4 m long, seat 38-48 cm high and 50-65 cm deep,
// 80-100 cm deep overall, back 75-95 cm, arms 55-70 cm high and 10-25 cm wide, on feet 0-15 cm;
// half the time a coffee table (35-48 cm) or an ottoman in front.
void sofa_static(Rng& rng, const SynthOptions& o, PresetBuild& b) {
  room(b.scene, rng);
  b.view = chest_view_ahead(rng, o);
  const float L = rng.uniform(1.5f, 2.4f), seat = rng.uniform(0.38f, 0.48f),
              seat_d = rng.uniform(0.5f, 0.65f);
  const float depth = std::max(seat_d + 0.15f, rng.uniform(0.8f, 1.0f)), back = rng.uniform(0.75f, 0.95f);
  const float arm_h = rng.uniform(0.55f, 0.70f), arm_w = rng.uniform(0.10f, 0.25f),
              feet = rng.uniform(0.f, 0.15f);
  // The radius takes in a table or ottoman in front (up to 1.2 m before the sofa's front).
  const V3 c = furniture_in_view(rng, b.view, std::max(0.5f * std::hypot(L, depth), 0.5f * depth + 1.2f));
  const float yaw = facing_wearer(rng, b.view, 0.7f);
  const Pose T = yaw_frame(c, yaw);  // front at x = +depth/2
  const Material m = fabric_material(rng);
  const float hx = 0.5f * depth, hl = 0.5f * L, base = std::max(feet, 0.02f);
  b.scene.add_box_in(T, V3(-hx, -hl + arm_w, base), V3(hx, hl - arm_w, seat), m, "sofa");
  b.scene.add_box_in(T, V3(-hx, -hl + arm_w, seat), V3(-hx + (depth - seat_d), hl - arm_w, back), m,
                     "sofa_back");
  for (float side : {-1.f, 1.f})
    b.scene.add_box_in(T, V3(-hx, side > 0 ? hl - arm_w : -hl, base),
                       V3(hx, side > 0 ? hl : -hl + arm_w, arm_h), m, "sofa_arm");
  if (feet > 0.02f) {
    const Material f = rng.chance(0.5f) ? wood_material(rng) : metal_material(rng);
    for (float i : {-1.f, 1.f})
      for (float j : {-1.f, 1.f})
        b.scene.add_box_in(T, V3(i * (hx - 0.05f) - 0.025f, j * (hl - 0.05f) - 0.025f, 0.f),
                           V3(i * (hx - 0.05f) + 0.025f, j * (hl - 0.05f) + 0.025f, feet), f, "sofa_foot");
  }
  if (rng.chance(0.5f)) {
    const float gap = rng.uniform(0.3f, 0.5f);
    if (rng.chance(0.5f)) {  // a coffee table
      const float tl = rng.uniform(0.8f, 1.3f), td = rng.uniform(0.5f, 0.7f);
      add_table(b.scene, T * V3(hx + gap + 0.5f * td, 0.f, 0.f), yaw + 0.5f * kPi, rng.uniform(0.35f, 0.48f),
                tl, td, rng);
    } else {  // an ottoman
      const V3 size(rng.uniform(0.4f, 0.7f), rng.uniform(0.4f, 0.9f), rng.uniform(0.35f, 0.45f));
      b.scene.add_box_in(T, V3(hx + gap, -0.5f * size.y(), 0.f),
                         V3(hx + gap + size.x(), 0.5f * size.y(), size.z()), m, "ottoman");
    }
  }
}

// Benches: 40-50 cm high, 30-45 cm deep, 0.9-2.0 m long: a slab on legs, a solid block, or a
// shoe bench with a shelf 12-25 cm up; seen from any side.
void bench_static(Rng& rng, const SynthOptions& o, PresetBuild& b) {
  room(b.scene, rng);
  b.view = chest_view_ahead(rng, o);
  const float h = rng.uniform(0.40f, 0.50f), dep = rng.uniform(0.30f, 0.45f), len = rng.uniform(0.9f, 2.0f);
  const Pose T =
      yaw_frame(furniture_in_view(rng, b.view, 0.5f * std::hypot(len, dep)), rng.uniform(-kPi, kPi));
  const Material m = rng.chance(0.5f) ? wood_material(rng) : concrete_material(rng);
  const float hl = 0.5f * len, hd = 0.5f * dep, slab = rng.uniform(0.03f, 0.06f);
  const int kind = rng.integer(0, 2);
  if (kind == 1) {
    b.scene.add_box_in(T, V3(-hl, -hd, 0.f), V3(hl, hd, h), m, "bench");
  } else {
    b.scene.add_box_in(T, V3(-hl, -hd, h - slab), V3(hl, hd, h), m, "bench");
    for (float side : {-1.f, 1.f}) {
      const float x = side * (hl - 0.08f);
      b.scene.add_box_in(T, V3(x - 0.03f, -hd + 0.02f, 0.f), V3(x + 0.03f, hd - 0.02f, h - slab), m,
                         "bench_leg");
    }
    if (kind == 2) {
      const float shelf = rng.uniform(0.12f, 0.25f);
      b.scene.add_box_in(T, V3(-hl + 0.11f, -hd + 0.02f, shelf - 0.02f), V3(hl - 0.11f, hd - 0.02f, shelf), m,
                         "bench_shelf");
      for (int i = 0, shoes = rng.integer(0, 3); i < shoes; ++i) {  // a pair of shoes on the shelf
        const float x = rng.uniform(-hl + 0.2f, hl - 0.35f);
        const Material sm = fabric_material(rng);
        for (float dx : {0.f, 0.11f})
          b.scene.add_box_in(T, V3(x + dx, -0.13f, shelf),
                             V3(x + dx + 0.09f, 0.13f, shelf + rng.uniform(0.07f, 0.12f)), sm, "shoe");
      }
    }
  }
}

// Low tables: coffee tables 35-50 cm high, 0.8-1.4 x 0.5-0.8 m, on legs, solid, or with a shelf
// 8-20 cm up; a rug under some; a smaller nesting table beside some. Seen from any side.
void lowtable_static(Rng& rng, const SynthOptions& o, PresetBuild& b) {
  room(b.scene, rng);
  b.view = chest_view_ahead(rng, o);
  const float h = rng.uniform(0.35f, 0.50f), len = rng.uniform(0.8f, 1.4f), dep = rng.uniform(0.5f, 0.8f);
  const float hl = 0.5f * len, hd = 0.5f * dep;
  const bool rug = rng.chance(0.4f);  // a rug, 1 cm thick
  const float rl = rug ? rng.uniform(1.6f, 2.4f) : 0.f, rd = rug ? rng.uniform(1.2f, 1.8f) : 0.f;
  const bool nesting = rng.chance(0.25f);  // a smaller, lower nesting table beside it
  const float h2 = h - rng.uniform(0.05f, 0.12f), s2 = rng.uniform(0.4f, 0.55f);
  const float radius =
      std::max({std::hypot(hl + (nesting ? 0.05f + s2 : 0.f), hd), 0.5f * std::hypot(rl, rd)});
  const Pose T = yaw_frame(furniture_in_view(rng, b.view, radius), rng.uniform(-kPi, kPi));
  if (rug)
    b.scene.add_box_in(T, V3(-0.5f * rl, -0.5f * rd, 0.f), V3(0.5f * rl, 0.5f * rd, 0.01f),
                       fabric_material(rng), "rug");
  const float base = rug ? 0.01f : 0.f;
  const Material m = wood_material(rng);
  const int kind = rng.integer(0, 4);  // 0-2 legs, 3 solid, 4 legs and a shelf
  const float top = rng.uniform(0.02f, 0.05f);
  if (kind == 3) {
    b.scene.add_box_in(T, V3(-hl, -hd, base), V3(hl, hd, h), m, "table");
  } else {
    b.scene.add_box_in(T, V3(-hl, -hd, h - top), V3(hl, hd, h), m, "table");
    const float leg = rng.uniform(0.04f, 0.06f);
    for (float i : {-1.f, 1.f})
      for (float j : {-1.f, 1.f})
        b.scene.add_box_in(T, V3(i * (hl - 0.05f) - 0.5f * leg, j * (hd - 0.05f) - 0.5f * leg, base),
                           V3(i * (hl - 0.05f) + 0.5f * leg, j * (hd - 0.05f) + 0.5f * leg, h - top), m,
                           "table_leg");
    if (kind == 4) {
      const float shelf = rng.uniform(0.08f, 0.20f);
      b.scene.add_box_in(T, V3(-hl + 0.05f, -hd + 0.05f, shelf - 0.02f), V3(hl - 0.05f, hd - 0.05f, shelf), m,
                         "table_shelf");
    }
  }
  if (nesting) {
    const float x = hl + 0.05f + 0.5f * s2;
    b.scene.add_box_in(T, V3(x - 0.5f * s2, -0.5f * s2, h2 - 0.02f), V3(x + 0.5f * s2, 0.5f * s2, h2), m,
                       "table");
    for (float i : {-1.f, 1.f})
      for (float j : {-1.f, 1.f})
        b.scene.add_box_in(
            T, V3(x + i * (0.5f * s2 - 0.03f) - 0.015f, j * (0.5f * s2 - 0.03f) - 0.015f, base),
            V3(x + i * (0.5f * s2 - 0.03f) + 0.015f, j * (0.5f * s2 - 0.03f) + 0.015f, h2 - 0.02f), m,
            "table_leg");
  }
}

// Beds: 1.9-2.2 m long, 0.9-1.9 m wide (single to king), a base 15-35 cm high under a mattress
// 15-30 cm thick set 0-5 cm in from the base's edges; a headboard on most, pillows; a bench at
// the foot (40-50 cm) on some, a bedside table (45-65 cm) on half. Seen from the foot or a side.
void bed_static(Rng& rng, const SynthOptions& o, PresetBuild& b) {
  room(b.scene, rng);
  b.view = chest_view_ahead(rng, o);
  const float L = rng.uniform(1.9f, 2.2f), W = rng.uniform(0.9f, 1.9f);
  const float base_h = rng.uniform(0.15f, 0.35f), mat_h = rng.uniform(0.15f, 0.30f),
              inset = rng.uniform(0.f, 0.05f);
  const bool foot_bench = rng.chance(0.3f);
  const Pose T =
      yaw_frame(furniture_in_view(rng, b.view, 0.5f * std::hypot(L + (foot_bench ? 0.5f : 0.f), W + 1.f)),
                rng.uniform(-kPi, kPi));  // foot at +x
  const float hl = 0.5f * L, hw = 0.5f * W;
  const Material frame = rng.chance(0.5f) ? wood_material(rng) : fabric_material(rng);
  Material mattress = fabric_material(rng);
  mattress.albedo = V3(0.75f, 0.75f, 0.78f) * rng.uniform(0.8f, 1.1f);
  b.scene.add_box_in(T, V3(-hl, -hw, 0.f), V3(hl, hw, base_h), frame, "bed");
  const float top = base_h + mat_h;
  b.scene.add_box_in(T, V3(-hl + inset, -hw + inset, base_h), V3(hl - inset, hw - inset, top), mattress,
                     "mattress");
  if (rng.chance(0.7f))
    b.scene.add_box_in(T, V3(-hl - rng.uniform(0.04f, 0.1f), -hw, 0.f), V3(-hl, hw, rng.uniform(0.9f, 1.3f)),
                       frame, "headboard");
  for (float side : {-1.f, 1.f})
    if (W > 1.2f || side < 0.f) {
      const float y = W > 1.2f ? side * 0.5f * hw : 0.f;
      b.scene.add_box_in(T, V3(-hl + inset + 0.05f, y - 0.3f, top),
                         V3(-hl + inset + 0.45f, y + 0.3f, top + 0.12f), mattress, "pillow");
    }
  if (foot_bench) {
    const float bh = rng.uniform(0.40f, 0.50f), bd = rng.uniform(0.35f, 0.45f),
                bl = W * rng.uniform(0.7f, 1.0f);
    const float x0 = hl + rng.uniform(0.f, 0.1f);
    b.scene.add_box_in(T, V3(x0, -0.5f * bl, 0.f), V3(x0 + bd, 0.5f * bl, bh), frame, "bench");
  }
  if (rng.chance(0.5f)) {
    const float s = rng.uniform(0.4f, 0.5f), th = rng.uniform(0.45f, 0.65f);
    const float side = rng.chance(0.5f) ? 1.f : -1.f;
    b.scene.add_box_in(T, V3(-hl, side * (hw + 0.05f), 0.f), V3(-hl + s, side * (hw + 0.05f + s), th),
                       wood_material(rng), "bedside_table");
  }
}

}  // namespace stairguide::synth::detail::world2
