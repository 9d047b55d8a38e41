#pragma once
/// \file scene.hpp
/// Scenes of the synthetic stair world: convex solids (oriented boxes, cylinders approximated by
/// prisms) whose planar faces the renderer rasterises, plus the staircases' exact geometry for
/// the ground truth. World frame: z up, origin on the floor the user starts on.

#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <vector>

#include "stairguide/core/ground_truth.hpp"
#include "stairguide/core/types.hpp"

namespace stairguide::synth {

/// Procedural texture families (tileable, made once per process; see src/synth/texture.cpp).
enum class Texture : std::uint8_t { kPlain, kTiles, kWood, kCarpet, kConcrete, kFabric, kCount };

/// Surface appearance: Lambert reflectance modulated by a procedural texture.
struct Material {
  Eigen::Vector3f albedo{0.7f, 0.7f, 0.7f};  ///< BGR reflectance, each in [0, 1]
  Texture texture = Texture::kPlain;
  float contrast = 0.3f;   ///< texture modulation amplitude (0 = flat colour)
  float texel_m = 0.005f;  ///< m, size of one texel on the surface
  /// m, depth relief following the texture (a carpet's pile: the rendered depth moves by
  /// relief_m times the texture's unit-variance value); 0 = a flat face, as every face but the
  /// second world's carpets.
  float relief_m = 0.f;
};

/// A planar convex face of a solid, in world coordinates.
struct Face {
  std::vector<Eigen::Vector3f> vertices;      ///< convex polygon, world
  Eigen::Vector3f normal{0.f, 0.f, 1.f};      ///< outward unit normal, world
  Eigen::Vector3f tex_origin{0.f, 0.f, 0.f};  ///< texture coordinates origin, world
  Eigen::Vector3f tex_s{1.f, 0.f, 0.f};       ///< unit texture axes in the face plane
  Eigen::Vector3f tex_t{0.f, 1.f, 0.f};
  int solid = -1;  ///< index of the solid in Scene::solids()
  int stair = -1;  ///< staircase whose tread this face is (-1: not a tread)
  int tread = 0;   ///< 1-based tread index within that staircase (0: not a tread)
};

enum class SolidShape { kBox, kCylinder };

/// A convex solid. Boxes span +-half_extents in their own frame; cylinders have their axis along
/// the solid's z, radii half_extents.x/.y (elliptic when they differ), half length half_extents.z,
/// and are rendered as `sides`-gon prisms.
struct Solid {
  SolidShape shape = SolidShape::kBox;
  Pose T_world_solid = Pose::Identity();
  Eigen::Vector3f half_extents{0.5f, 0.5f, 0.5f};
  int sides = 16;
  Material material;
  std::string label;   ///< "floor", "tread", "riser", "wall", "person", "table", ...
  int stair = -1;      ///< staircase whose tread the upward face of this solid is
  int tread = 0;       ///< 1-based tread index of that upward face
  int first_face = 0;  ///< this solid's faces are Scene::faces()[first_face, first_face + face_count)
  int face_count = 0;
};

/// Exact geometry of one staircase (or single step / curb), in the stair frame S of
/// ground_truth.hpp. Tread k (1..steps) lies at height +-k*riser (minus for descending or a curb
/// down) and starts at z = (k-1)*tread; tread `steps` is the landing/floor reached after the last
/// riser. For a single step or a curb, `tread_m` is the depth of the raised/lowered surface.
struct StairSpec {
  int id = 0;
  StairKind kind = StairKind::kNone;
  int steps = 0;
  float riser_m = 0.f;
  float tread_m = 0.f;
  float width_m = 0.f;
  bool open_risers = false;
  bool down = false;     ///< the surfaces after the first edge are lower (descending, curb down)
  float nosing_m = 0.f;  ///< overhang of each tread beyond its riser
  Pose T_world_stair = Pose::Identity();
  float base_z = 0.f;  ///< world height of the floor before the first edge

  /// World height of tread k (k = 0: the floor before the staircase).
  float tread_height(int k) const { return base_z + (down ? -1.f : 1.f) * riser_m * static_cast<float>(k); }
  /// Tread (0..steps) under a ground point given in world coordinates; 0 when it is off the
  /// staircase's width or before its first edge.
  int tread_under(const Eigen::Vector3f& p_world) const;
};

/// The edge of a drop-off (issue 42 item 4): the floor ends along the segment a-b (world) and the
/// level beyond lies `depth_m` below it, on the side `down_dir` (a horizontal unit vector) points to.
struct DropEdge {
  Eigen::Vector3f a = Eigen::Vector3f::Zero(), b = Eigen::Vector3f::Zero();
  Eigen::Vector3f down_dir = Eigen::Vector3f::UnitX();
  float depth_m = 0.f;
};

/// A scene: solids (with their faces, built on insertion), staircases and lighting.
class Scene {
 public:
  /// Adds an oriented box; returns its solid index.
  int add_box(const Pose& T_world_solid, const Eigen::Vector3f& half_extents, const Material& m,
              const std::string& label, int stair = -1, int tread = 0);
  /// Adds the box spanning [lo, hi] in frame F (given by T_world_frame).
  int add_box_in(const Pose& T_world_frame, const Eigen::Vector3f& lo, const Eigen::Vector3f& hi,
                 const Material& m, const std::string& label, int stair = -1, int tread = 0);
  /// Adds a world-axis-aligned box spanning [lo, hi].
  int add_box_world(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi, const Material& m,
                    const std::string& label);
  /// Adds a capped cylinder (prism) between world points a and b with radii rx, ry.
  int add_cylinder(const Eigen::Vector3f& a, const Eigen::Vector3f& b, float rx, float ry, const Material& m,
                   const std::string& label, int sides = 16);

  const std::vector<Solid>& solids() const { return solids_; }
  const std::vector<Face>& faces() const { return faces_; }

  std::string name;
  std::vector<StairSpec> stairs;
  std::vector<DropEdge> drops;  ///< drop-off edges (synthetic_drops.cpp), for the ground truth
  Eigen::Vector3f light_dir{0.35f, 0.25f, 0.90f};  ///< world, towards the light (normalised on use)
  float ambient = 0.35f;                           ///< fraction of light that is ambient

 private:
  void add_faces(int solid_index);
  std::vector<Solid> solids_;
  std::vector<Face> faces_;
};

}  // namespace stairguide::synth
