// Solids and their faces. Every solid is convex, so the renderer can treat each face as an
// independent convex polygon with back-face culling and an inverse-depth buffer.
#include "stairguide/synth/scene.hpp"

#include <cmath>

namespace stairguide::synth {

int StairSpec::tread_under(const Eigen::Vector3f& p_world) const {
  const Eigen::Vector3f p = T_world_stair.inverse() * p_world;
  if (std::abs(p.x()) > 0.5f * width_m || p.z() < 0.f) return 0;
  if (kind == StairKind::kSingleStep) return p.z() <= tread_m ? 1 : 0;
  if (kind == StairKind::kCurb) return 1;
  const int k = static_cast<int>(std::floor(p.z() / tread_m)) + 1;
  return k < steps ? k : steps;
}

int Scene::add_box(const Pose& T_world_solid, const Eigen::Vector3f& half_extents, const Material& m,
                   const std::string& label, int stair, int tread) {
  Solid s;
  s.shape = SolidShape::kBox;
  s.T_world_solid = T_world_solid;
  s.half_extents = half_extents;
  s.material = m;
  s.label = label;
  s.stair = stair;
  s.tread = tread;
  solids_.push_back(s);
  add_faces(static_cast<int>(solids_.size()) - 1);
  return static_cast<int>(solids_.size()) - 1;
}

int Scene::add_box_in(const Pose& T_world_frame, const Eigen::Vector3f& lo, const Eigen::Vector3f& hi,
                      const Material& m, const std::string& label, int stair, int tread) {
  Pose T = T_world_frame;
  T.translation() = T_world_frame * (0.5f * (lo + hi));
  return add_box(T, 0.5f * (hi - lo).cwiseAbs(), m, label, stair, tread);
}

int Scene::add_box_world(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi, const Material& m,
                         const std::string& label) {
  return add_box_in(Pose::Identity(), lo, hi, m, label);
}

int Scene::add_cylinder(const Eigen::Vector3f& a, const Eigen::Vector3f& b, float rx, float ry,
                        const Material& m, const std::string& label, int sides) {
  Solid s;
  s.shape = SolidShape::kCylinder;
  const Eigen::Vector3f axis = (b - a).normalized();
  // Any frame whose z is the axis; x is kept horizontal when possible so elliptic sections
  // (a torso) are oriented predictably.
  Eigen::Vector3f x = Eigen::Vector3f::UnitZ().cross(axis);
  if (x.norm() < 1e-4f) x = Eigen::Vector3f::UnitX();
  x.normalize();
  const Eigen::Vector3f y = axis.cross(x);
  Eigen::Matrix3f R;
  R.col(0) = x;
  R.col(1) = y;
  R.col(2) = axis;
  s.T_world_solid = Pose::Identity();
  s.T_world_solid.linear() = R;
  s.T_world_solid.translation() = 0.5f * (a + b);
  s.half_extents = Eigen::Vector3f(rx, ry, 0.5f * (b - a).norm());
  s.sides = sides < 3 ? 3 : sides;
  s.material = m;
  s.label = label;
  solids_.push_back(s);
  add_faces(static_cast<int>(solids_.size()) - 1);
  return static_cast<int>(solids_.size()) - 1;
}

void Scene::add_faces(int si) {
  solids_[static_cast<std::size_t>(si)].first_face = static_cast<int>(faces_.size());
  const Solid& s = solids_[static_cast<std::size_t>(si)];
  const Pose& T = s.T_world_solid;
  const Eigen::Vector3f& h = s.half_extents;
  auto push = [&](std::vector<Eigen::Vector3f> local, const Eigen::Vector3f& n_local) {
    Face f;
    f.vertices.reserve(local.size());
    for (const auto& v : local) f.vertices.push_back(T * v);
    f.normal = (T.linear() * n_local).normalized();
    f.solid = si;
    // Texture axes: horizontal faces use world x/y so neighbouring treads and floor tiles line
    // up; other faces run along their first edge.
    if (std::abs(f.normal.z()) > 0.9f) {
      f.tex_origin = Eigen::Vector3f::Zero();
      f.tex_s = Eigen::Vector3f::UnitX();
      f.tex_t = Eigen::Vector3f::UnitY();
    } else {
      f.tex_origin = f.vertices[0];
      Eigen::Vector3f e = f.normal.cross(Eigen::Vector3f::UnitZ());  // horizontal in-plane axis
      if (e.norm() < 1e-4f) e = f.vertices[1] - f.vertices[0];
      f.tex_s = e.normalized();
      f.tex_t = f.normal.cross(f.tex_s).normalized();
    }
    if (s.tread > 0 && f.normal.z() > 0.99f) {
      f.stair = s.stair;
      f.tread = s.tread;
    }
    faces_.push_back(std::move(f));
  };
  if (s.shape == SolidShape::kBox) {
    for (int axis = 0; axis < 3; ++axis) {
      for (int sign = -1; sign <= 1; sign += 2) {
        const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
        std::vector<Eigen::Vector3f> q(4);
        const float c1[4] = {-1.f, 1.f, 1.f, -1.f}, c2[4] = {-1.f, -1.f, 1.f, 1.f};
        for (int i = 0; i < 4; ++i) {
          q[static_cast<std::size_t>(i)][axis] = static_cast<float>(sign) * h[axis];
          q[static_cast<std::size_t>(i)][a1] = c1[i] * h[a1];
          q[static_cast<std::size_t>(i)][a2] = c2[i] * h[a2];
        }
        Eigen::Vector3f n = Eigen::Vector3f::Zero();
        n[axis] = static_cast<float>(sign);
        push(q, n);
      }
    }
  } else {
    const int n = s.sides;
    std::vector<Eigen::Vector3f> ring(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) {
      const float a = 6.2831853f * static_cast<float>(i) / static_cast<float>(n);
      ring[static_cast<std::size_t>(i)] = Eigen::Vector3f(h.x() * std::cos(a), h.y() * std::sin(a), 0.f);
    }
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector3f& p0 = ring[static_cast<std::size_t>(i)];
      const Eigen::Vector3f& p1 = ring[static_cast<std::size_t>((i + 1) % n)];
      const Eigen::Vector3f dz(0.f, 0.f, h.z());
      const Eigen::Vector3f mid = 0.5f * (p0 + p1);
      // Outward normal of the edge p0->p1 in the section plane.
      Eigen::Vector3f nn(p1.y() - p0.y(), -(p1.x() - p0.x()), 0.f);
      if (nn.dot(mid) < 0.f) nn = -nn;
      push({p0 - dz, p1 - dz, p1 + dz, p0 + dz}, nn.normalized());
    }
    std::vector<Eigen::Vector3f> top, bottom;
    for (int i = 0; i < n; ++i) {
      top.push_back(ring[static_cast<std::size_t>(i)] + Eigen::Vector3f(0.f, 0.f, h.z()));
      bottom.push_back(ring[static_cast<std::size_t>(n - 1 - i)] - Eigen::Vector3f(0.f, 0.f, h.z()));
    }
    push(top, Eigen::Vector3f::UnitZ());
    push(bottom, -Eigen::Vector3f::UnitZ());
  }
  solids_[static_cast<std::size_t>(si)].face_count =
      static_cast<int>(faces_.size()) - solids_[static_cast<std::size_t>(si)].first_face;
}

}  // namespace stairguide::synth
