// ManhattanTracker::estimate and its phases: samples of the floor and of the other regions, one
// vote per vertical plane, what lies beyond each plane, the frame the planes make (walls first,
// then risers, then all), the image edges when the planes alone make none, and the walls' veto.
#include <algorithm>
#include <cmath>
#include <limits>

#include "internal.hpp"

namespace stairguide {

using namespace manhattan_detail;

namespace {
// The image edges' direction, asked of `compass` once a frame at most (the first time it is needed).
const EdgeCompassResult& ask_compass(std::optional<EdgeCompassResult>& cache,
                                     const std::function<EdgeCompassResult()>& compass) {
  if (!cache) cache = compass ? compass() : EdgeCompassResult{};
  return *cache;
}
}  // namespace

ManhattanEstimate ManhattanTracker::estimate(const std::vector<PlaneRegion>& regions,
                                             const Pose& T_floor_camera,
                                             const std::function<EdgeCompassResult()>& compass) {
  ManhattanEstimate est;
  std::optional<EdgeCompassResult> compass_cache;
  sample_floor(regions, T_floor_camera);
  sample_structure(regions, T_floor_camera);
  const float total_area = collect_votes(regions, T_floor_camera);
  const std::vector<Vote>& votes = votes_;
  if (votes.empty()) {
    est.why = "no vertical plane";
    return est;
  }
  mark_sides(regions, T_floor_camera);
  if (cfg_.riser_agreement > 0.f) mark_risers(regions, T_floor_camera);
  mark_structure_beyond();
  bool bounding_only = false, riser_frame = false;
  ManhattanEstimate frame = frame_of_planes(total_area, bounding_only, riser_frame);
  if (!frame.found && compass && cfg_.compass_min_support < 1.f) {
    // The planes alone are too narrow or too small to trust: planes that the image's edges agree
    // with (an independent witness) make the frame, checked by the walls below as any other.
    const EdgeCompassResult& c = ask_compass(compass_cache, compass);
    ManhattanEstimate confirmed = confirm(votes, total_area, c);
    if (!confirmed.found) {
      frame.why +=
          !c.valid || c.support < std::min(cfg_.compass_min_support, cfg_.compass_wall_min_support)
              ? "; the image edges show no clear direction"
          : c.support >= cfg_.compass_min_support
              ? "; the image edges' direction confirms no plane wide enough"
              : "; the image edges' direction, too weak to confirm more than a wall strip, confirms none";
      return frame;
    }
    frame = confirmed;
  }
  if (!frame.found) return frame;
  find_vetoes(frame, riser_frame, bounding_only);
  if (!vetoes_.empty() && !apply_vetoes(frame, total_area, compass, compass_cache)) {
    est.why =
        "a wall seen beyond the planes that make the frame disagrees with them (furniture turned against "
        "the room in front of it)";
    est.fraction = frame.fraction;
    est.vertical_area = frame.vertical_area;
    return est;
  }
  prev_yaw_ = frame.yaw;
  return frame;
}

void ManhattanTracker::sample_floor(const std::vector<PlaneRegion>& regions, const Pose& T_floor_camera) {
  const Eigen::Matrix3f R = T_floor_camera.linear();
  const float cos_tol = std::cos(cfg_.vertical_tolerance);
  // Floor samples (floor frame x and z, with the area each stands for) from every horizontal plane
  // at the floor's height, not only the floor region: furniture splits the floor in parts.
  std::vector<FloorSample>& floor_pts = floor_pts_;
  floor_pts.clear();
  auto is_floor = [&](const PlaneRegion& r) {
    if (r.points.empty() || std::fabs((R * r.normal).y()) < cos_tol) return false;
    return std::fabs((T_floor_camera * r.centroid).y()) <= cfg_.floor_beyond_height;
  };
  std::size_t n_floor = 0;
  for (const PlaneRegion& r : regions)
    if (is_floor(r)) n_floor += r.points.size();
  // A bounded sample keeps the test linear in the number of vertical planes, not in pixels.
  constexpr std::size_t kMaxFloorSamples = 1024;
  const std::size_t stride = std::max<std::size_t>(1, (n_floor + kMaxFloorSamples - 1) / kMaxFloorSamples);
  for (const PlaneRegion& r : regions) {
    if (!is_floor(r)) continue;
    const float w = r.area / static_cast<float>(r.points.size()) * static_cast<float>(stride);
    for (std::size_t i = 0; i < r.points.size(); i += stride) {
      const Eigen::Vector3f q = T_floor_camera * r.points[i];
      floor_pts.push_back({q.x(), q.z(), w});
    }
  }
}

void ManhattanTracker::sample_structure(const std::vector<PlaneRegion>& regions, const Pose& T_floor_camera) {
  const Eigen::Matrix3f R = T_floor_camera.linear();
  const float cos_tol = std::cos(cfg_.vertical_tolerance);
  // Samples of every other region (floor frame x and z, the area each stands for, the region),
  // at most kMaxRegionSamples per region so that a small far wall is not lost among big regions.
  // Region k's samples are struct_pts[first[k], first[k + 1]).
  std::vector<StructureSample>& struct_pts = struct_pts_;
  struct_pts.clear();
  std::vector<std::size_t>& first = region_samples_;
  first.assign(regions.size() + 1, 0);
  constexpr std::size_t kMaxRegionSamples = 48;
  for (std::size_t k = 0; k < regions.size(); ++k) {
    const PlaneRegion& r = regions[k];
    first[k] = struct_pts.size();
    if (r.points.empty()) continue;
    const bool floor_like = std::fabs((R * r.normal).y()) >= cos_tol &&
                            std::fabs((T_floor_camera * r.centroid).y()) <= cfg_.floor_beyond_height;
    if (floor_like) continue;  // the floor has its own test (floor_pts)
    const std::size_t stride =
        std::max<std::size_t>(1, (r.points.size() + kMaxRegionSamples - 1) / kMaxRegionSamples);
    const std::size_t n = (r.points.size() + stride - 1) / stride;
    const float w = r.area / static_cast<float>(n);
    for (std::size_t i = 0; i < r.points.size(); i += stride) {
      const Eigen::Vector3f q = T_floor_camera * r.points[i];
      struct_pts.push_back({q.x(), q.z(), w, static_cast<int>(k)});
    }
  }
  first[regions.size()] = struct_pts.size();
}

float ManhattanTracker::collect_votes(const std::vector<PlaneRegion>& regions, const Pose& T_floor_camera) {
  VoteView view;
  view.R = T_floor_camera.linear();
  view.sin_tol = std::sin(cfg_.vertical_tolerance);
  view.camera_height = T_floor_camera.translation().y();  // the floor frame's origin is under the camera
  // Up in camera coordinates: the horizontal direction within a vertical plane is up x normal.
  view.up_c = view.R.transpose() * Eigen::Vector3f::UnitY();
  view.full_w = std::max(cfg_.yaw_full_width, 1e-3f);
  view.clip_depth =
      max_range_ > 0.f ? max_range_ - cfg_.range_clip_margin : std::numeric_limits<float>::max();
  float total_area = 0.f;
  std::vector<Vote>& votes = votes_;
  votes.clear();
  for (std::size_t k = 0; k < regions.size(); ++k) {
    const PlaneRegion& r = regions[k];
    total_area += r.area;
    Vote v{};
    if (vote_of(r, static_cast<int>(k), view, v)) votes.push_back(v);
  }
  return total_area;
}

bool ManhattanTracker::vote_of(const PlaneRegion& r, int k, const VoteView& view, Vote& vote) const {
  const Eigen::Matrix3f& R = view.R;
  const Eigen::Vector3f& up_c = view.up_c;
  const Eigen::Vector3f nf = R * r.normal;
  if (r.points.empty()) return false;
  // A band a few centimetres tall along a level axis (a riser's strip at the image's edge, a
  // kerb's face) fixes its plane only up to a turn about that axis: its tilt may be off by
  // degrees, its axis and so its yaw are not (a single step's riser corner, 7 cm tall and 0.4 m
  // long, 13 deg from vertical, yaw 0.3 deg off). Tilted more than vertical_tolerance, it votes
  // only where the image edges confirm it (confirm()), its heading taken from the axis.
  bool tilted = false;
  float heading = std::atan2(nf.x(), nf.z());
  if (std::fabs(nf.y()) > view.sin_tol) {
    const Eigen::Vector3f axis = R * r.rect_axis_major;
    if (std::fabs(nf.y()) > std::sin(cfg_.level_band_max_tilt) ||
        !(r.rect_length_minor < cfg_.level_band_max_height) ||
        std::fabs(axis.y()) > std::sin(cfg_.level_band_max_slope))
      return false;
    tilted = true;
    // The horizontal normal of the axis, on the side of the plane's normal.
    Eigen::Vector2f h(axis.z(), -axis.x());
    if (h.x() * nf.x() + h.y() * nf.z() < 0.f) h = -h;
    heading = std::atan2(h.x(), h.y());
  }
  // Horizontal width of the region: the spread of its points along the horizontal in its plane;
  // the height of its lowest point; how many of its points lie at the depth cut-off.
  const Eigen::Vector3f hz = up_c.cross(r.normal).normalized();
  float lo = hz.dot(r.points.front()), hi = lo;
  float base = std::numeric_limits<float>::max();
  float top = -std::numeric_limits<float>::max();
  std::size_t clipped_points = 0;
  for (const Eigen::Vector3f& q : r.points) {
    const float t = hz.dot(q);
    lo = std::min(lo, t);
    hi = std::max(hi, t);
    const float u = up_c.dot(q);
    base = std::min(base, u);
    top = std::max(top, u);
    clipped_points += q.z() > view.clip_depth;
  }
  base += view.camera_height;
  top += view.camera_height;
  const float width = hi - lo;
  // The yaw of a plane fit is as precise as the plane is wide (lever arm): a person's front,
  // a post or the side of a box a few decimetres wide is off by degrees where a wall or a
  // riser is not. Votes weigh area * (width / full width)^2, the inverse of that variance.
  const float s = std::min(1.f, width / view.full_w);
  const float w = r.area * s * s;
  // Standing on the floor: its lowest point is at the floor's height. With no floor beyond it,
  // that is a wall; a person on a flight going down (no floor seen behind them either) stands
  // below the floor, a wall cabinet or a person's chest above it.
  const bool grounded = std::fabs(base) <= cfg_.floor_beyond_height;
  // A plane seen mostly at the depth cut-off is a sliver kept only where the noise fell short of
  // the cut-off: its fit may be biased by degrees (synthetic walls 5 m away: 1 to 10 degrees off).
  // It votes, but cannot make a frame of walls alone against the other planes.
  const bool clipped = 2 * clipped_points > r.points.size();
  // Unless it is a sliver (below), its yaw is then that of its plane held upright
  // (fit_upright_normal). Synthetic walls 4.6-5 m away were off as segmented by 0.57 deg
  // (median) and 1.96 (90th percentile) when 0.6 m wide and 0.3 m tall or more, 1.96 and 3.48
  // when 0.2-0.3 m tall; held upright by 0.36 and 1.13, 0.62 and 1.64. The real clouds' far
  // walls so cut, against the same planes seen uncut, are no worse on the whole (14 planes: a
  // mean 7.58 deg off as segmented, 5.01 held upright; PerceptionRealData in test_perception),
  // which is also why such a plane still makes no frame alone. A sliver (narrower than
  // sliver_width) gains nothing so: its yaw stays the segmentation's.
  if (clipped && !tilted && !(r.rect_length_minor < cfg_.sliver_width)) {
    const Eigen::Vector3f nu = fit_upright_normal(r.points, up_c, r.normal);
    const Eigen::Vector3f n = R * fit_upright_normal_clear_of_cutoff(r.points, up_c, nu, clear_depth_);
    heading = std::atan2(n.x(), n.z());
  }
  const float a = wrap_quarter(heading);
  // Such a plane is biased where the cut-off runs along it: a sliver a few centimetres wide lies
  // wholly in the noise band at the cut-off (10 degrees off seen), a wider patch mostly not.
  const bool sliver = clipped && r.rect_length_minor < cfg_.sliver_width;
  // A plane reaching below the floor stands in a hole in it (a person on a flight going down,
  // whose floor beyond is not seen): inside, like the planes with floor beyond them (below).
  const bool below = base < -cfg_.floor_beyond_height;
  vote = Vote{a, w, r.area, width, heading, below, grounded, clipped, k, sliver};
  // A band a few centimetres thick (a handrail, a stringer, a riser strip) fixes its plane only up
  // to a turn about its long axis. Along a horizontal axis (a riser strip) that turn moves the
  // tilt and leaves the yaw; along an axis that slopes with a flight it moves the yaw too: the
  // handrails beside an open-sided descent, seen against the floor below, made frames 4-5 deg off
  // with the staircase in view (synthetic held-out views). Such a band votes but makes no frame.
  vote.tilted = tilted;
  vote.sloped_band = r.area < cfg_.band_max_thickness * r.rect_length_major &&
                     std::fabs((R * r.rect_axis_major).y()) > std::sin(cfg_.band_min_slope);
  vote.range = r.centroid.norm();
  vote.far = vote.range >= cfg_.far_wall_range && width < cfg_.far_wall_width;
  vote.base = base;
  vote.top = top;
  return true;
}

void ManhattanTracker::mark_sides(const std::vector<PlaneRegion>& regions, const Pose& T_floor_camera) {
  const Eigen::Matrix3f R = T_floor_camera.linear();
  const Eigen::Vector3f cam_f = T_floor_camera.translation();
  // Does something lie beyond each vertical plane? A wall bounds the room: the floor and every
  // other surface lie on the camera's side of its plane. Furniture, people and risers stand inside
  // the room: the floor, the wall behind them, a seat or the treads above are seen beyond their
  // plane's extension. The test is in 3D and holds for any camera tilt (a level camera sees a
  // cupboard's top edge against the wall behind it, a tilted one does not).
  //  - Floor beyond: `inside`, the plane votes only when the walls make no frame.
  //  - Any other surface beyond: not a wall, it cannot veto a frame (below). It does not make the
  //    plane `inside`: a kitchen's cupboard fronts have the worktop beyond them and agree with its
  //    walls only to a few degrees; taking them out of the walls' frame moved the kitchen's
  //    frames by up to 2 degrees in the world (and more views apart).
  for (Vote& v : votes_) {
    const PlaneRegion& r = regions[static_cast<std::size_t>(v.region)];
    const Eigen::Vector3f nf = R * r.normal;
    Eigen::Vector2f nh(nf.x(), nf.z());
    if (nh.norm() <= 1e-6f) continue;
    nh.normalize();
    const Eigen::Vector3f cf = T_floor_camera * r.centroid;
    if (nh.x() * (cam_f.x() - cf.x()) + nh.y() * (cam_f.z() - cf.z()) < 0.f) nh = -nh;
    // A point p lies beyond the plane by more than the margin when nh . (p - cf) < -margin.
    v.has_side = true;
    v.nx = nh.x();
    v.nz = nh.y();
    v.limit = nh.x() * cf.x() + nh.y() * cf.z() - cfg_.floor_beyond_margin;
    v.cx = cf.x();
    v.cz = cf.z();
    float floor_beyond = 0.f;
    for (const FloorSample& f : floor_pts_)
      if (v.nx * f.x + v.nz * f.z < v.limit) floor_beyond += f.area;
    v.inside = v.inside || floor_beyond >= cfg_.floor_beyond_area;
  }
}

// Square metres of the other regions' samples beyond a vertical plane's extension (see `limit`),
// among samples [from, to).
float ManhattanTracker::area_beyond(const Vote& v, std::size_t from, std::size_t to) const {
  float sum = 0.f;
  for (std::size_t i = from; i < to; ++i) {
    const StructureSample& q = struct_pts_[i];
    if (q.region != v.region && v.nx * q.x + v.nz * q.z < v.limit) sum += q.area;
  }
  return sum;
}

void ManhattanTracker::mark_structure_beyond() {
  // A plane on the floor narrower than min_plane_width makes the walls' frame alone only as a wall
  // does: with nothing beyond it (a corridor's wall seen as a strip past a door frame). A person's
  // shins 0.22 m wide at the top of a descent, with the flight and the wall below it beyond them,
  // made a frame 23 deg off with the staircase in view (real-like noise, seed 1 people #13; the only
  // view so changed on seeds 1-12 real-like and 1-20 white, the kitchen's unchanged).
  for (Vote& v : votes_)
    if (v.has_side && v.grounded && v.width < cfg_.min_plane_width)
      v.structure_beyond = area_beyond(v, 0, struct_pts_.size()) >= cfg_.structure_beyond_area;
}

// A wall far away (far_wall_range) or at the depth cut-off is good to a few degrees only on the
// real sensor (see below); a staircase's risers a few metres away are good to a few tenths, and
// their direction is the staircase's own, which the user climbs whatever the room's. When only
// such walls make the walls' frame, the risers' frame within riser_agreement of it is taken
// (beyond that, the "risers" may be furniture turned against the room), and neither then can
// such a wall veto a frame that risers agree with, however it was made (below). With the
// real-like noise, seeds 1-12 of the static presets: frames more than 2 deg off with a staircase
// in view 21 -> 12 (their risers within 0.35 deg, the far walls 2.5 to 7 deg off), 7 views of a
// staircase that a far wall's veto left without a frame now have one; white noise: 2 more views
// with a frame, none changed otherwise (ManhattanFrame.RisersOverruleFarWalls*).
// Does a wall that is not far (by range, or `far`) and wide enough to make the walls' frame agree
// with it?
bool ManhattanTracker::near_wall_agrees(float yaw, bool far_by_range) const {
  for (const Vote& v : votes_) {
    const bool is_far = far_by_range ? v.range >= cfg_.far_wall_range : v.far;
    if (!v.inside && !v.tilted && !v.clipped && !v.sloped_band && !is_far &&
        v.width >= min_width(v, /*bounding_only=*/true) &&
        std::fabs(wrap_quarter(v.a - yaw)) <= cfg_.cluster_tolerance)
      return true;
  }
  return false;
}

ManhattanEstimate ManhattanTracker::frame_of_planes(float total_area, bool& bounding_only,
                                                    bool& riser_frame) {
  const std::vector<Vote>& votes = votes_;
  // Planes that bound the room (walls) make the frame when they can; the rest (furniture turned
  // against the room, risers, people) vote only when the bounding planes alone make no frame.
  bool any_bounding = false;
  for (const Vote& v : votes) any_bounding = any_bounding || (!v.inside && !v.tilted);
  bounding_only = any_bounding;
  riser_frame = false;
  ManhattanEstimate frame;
  if (any_bounding) frame = solve(votes, total_area, Voters::kBounding);
  // The risers' frame over far walls (see near_wall_agrees).
  if (frame.found && cfg_.riser_agreement > 0.f) {
    if (!near_wall_agrees(frame.yaw, /*far_by_range=*/true)) {
      const ManhattanEstimate risers = solve(votes, total_area, Voters::kRisers);
      if (risers.found && std::fabs(wrap_quarter(risers.yaw - frame.yaw)) <= cfg_.riser_agreement) {
        frame = risers;
        bounding_only = false;
        riser_frame = true;
      }
    }
  }
  // A frame that only far, narrow walls make (`far`) is good to a few degrees on the real sensor,
  // not to the 2 deg asked: its depth noise is 2 to 4 cm there and correlated between neighbouring
  // pixels (the real clouds' far walls, held upright, are 5 deg off on average:
  // PerceptionRealData.FarWallsAtTheCutOffHeldUprightAreNoWorse), and the synthetic walls so seen
  // were 3 to 7 deg off with the real-like noise, against risers 1.5 m wide 2.5 m away within
  // 0.3 deg. When all the vertical planes together (risers, furniture, nearer and wider) make a
  // frame within far_wall_agreement of the walls', the walls cannot show that frame wrong, and it
  // is taken; it then faces the walls' veto below as any other. Furniture turned further against
  // the room keeps the walls' frame. (With white noise the far walls are right to a degree, and
  // furniture turned 2 to 4 deg now gives its frame, that far off: on seeds 1-20, 6 more frames
  // off with a wall in view of 4815 views, none with a staircase in view.)
  if (frame.found && !riser_frame && cfg_.far_wall_agreement > 0.f) {
    if (!near_wall_agrees(frame.yaw, /*far_by_range=*/false)) {
      const ManhattanEstimate all = solve(votes, total_area, Voters::kAll);
      if (all.found && std::fabs(wrap_quarter(all.yaw - frame.yaw)) <= cfg_.far_wall_agreement) {
        frame = all;
        bounding_only = false;
      }
    }
  }
  if (!frame.found) {
    bounding_only = false;
    frame = solve(votes, total_area, Voters::kAll);
  }
  return frame;
}

void ManhattanTracker::find_vetoes(const ManhattanEstimate& frame, bool riser_frame, bool bounding_only) {
  const std::vector<Vote>& votes = votes_;
  const std::vector<std::size_t>& first = region_samples_;
  // A wall seen beyond the planes that make the frame, disagreeing with them: they are furniture
  // turned against the room (a sofa, shelves, clutter filling the view) and the wall, too small,
  // too far or clipped to make a frame of its own, says their frame is wrong. No frame is safer
  // than a wrong one (synthetic views: 17, 31 and 40 degrees off before). A wall at right angles
  // past a convex corner agrees modulo 90 degrees.
  std::vector<const Vote*>& vetoes = vetoes_;  // the walls that veto the frame
  vetoes.clear();
  // Risers agreeing with the frame: far walls and walls at the cut-off cannot veto it (see above).
  for (const Vote& v : votes)
    riser_frame =
        riser_frame || (v.riser && std::fabs(wrap_quarter(v.a - frame.yaw)) <= cfg_.cluster_tolerance);
  // The samples beyond a plane are counted only for the few planes this can concern (all pairs cost
  // 0.3 ms on a kitchen view of 100 regions).
  for (const Vote& vf : votes) {
    if (vf.tilted) continue;
    if (riser_frame && (vf.range >= cfg_.far_wall_range || vf.clipped)) continue;
    // A wall stands on the floor or goes on past the depth cut-off; a plane floating above the
    // floor and ending within range with nothing seen behind it may be a person's upper body.
    if (!vf.grounded && !vf.clipped) continue;
    // A narrow plane's yaw is off by degrees (a cupboard's side 6 cm wide in the kitchen: 9 deg).
    if (vf.width < cfg_.veto_min_width) continue;
    if (std::fabs(wrap_quarter(vf.a - frame.yaw)) <= disagree_tolerance(vf)) continue;
    // Not a wall when anything lies beyond it too.
    if (vf.inside || (vf.has_side && area_beyond(vf, 0, struct_pts_.size()) >= cfg_.structure_beyond_area))
      continue;
    const std::size_t f0 = first[static_cast<std::size_t>(vf.region)];
    const std::size_t f1 = first[static_cast<std::size_t>(vf.region) + 1];
    for (const Vote& vn : votes) {
      if (&vn == &vf || !vn.has_side || vn.tilted) continue;
      if (bounding_only && vn.inside) continue;  // did not make this frame
      if (std::fabs(wrap_quarter(vn.a - frame.yaw)) > cfg_.cluster_tolerance) continue;
      if (std::fabs(wrap_quarter(vf.a - vn.a)) <= std::max(disagree_tolerance(vn), disagree_tolerance(vf)))
        continue;
      // Seen beyond it: structure_beyond_area of the wall, or half of a smaller wall (a strip of
      // wall 0.2 to 0.3 m wide seen past a sofa or shelves has 0.01 to 0.02 m^2 in view: synthetic
      // views 9 to 14 degrees off before).
      if (area_beyond(vn, f0, f1) < std::min(cfg_.structure_beyond_area, 0.5f * vf.area)) continue;
      vetoes.push_back(&vf);
      break;
    }
  }
}

bool ManhattanTracker::apply_vetoes(ManhattanEstimate& frame, float total_area,
                                    const std::function<EdgeCompassResult()>& compass,
                                    std::optional<EdgeCompassResult>& compass_cache) const {
  const std::vector<const Vote*>& vetoes = vetoes_;
  // The widest vetoing wall, when as wide as a wall that makes a frame on its own
  // (min_plane_width), gives the frame itself with the walls agreeing with it: the furniture in
  // front of it is turned against the room, the room is not (synthetic sofa and shelves views
  // that had no frame). A narrower one, or vetoing walls that disagree among themselves, only
  // say the frame is wrong.
  const Vote* veto = vetoes.front();
  for (const Vote* v : vetoes)
    if (v->width > veto->width) veto = v;
  bool walls_agree = veto->width >= cfg_.min_plane_width;
  for (const Vote* v : vetoes)
    walls_agree = walls_agree && std::fabs(wrap_quarter(v->a - veto->a)) <=
                                     std::max(disagree_tolerance(*v), disagree_tolerance(*veto));
  bool edges_give_frame = false;
  if (!walls_agree && compass && cfg_.compass_veto_min_support < 1.f && cfg_.compass_veto_agreement > 0.f) {
    // Walls too narrow to make the frame say the furniture's frame is wrong, not which frame is
    // right; a sliver at the depth cut-off is good to a few degrees only (2.4 to 5 deg off with
    // white noise on the suite's seed, room_clutter #6 and #10). The image edges see the room
    // beyond the cut-off as well: its walls' base and joints (edge_compass.hpp). When their
    // direction agrees with the widest vetoing wall within compass_veto_agreement and not with
    // the furniture's frame, two independent witnesses say the same: the edges' direction, the
    // more precise of them (0.2 and 0.5 deg off in those two views), gives the frame. Here the
    // edges need less support than to confirm planes (compass_min_support): the wall has already
    // ruled out the furniture's own edges. On seeds 1-20 (white) and 1-12 (real-like) of the
    // static presets: 24 and 7 more views with a frame, none more off; no new frame was off
    // with the support down to 0.03 or the agreement up to 9 deg.
    const EdgeCompassResult& c = ask_compass(compass_cache, compass);
    if (c.valid && c.support >= cfg_.compass_veto_min_support &&
        std::fabs(wrap_quarter(veto->a - c.yaw)) <= cfg_.compass_veto_agreement &&
        std::fabs(wrap_quarter(c.yaw - frame.yaw)) > cfg_.cluster_tolerance) {
      float agree = 0.f;
      for (const Vote* v : vetoes)
        if (std::fabs(wrap_quarter(v->a - c.yaw)) <= cfg_.compass_veto_agreement) agree += v->area;
      set_frame(frame, manhattan_keep_branch(c.yaw, prev_yaw_), agree, total_area);
      edges_give_frame = true;
    }
  }
  if (walls_agree) {
    float sc = 0.f, ss = 0.f, agree = 0.f;
    for (const Vote& v : votes_) {
      if (v.inside || v.tilted || std::fabs(wrap_quarter(v.a - veto->a)) > cfg_.cluster_tolerance) continue;
      sc += v.w * std::cos(4.f * v.a);
      ss += v.w * std::sin(4.f * v.a);
      agree += v.area;
    }
    set_frame(frame, manhattan_keep_branch(wrap_quarter(0.25f * std::atan2(ss, sc)), prev_yaw_), agree,
              total_area);
    return true;
  }
  return edges_give_frame;
}

}  // namespace stairguide
