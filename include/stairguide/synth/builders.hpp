#pragma once
/// \file builders.hpp
/// Building blocks of the synthetic scenes: a portable seeded random generator, staircases
/// (ascending, descending, open risers, nosings, landings, side walls, handrails), single steps,
/// curbs, rooms, doors, furniture and people.

#include <cmath>
#include <cstdint>

#include "stairguide/synth/scene.hpp"

namespace stairguide::synth {

/// SplitMix64: tiny, portable (same numbers on every platform, unlike std distributions).
class Rng {
 public:
  explicit Rng(std::uint64_t seed) : s_(seed) {}
  std::uint64_t next() {
    std::uint64_t z = (s_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  /// Uniform in [0, 1).
  float uniform() { return static_cast<float>(next() >> 40) * (1.f / 16777216.f); }
  float uniform(float a, float b) { return a + (b - a) * uniform(); }
  /// Uniform integer in [a, b].
  int integer(int a, int b) { return a + static_cast<int>(next() % static_cast<std::uint64_t>(b - a + 1)); }
  bool chance(float p) { return uniform() < p; }
  float normal() {
    const float u1 = (static_cast<float>(next() >> 40) + 1.f) * (1.f / 16777217.f);
    const float u2 = uniform();
    return std::sqrt(-2.f * std::log(u1)) * std::cos(6.2831853f * u2);
  }

 private:
  std::uint64_t s_;
};

/// Mixes values into one 64-bit seed (for per-frame and per-purpose streams).
std::uint64_t mix_seed(std::uint64_t a, std::uint64_t b, std::uint64_t c = 0);

/// Stock materials with a little seeded variation of colour.
Material floor_material(Rng& rng);
Material wall_material(Rng& rng);
Material stair_material(Rng& rng);
Material wood_material(Rng& rng);
Material fabric_material(Rng& rng);
Material metal_material(Rng& rng);
Material concrete_material(Rng& rng);

/// What to build for one staircase.
struct StairParams {
  StairKind kind = StairKind::kAscending;
  int steps = 8;  ///< risers
  float riser_m = 0.17f;
  float tread_m = 0.29f;  ///< edge to edge; single step / curb: depth of the raised/lowered surface
  float width_m = 1.2f;
  bool open_risers = false;  ///< treads only (slabs on stringers), seen-through risers
  float nosing_m = 0.f;      ///< tread overhang beyond its riser (0 = flush)
  bool side_walls = true;    ///< walls along both sides (otherwise open sides)
  bool handrails = false;
  bool down = false;                      ///< curb: the ground beyond the edge is lower
  float top_depth_m = 2.5f;               ///< depth of the landing/floor after the last riser
  float wall_start_m = -0.6f;             ///< stair-frame z where the side walls begin
  Pose T_world_stair = Pose::Identity();  ///< origin at the first edge centre (see ground_truth.hpp)
  float base_z = 0.f;                     ///< world height of the floor before the first edge
  bool build_floor = true;  ///< also build the floor before the edge (and the lower floor for descending)
};

/// A flight's parameters with its dimensions given (everything else as StairParams has it). Pass
/// values, not random draws: the order in which arguments are evaluated is not fixed, and a preset's
/// draws must come in one order to make the same scene on every compiler.
inline StairParams flight_params(StairKind kind, int steps, float riser_m, float tread_m, float width_m) {
  StairParams p;
  p.kind = kind;
  p.steps = steps;
  p.riser_m = riser_m;
  p.tread_m = tread_m;
  p.width_m = width_m;
  return p;
}

/// T_world_stair for a staircase whose first edge centre is at ground point (x, y) with
/// direction of travel `yaw` (rad from world +x), at world height `edge_z`.
Pose stair_pose(float x, float y, float yaw, float edge_z);

/// Adds a staircase, single step or curb; returns its index in scene.stairs.
int add_staircase(Scene& scene, const StairParams& p, Rng& rng);

/// Adds four walls (and no ceiling) enclosing [lo, hi] (world xy, floor at z = floor_z).
void add_room_walls(Scene& scene, const Eigen::Vector2f& lo, const Eigen::Vector2f& hi, float floor_z,
                    float height, const Material& m);
/// Adds a door (panel and frame) on a wall: centre of its bottom edge at `p`, `yaw` = the
/// direction the wall's face points to (into the room).
void add_door(Scene& scene, const Eigen::Vector3f& p, float yaw, Rng& rng);
/// A standing person (legs, torso, arms, head) with feet at `feet`, facing `yaw`.
void add_person(Scene& scene, const Eigen::Vector3f& feet, float yaw, float height_m, Rng& rng);
void add_table(Scene& scene, const Eigen::Vector3f& centre, float yaw, float height, float length,
               float depth, Rng& rng);
void add_chair(Scene& scene, const Eigen::Vector3f& centre, float yaw, Rng& rng);
void add_bench(Scene& scene, const Eigen::Vector3f& centre, float yaw, float height, float length, Rng& rng);
void add_shelves(Scene& scene, const Eigen::Vector3f& centre, float yaw, float width, float depth,
                 const std::vector<float>& board_heights, Rng& rng);
void add_sofa(Scene& scene, const Eigen::Vector3f& centre, float yaw, float seat_height, Rng& rng);
/// A closed box standing on the floor (clutter, low platform).
void add_crate(Scene& scene, const Eigen::Vector3f& centre, float yaw, const Eigen::Vector3f& size,
               const Material& m, const std::string& label);

}  // namespace stairguide::synth
