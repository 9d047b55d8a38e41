// Scene building blocks. Staircases are built in a "base" frame B: the stair frame S of
// ground_truth.hpp moved down to the floor before the first edge (x left, y up, z forward, z = 0
// at the first edge), so every height below reads as height above that floor. Solid stairs are
// columns standing on the floor (one per tread), which leaves no crack between a tread and the
// riser above it, whatever the rasterisation rounding.
#include "stairguide/synth/builders.hpp"

#include <algorithm>
#include <cmath>

namespace stairguide::synth {
namespace {

using V3 = Eigen::Vector3f;

Eigen::Vector3f jitter(Rng& rng, Eigen::Vector3f bgr, float amount) {
  for (int i = 0; i < 3; ++i)
    bgr[i] = std::clamp(bgr[i] * (1.f + rng.uniform(-amount, amount)), 0.02f, 0.98f);
  return bgr;
}

Material mat(Rng& rng, Eigen::Vector3f bgr, Texture t, float contrast, float texel = 0.005f) {
  Material m;
  m.albedo = jitter(rng, bgr, 0.12f);
  m.texture = t;
  m.contrast = contrast * rng.uniform(0.8f, 1.2f);
  m.texel_m = texel;
  return m;
}

// Pose of a frame whose x axis points along `yaw` (world), z up, origin at p.
Pose yaw_pose(const V3& p, float yaw) {
  Pose T = Pose::Identity();
  T.linear() = Eigen::AngleAxisf(yaw, V3::UnitZ()).toRotationMatrix();
  T.translation() = p;
  return T;
}

}  // namespace

std::uint64_t mix_seed(std::uint64_t a, std::uint64_t b, std::uint64_t c) {
  Rng r(a * 0x9E3779B97F4A7C15ull ^ (b + 0x632BE59BD9B4E019ull) * 0xD6E8FEB86659FD93ull ^
        (c + 0x85157AF5ull) * 0xA0761D6478BD642Full);
  r.next();
  return r.next();
}

Material floor_material(Rng& rng) {
  switch (rng.integer(0, 2)) {
    case 0: return mat(rng, V3(0.55f, 0.60f, 0.65f), Texture::kTiles, 0.35f);
    case 1: return mat(rng, V3(0.35f, 0.30f, 0.45f), Texture::kCarpet, 0.45f, 0.004f);
    default: return mat(rng, V3(0.50f, 0.52f, 0.52f), Texture::kConcrete, 0.4f);
  }
}
Material wall_material(Rng& rng) {
  const V3 palettes[3] = {V3(0.80f, 0.82f, 0.85f), V3(0.60f, 0.75f, 0.80f), V3(0.75f, 0.70f, 0.60f)};
  return mat(rng, palettes[rng.integer(0, 2)], Texture::kPlain, 0.25f, 0.008f);
}
Material stair_material(Rng& rng) {
  switch (rng.integer(0, 3)) {
    case 0: return mat(rng, V3(0.25f, 0.40f, 0.60f), Texture::kWood, 0.35f, 0.004f);
    case 1: return mat(rng, V3(0.55f, 0.56f, 0.56f), Texture::kConcrete, 0.4f);
    case 2: return mat(rng, V3(0.50f, 0.55f, 0.60f), Texture::kTiles, 0.3f);
    default: return mat(rng, V3(0.30f, 0.25f, 0.40f), Texture::kCarpet, 0.45f, 0.004f);
  }
}
Material wood_material(Rng& rng) { return mat(rng, V3(0.20f, 0.35f, 0.55f), Texture::kWood, 0.35f, 0.004f); }
Material fabric_material(Rng& rng) {
  const V3 palettes[3] = {V3(0.55f, 0.30f, 0.20f), V3(0.25f, 0.45f, 0.30f), V3(0.30f, 0.30f, 0.60f)};
  return mat(rng, palettes[rng.integer(0, 2)], Texture::kFabric, 0.3f, 0.003f);
}
Material metal_material(Rng& rng) { return mat(rng, V3(0.60f, 0.60f, 0.62f), Texture::kPlain, 0.1f, 0.01f); }
Material concrete_material(Rng& rng) { return mat(rng, V3(0.55f, 0.56f, 0.56f), Texture::kConcrete, 0.4f); }

Pose stair_pose(float x, float y, float yaw, float edge_z) {
  Pose T = Pose::Identity();
  Eigen::Matrix3f R;
  R.col(2) = V3(std::cos(yaw), std::sin(yaw), 0.f);  // z_S: direction of travel
  R.col(1) = V3::UnitZ();                            // y_S: up
  R.col(0) = R.col(1).cross(R.col(2));               // x_S: to the user's left
  T.linear() = R;
  T.translation() = V3(x, y, edge_z);
  return T;
}

int add_staircase(Scene& scene, const StairParams& p, Rng& rng) {
  const int id = static_cast<int>(scene.stairs.size());
  StairSpec spec;
  spec.id = id;
  spec.kind = p.kind;
  spec.steps = (p.kind == StairKind::kSingleStep || p.kind == StairKind::kCurb) ? 1 : std::max(1, p.steps);
  spec.riser_m = p.riser_m;
  spec.tread_m = p.tread_m;
  spec.width_m = p.width_m;
  spec.open_risers = p.open_risers;
  spec.nosing_m = p.nosing_m;
  spec.down = p.kind == StairKind::kDescending || (p.kind == StairKind::kCurb && p.down);
  spec.T_world_stair = p.T_world_stair;
  spec.base_z = p.base_z;
  scene.stairs.push_back(spec);

  const int N = spec.steps;
  const float r = p.riser_m, t = p.tread_m, w = p.width_m, hw = 0.5f * w, n = std::max(0.f, p.nosing_m);
  const float s = n > 0.f ? 0.03f : 0.f;  // nosed treads are slabs this thick
  const float origin_h = spec.down ? 0.f : r;
  Pose T_wb = p.T_world_stair;
  T_wb.translation() = p.T_world_stair * V3(0.f, -origin_h, 0.f);
  const Material tread_m = stair_material(rng);
  Material riser_m = tread_m;
  riser_m.albedo = jitter(rng, tread_m.albedo * 0.9f, 0.05f);
  const Material wall_m = wall_material(rng);
  const Material rail_m = metal_material(rng);
  auto box = [&](V3 lo, V3 hi, const Material& m, const char* label, int tread = 0) {
    scene.add_box_in(T_wb, lo, hi, m, label, tread > 0 ? id : -1, tread);
  };
  // Along-the-slope prism between two points of frame B.
  auto beam = [&](V3 a, V3 b, float radius, const Material& m, const char* label) {
    scene.add_cylinder(T_wb * a, T_wb * b, radius, radius, m, label, 8);
  };
  const float top_z0 = static_cast<float>(N - 1) * t;  // where the last tread (landing) begins
  const float top_end = top_z0 + p.top_depth_m;

  if (p.kind == StairKind::kSingleStep || (p.kind == StairKind::kCurb && !p.down)) {
    box(V3(-hw, 0.f, 0.f), V3(hw, r, t), tread_m, p.kind == StairKind::kCurb ? "curb" : "single_step", 1);
    return id;
  }
  if (p.kind == StairKind::kCurb) {  // down: the user's level ends, the lower ground lies beyond
    if (p.build_floor) box(V3(-hw, -r - 0.3f, -8.f), V3(hw, 0.f, 0.f), floor_material(rng), "floor");
    box(V3(-hw, -r - 0.3f, 0.f), V3(hw, -r, t), concrete_material(rng), "road", 1);
    return id;
  }

  const float dir = spec.down ? -1.f : 1.f;
  const float total = static_cast<float>(N) * r;
  if (!spec.down) {
    if (!p.open_risers) {
      for (int k = 1; k <= N; ++k) {
        const float z0 = static_cast<float>(k - 1) * t;
        const float z1 = k < N ? static_cast<float>(k) * t : top_end;
        const float y = static_cast<float>(k) * r;
        if (s > 0.f) {
          box(V3(-hw, 0.f, z0 + n), V3(hw, y - s, z1 + n), riser_m, "riser");
          box(V3(-hw, y - s, z0), V3(hw, y, z1 + n), tread_m, "tread", k);
        } else {
          box(V3(-hw, 0.f, z0), V3(hw, y, z1), tread_m, "tread", k);
        }
      }
    } else {
      const float th = 0.04f;
      for (int k = 1; k < N; ++k) {
        const float z0 = static_cast<float>(k - 1) * t;
        const float y = static_cast<float>(k) * r;
        box(V3(-hw, y - th, z0), V3(hw, y, z0 + t + 0.03f), tread_m, "tread", k);
      }
      box(V3(-hw, total - 0.2f, top_z0), V3(hw, total, top_end), tread_m, "landing", N);
      box(V3(-hw, 0.f, top_z0 + 0.6f), V3(hw, total - 0.2f, top_end), wall_m, "landing_support");
      // Stringers under the tread ends, along the slope 12 cm below the nosing line.
      const float z_start = std::min(-0.02f, (0.12f - r) * t / r);
      for (int side = -1; side <= 1; side += 2) {
        const float x = static_cast<float>(side) * (hw + 0.03f);
        beam(V3(x, r + z_start * r / t - 0.12f, z_start), V3(x, r + top_z0 * r / t - 0.12f, top_z0), 0.05f,
             rail_m, "stringer");
      }
    }
  } else {
    if (p.build_floor) {
      const Material fm = floor_material(rng);
      if (s > 0.f) {
        box(V3(-6.f, -total, -8.f), V3(6.f, -s, -n), riser_m, "floor_edge");
        box(V3(-6.f, -s, -8.f), V3(6.f, 0.f, 0.f), fm, "floor");
      } else {
        box(V3(-6.f, -total, -8.f), V3(6.f, 0.f, p.open_risers ? 0.f : -n), fm, "floor");
      }
      if (p.side_walls) {
        for (int side = -1; side <= 1; side += 2) {
          const float xa = static_cast<float>(side) * hw, xb = static_cast<float>(side) * 6.f;
          box(V3(std::min(xa, xb), -total, -n), V3(std::max(xa, xb), 0.f, top_z0 + 4.f), fm, "floor");
        }
      }
      // The lower floor, the flight's last tread, runs on under the upper floor: beside an
      // open-sided flight it is seen below the upper floor's edge (no bottomless void there, and no
      // slab edge standing in one that would count as a wall).
      const Material lower_m = floor_material(rng);
      box(V3(-6.f, -total - 0.2f, top_z0 - n), V3(6.f, -total, top_z0 + 8.f), lower_m, "lower_floor", N);
      box(V3(-6.f, -total - 0.2f, -8.f), V3(6.f, -total, top_z0 - n), lower_m, "floor");
    }
    if (!p.open_risers) {
      for (int k = 1; k < N; ++k) {
        const float z0 = static_cast<float>(k - 1) * t;
        const float y = -static_cast<float>(k) * r;
        if (s > 0.f) {
          box(V3(-hw, -total, z0 - n), V3(hw, y - s, z0 + t - n), riser_m, "riser");
          box(V3(-hw, y - s, z0 - n), V3(hw, y, z0 + t), tread_m, "tread", k);
        } else {
          box(V3(-hw, -total, z0), V3(hw, y, z0 + t), tread_m, "tread", k);
        }
      }
    } else {
      const float th = 0.04f;
      for (int k = 1; k < N; ++k) {
        const float z0 = static_cast<float>(k - 1) * t;
        const float y = -static_cast<float>(k) * r;
        box(V3(-hw, y - th, z0 - 0.03f), V3(hw, y, z0 + t), tread_m, "tread", k);
      }
      for (int side = -1; side <= 1; side += 2) {
        const float x = static_cast<float>(side) * (hw - 0.03f);
        beam(V3(x, -0.12f - 0.5f * r, 0.f), V3(x, -total + 0.05f, top_z0 + 0.2f), 0.05f, rail_m, "stringer");
      }
    }
  }

  if (p.side_walls && !spec.down) {
    for (int side = -1; side <= 1; side += 2) {
      const float xa = static_cast<float>(side) * hw, xb = static_cast<float>(side) * (hw + 0.12f);
      box(V3(std::min(xa, xb), 0.f, p.wall_start_m), V3(std::max(xa, xb), total + 2.4f, top_end), wall_m,
          "wall");
    }
  }
  if (p.handrails) {
    // Rail 0.9 m above the nosing line; posts on open sides.
    const float inset = p.side_walls ? 0.06f : 0.04f;
    for (int side = -1; side <= 1; side += 2) {
      const float x = static_cast<float>(side) * (hw - inset);
      const float za = spec.down ? -0.4f : -0.3f, zb = top_z0 + 0.3f;
      auto nose_y = [&](float z) {
        const float zz = std::clamp(z, 0.f, top_z0);
        return spec.down ? -zz * r / t : r + zz * r / t;
      };
      beam(V3(x, nose_y(za) + 0.9f, za), V3(x, nose_y(0.f) + 0.9f, 0.f), 0.022f, rail_m, "handrail");
      beam(V3(x, nose_y(0.f) + 0.9f, 0.f), V3(x, nose_y(top_z0) + 0.9f, top_z0), 0.022f, rail_m, "handrail");
      beam(V3(x, nose_y(top_z0) + 0.9f, top_z0), V3(x, nose_y(zb) + 0.9f, zb), 0.022f, rail_m, "handrail");
      if (!p.side_walls) {
        for (int k = 1; k <= N; k += 2) {
          const float z = static_cast<float>(k - 1) * t + 0.5f * t;
          const float y = dir * static_cast<float>(k) * r;  // on tread k
          beam(V3(x, y, z), V3(x, nose_y(z) + 0.9f, z), 0.018f, rail_m, "handrail_post");
        }
      }
    }
  }
  return id;
}

void add_room_walls(Scene& scene, const Eigen::Vector2f& lo, const Eigen::Vector2f& hi, float floor_z,
                    float height, const Material& m) {
  const float th = 0.15f, z0 = floor_z, z1 = floor_z + height;
  scene.add_box_world(V3(lo.x() - th, lo.y() - th, z0), V3(lo.x(), hi.y() + th, z1), m, "wall");
  scene.add_box_world(V3(hi.x(), lo.y() - th, z0), V3(hi.x() + th, hi.y() + th, z1), m, "wall");
  scene.add_box_world(V3(lo.x(), lo.y() - th, z0), V3(hi.x(), lo.y(), z1), m, "wall");
  scene.add_box_world(V3(lo.x(), hi.y(), z0), V3(hi.x(), hi.y() + th, z1), m, "wall");
}

void add_door(Scene& scene, const V3& p, float yaw, Rng& rng) {
  const Pose T = yaw_pose(p, yaw);  // x: out of the wall into the room, y: along the wall
  Material panel = rng.chance(0.5f) ? wood_material(rng) : wall_material(rng);
  panel.albedo *= 0.8f;
  scene.add_box_in(T, V3(0.f, -0.45f, 0.f), V3(0.03f, 0.45f, 2.0f), panel, "door");
  const Material frame = metal_material(rng);
  scene.add_box_in(T, V3(0.f, -0.52f, 0.f), V3(0.05f, -0.45f, 2.07f), frame, "door_frame");
  scene.add_box_in(T, V3(0.f, 0.45f, 0.f), V3(0.05f, 0.52f, 2.07f), frame, "door_frame");
  scene.add_box_in(T, V3(0.f, -0.45f, 2.0f), V3(0.05f, 0.45f, 2.07f), frame, "door_frame");
  scene.add_box_in(T, V3(0.03f, 0.3f, 0.95f), V3(0.08f, 0.4f, 1.0f), frame, "door_handle");
}

void add_person(Scene& scene, const V3& feet, float yaw, float height_m, Rng& rng) {
  const float H = height_m;
  const V3 left(-std::sin(yaw), std::cos(yaw), 0.f);
  Material trousers = fabric_material(rng);
  trousers.albedo *= 0.6f;
  const Material shirt = fabric_material(rng);
  Material skin;
  skin.albedo = jitter(rng, V3(0.45f, 0.55f, 0.75f), 0.3f);
  skin.texture = Texture::kPlain;
  skin.contrast = 0.1f;
  const float leg = 0.47f * H, torso = 0.30f * H;
  for (int side = -1; side <= 1; side += 2) {
    const V3 hip = feet + 0.09f * static_cast<float>(side) * left;
    scene.add_cylinder(hip, hip + V3(0.f, 0.f, leg), 0.07f, 0.07f, trousers, "person", 10);
    const V3 sh = feet + 0.22f * static_cast<float>(side) * left + V3(0.f, 0.f, leg + torso - 0.02f);
    scene.add_cylinder(sh - V3(0.f, 0.f, 0.33f * H), sh, 0.045f, 0.045f, shirt, "person", 8);
  }
  scene.add_cylinder(feet + V3(0.f, 0.f, leg - 0.03f), feet + V3(0.f, 0.f, leg + torso), 0.17f, 0.17f, shirt,
                     "person", 14);
  const float neck = leg + torso;
  scene.add_cylinder(feet + V3(0.f, 0.f, neck), feet + V3(0.f, 0.f, neck + 0.05f), 0.05f, 0.05f, skin,
                     "person", 8);
  scene.add_cylinder(feet + V3(0.f, 0.f, neck + 0.05f), feet + V3(0.f, 0.f, H), 0.095f, 0.095f, skin,
                     "person", 12);
}

void add_table(Scene& scene, const V3& c, float yaw, float height, float length, float depth, Rng& rng) {
  const Pose T = yaw_pose(c, yaw);
  const Material top = wood_material(rng);
  const Material leg = rng.chance(0.5f) ? metal_material(rng) : top;
  const float hl = 0.5f * length, hd = 0.5f * depth;
  scene.add_box_in(T, V3(-hl, -hd, height - 0.03f), V3(hl, hd, height), top, "table");
  for (int i = -1; i <= 1; i += 2)
    for (int j = -1; j <= 1; j += 2) {
      const float x = static_cast<float>(i) * (hl - 0.06f), y = static_cast<float>(j) * (hd - 0.06f);
      scene.add_box_in(T, V3(x - 0.025f, y - 0.025f, 0.f), V3(x + 0.025f, y + 0.025f, height - 0.03f), leg,
                       "table_leg");
    }
}

void add_chair(Scene& scene, const V3& c, float yaw, Rng& rng) {
  const Pose T = yaw_pose(c, yaw);  // the chair faces +x
  const Material m = rng.chance(0.5f) ? wood_material(rng) : fabric_material(rng);
  const float seat = rng.uniform(0.43f, 0.47f);
  scene.add_box_in(T, V3(-0.22f, -0.22f, seat - 0.04f), V3(0.22f, 0.22f, seat), m, "chair");
  scene.add_box_in(T, V3(-0.24f, -0.22f, seat), V3(-0.20f, 0.22f, seat + 0.45f), m, "chair");
  for (int i = -1; i <= 1; i += 2)
    for (int j = -1; j <= 1; j += 2) {
      const float x = static_cast<float>(i) * 0.19f, y = static_cast<float>(j) * 0.19f;
      scene.add_box_in(T, V3(x - 0.02f, y - 0.02f, 0.f), V3(x + 0.02f, y + 0.02f, seat - 0.04f), m,
                       "chair_leg");
    }
}

void add_bench(Scene& scene, const V3& c, float yaw, float height, float length, Rng& rng) {
  const Pose T = yaw_pose(c, yaw);  // long axis along x
  const Material m = rng.chance(0.5f) ? wood_material(rng) : concrete_material(rng);
  const float hl = 0.5f * length, hd = rng.uniform(0.17f, 0.22f);
  scene.add_box_in(T, V3(-hl, -hd, height - 0.05f), V3(hl, hd, height), m, "bench");
  for (int i = -1; i <= 1; i += 2) {
    const float x = static_cast<float>(i) * (hl - 0.12f);
    scene.add_box_in(T, V3(x - 0.03f, -hd + 0.02f, 0.f), V3(x + 0.03f, hd - 0.02f, height - 0.05f), m,
                     "bench_leg");
  }
}

void add_shelves(Scene& scene, const V3& c, float yaw, float width, float depth,
                 const std::vector<float>& boards, Rng& rng) {
  const Pose T = yaw_pose(c, yaw);  // open side faces +x
  const Material m = wood_material(rng);
  const float hw = 0.5f * width, hd = 0.5f * depth;
  const float top = boards.empty() ? 1.f : boards.back() + 0.02f;
  scene.add_box_in(T, V3(-hd, -hw - 0.02f, 0.f), V3(hd, -hw, top), m, "shelf_side");
  scene.add_box_in(T, V3(-hd, hw, 0.f), V3(hd, hw + 0.02f, top), m, "shelf_side");
  scene.add_box_in(T, V3(-hd - 0.01f, -hw, 0.f), V3(-hd, hw, top), m, "shelf_back");
  for (float b : boards) scene.add_box_in(T, V3(-hd, -hw, b - 0.02f), V3(hd, hw, b), m, "shelf_board");
  // A few objects on the boards.
  for (std::size_t i = 0; i + 1 < boards.size(); ++i) {
    if (!rng.chance(0.6f)) continue;
    const float y = rng.uniform(-hw + 0.1f, hw - 0.2f),
                hgt = std::min(0.12f, boards[i + 1] - boards[i] - 0.05f);
    if (hgt > 0.03f)
      scene.add_box_in(T, V3(-hd + 0.05f, y, boards[i]), V3(hd - 0.05f, y + 0.1f, boards[i] + hgt),
                       fabric_material(rng), "shelf_item");
  }
}

void add_sofa(Scene& scene, const V3& c, float yaw, float seat, Rng& rng) {
  const Pose T = yaw_pose(c, yaw);  // faces +x
  const Material m = fabric_material(rng);
  const float hl = rng.uniform(0.8f, 1.1f);
  scene.add_box_in(T, V3(-0.45f, -hl, 0.08f), V3(0.45f, hl, seat), m, "sofa");
  scene.add_box_in(T, V3(-0.45f, -hl, seat), V3(-0.25f, hl, seat + 0.4f), m, "sofa_back");
  for (int i = -1; i <= 1; i += 2) {
    const float y = static_cast<float>(i) * hl;
    scene.add_box_in(T, V3(-0.45f, std::min(y, y - 0.18f * static_cast<float>(i)), 0.08f),
                     V3(0.45f, std::max(y, y - 0.18f * static_cast<float>(i)), seat + 0.18f), m, "sofa_arm");
  }
  const Material f = metal_material(rng);
  for (int i = -1; i <= 1; i += 2)
    for (int j = -1; j <= 1; j += 2)
      scene.add_box_in(
          T, V3(0.4f * static_cast<float>(i) - 0.03f, (hl - 0.05f) * static_cast<float>(j) - 0.03f, 0.f),
          V3(0.4f * static_cast<float>(i) + 0.03f, (hl - 0.05f) * static_cast<float>(j) + 0.03f, 0.08f), f,
          "sofa_foot");
}

void add_crate(Scene& scene, const V3& c, float yaw, const V3& size, const Material& m,
               const std::string& label) {
  scene.add_box_in(yaw_pose(c, yaw), V3(-0.5f * size.x(), -0.5f * size.y(), 0.f),
                   V3(0.5f * size.x(), 0.5f * size.y(), size.z()), m, label);
}

}  // namespace stairguide::synth
