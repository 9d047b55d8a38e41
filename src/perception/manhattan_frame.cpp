#include "stairguide/perception/manhattan_frame.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace stairguide {

namespace {
constexpr float kPi = 3.14159265358979f;
constexpr float kHalfPi = 0.5f * kPi;
float wrap_quarter(float a) { return manhattan_wrap(a); }
// `e` found at `yaw` (its k_M branch already kept), with `agree` m^2 of vertical planes agreeing.
void set_frame(ManhattanEstimate& e, float yaw, float agree, float total_area) {
  e.found = true;
  e.yaw = yaw;
  e.T_manhattan_floor = manhattan_pose_from_yaw(yaw);
  e.vertical_area = agree;
  e.fraction = total_area > 0.f ? agree / total_area : 0.f;
}
}  // namespace

Pose manhattan_pose_from_yaw(float yaw) {
  Pose T = Pose::Identity();
  T.linear() = Eigen::AngleAxisf(-yaw, Eigen::Vector3f::UnitY()).toRotationMatrix();
  return T;
}

float manhattan_wrap(float a) {
  while (a > 0.25f * kPi) a -= kHalfPi;
  while (a <= -0.25f * kPi) a += kHalfPi;
  return a;
}

// Least squares in inverse depth: a point on the ray r = p / z of an upright plane n . p = D has
// 1/z = (n / D) . r, and with n / D = al h1 + be h2 (h1, h2 spanning the horizontal) that is linear
// in al and be.
// Kinect noise is a constant sigma in 1/z along the ray, so least squares there is unbiased (as
// the segmentation's own fit, InvDepthMoments), and holding the normal upright leaves the tilt out:
// a band a few decimetres tall fixes its tilt poorly, and the tilt's error leaks into its yaw.
// The points fitted are those `keep` accepts.
namespace {
template <typename Keep>
Eigen::Vector3f fit_upright_normal_of(const std::vector<Eigen::Vector3f>& pts, const Eigen::Vector3f& up,
                                      const Eigen::Vector3f& n0, const Keep& keep) {
  Eigen::Vector3d h1 = (n0 - n0.dot(up) * up).cast<double>();
  if (h1.norm() < 1e-6) return n0;
  h1.normalize();
  const Eigen::Vector3d h2 = up.cast<double>().cross(h1).normalized();
  double a11 = 0, a12 = 0, a22 = 0, b1 = 0, b2 = 0;
  for (const Eigen::Vector3f& p : pts) {
    if (!(p.z() > 0.f) || !keep(p)) continue;
    const Eigen::Vector3d r = p.cast<double>() / p.z();
    const double x1 = h1.dot(r), x2 = h2.dot(r), w = 1.0 / p.z();
    a11 += x1 * x1, a12 += x1 * x2, a22 += x2 * x2, b1 += x1 * w, b2 += x2 * w;
  }
  const double det = a11 * a22 - a12 * a12;
  if (!(det > 1e-18 * std::max(1.0, a11 * a22))) return n0;
  const Eigen::Vector3d nd = ((a22 * b1 - a12 * b2) / det) * h1 + ((a11 * b2 - a12 * b1) / det) * h2;
  if (!(nd.norm() > 0.0)) return n0;
  Eigen::Vector3f n = nd.normalized().cast<float>();
  return n.dot(n0) < 0.f ? Eigen::Vector3f(-n) : n;
}
}  // namespace

Eigen::Vector3f fit_upright_normal(const std::vector<Eigen::Vector3f>& pts, const Eigen::Vector3f& up,
                                   const Eigen::Vector3f& n0) {
  return fit_upright_normal_of(pts, up, n0, [](const Eigen::Vector3f&) { return true; });
}

// The depth cut-off keeps a reading only when its noise fell short of it: along a plane reaching
// the cut-off, the readings of its far part are the ones pushed nearer, and least squares turns the
// plane towards the camera there (a synthetic wall 0.5 m of which lies 4.55-5.3 m away: 0.92 deg
// off held upright, 0.28 fitted so; ManhattanFrame.WallReachingTheCutOffIsFittedClearOfIt). Readings
// whose plane lies 3 sigma nearer than the cut-off lost nothing to it. Which readings those are is
// decided by their ray (the plane's depth along it), which the noise does not move, not by the
// reading itself: choosing readings by their depth would cut the noise again where the choice is
// made. The plane's depth comes from the fit of all readings, biased a little, and is taken again
// from the first refit. A plane seen mostly inside the band keeps its upright fit: its clear part
// is too narrow to fix a yaw (a wall 0.74 m wide refitted on its nearest quarter made a frame 9 deg
// off).
// This models nothing of the noise beyond its size at the cut-off, unlike the corrections README
// tells of (a truncated normal's mean excess, a truncated-Gaussian likelihood), which the real
// clouds refused; on their far walls it refits 2 of 14 planes, both nearer the truth
// (PerceptionRealData.FarWallsAtTheCutOffHeldUprightAreNoWorse).
Eigen::Vector3f fit_upright_normal_clear_of_cutoff(const std::vector<Eigen::Vector3f>& pts,
                                                   const Eigen::Vector3f& up, const Eigen::Vector3f& n_upright,
                                                   float clear_depth) {
  constexpr std::size_t kMinPoints = 30;
  Eigen::Vector3f n = n_upright;
  if (pts.size() < kMinPoints || !(clear_depth > 0.f)) return n;
  for (int pass = 0; pass < 2; ++pass) {
    double sum = 0.0;
    for (const Eigen::Vector3f& p : pts) sum += n.dot(p);
    const float D = static_cast<float>(sum / static_cast<double>(pts.size()));  // the plane n . p = D
    // On the plane, the point on p's ray has depth D / (n . p / z).
    auto clear = [&](const Eigen::Vector3f& p) {
      const float nr = n.dot(p) / p.z();
      return std::fabs(nr) > 1e-6f && D / nr > 0.f && D / nr < clear_depth;
    };
    std::size_t kept = 0;
    for (const Eigen::Vector3f& p : pts) kept += p.z() > 0.f && clear(p);
    if (kept < kMinPoints || 2 * kept < pts.size()) break;
    n = fit_upright_normal_of(pts, up, n, clear);
  }
  return n;
}

float manhattan_keep_branch(float yaw, const std::optional<float>& previous) {
  if (!previous) return yaw;
  float best = yaw, bestd = 1e9f;
  for (int k = -1; k <= 1; ++k) {
    const float c = yaw + k * kHalfPi;
    const float dd = std::fabs(c - *previous);
    if (dd < bestd) {
      bestd = dd;
      best = c;
    }
  }
  const float hysteresis = 0.1745f;  // 10 degrees
  return std::fabs(best) < 0.25f * kPi + hysteresis ? best : yaw;
}

void ManhattanHistogram::add(float a, float w) {
  int bin = static_cast<int>((a + 0.25f * kPi) / kHalfPi * kBins);
  bin = (bin % kBins + kBins) % kBins;
  for (int k = -2; k <= 2; ++k) hist_[((bin + k) % kBins + kBins) % kBins] += w * (3 - std::abs(k));
}

float ManhattanHistogram::mode() const {
  int peak = 0;
  for (int b = 1; b < kBins; ++b)
    if (hist_[b] > hist_[peak]) peak = b;
  return -0.25f * kPi + (static_cast<float>(peak) + 0.5f) * kHalfPi / kBins;
}

ManhattanTracker::ManhattanTracker(const ManhattanConfig& config, float max_range, float depth_noise_coeff)
    : cfg_(config), max_range_(max_range) {
  if (max_range_ > 0.f) clear_depth_ = max_range_ - 3.f * std::max(0.f, depth_noise_coeff) * max_range_ * max_range_;
}

ManhattanEstimate ManhattanTracker::estimate(const std::vector<PlaneRegion>& regions, const Pose& T_floor_camera,
                                             const std::function<EdgeCompassResult()>& compass) {
  ManhattanEstimate est;
  std::optional<EdgeCompassResult> compass_cache;
  auto ask_compass = [&]() -> const EdgeCompassResult& {
    if (!compass_cache) compass_cache = compass ? compass() : EdgeCompassResult{};
    return *compass_cache;
  };
  const Eigen::Matrix3f R = T_floor_camera.linear();
  const float sin_tol = std::sin(cfg_.vertical_tolerance);
  const float cos_tol = std::cos(cfg_.vertical_tolerance);
  const float camera_height = T_floor_camera.translation().y();  // the floor frame's origin is under the camera
  float total_area = 0.f;
  std::vector<Vote>& votes = votes_;
  votes.clear();
  // Floor samples (floor frame x and z, with the area each stands for) from every horizontal plane
  // at the floor's height, not only the floor region: furniture splits the floor in parts.
  std::vector<FloorSample>& floor_pts = floor_pts_;
  floor_pts.clear();
  {
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
  // Samples of every other region (floor frame x and z, the area each stands for, the region),
  // at most kMaxRegionSamples per region so that a small far wall is not lost among big regions.
  // Region k's samples are struct_pts[first[k], first[k + 1]).
  std::vector<StructureSample>& struct_pts = struct_pts_;
  struct_pts.clear();
  std::vector<std::size_t>& first = region_samples_;
  first.assign(regions.size() + 1, 0);
  {
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
  // Up in camera coordinates: the horizontal direction within a vertical plane is up x normal.
  const Eigen::Vector3f up_c = R.transpose() * Eigen::Vector3f::UnitY();
  const Eigen::Vector3f cam_f = T_floor_camera.translation();
  const float full_w = std::max(cfg_.yaw_full_width, 1e-3f);
  const float clip_depth = max_range_ > 0.f ? max_range_ - cfg_.range_clip_margin : std::numeric_limits<float>::max();
  for (std::size_t k = 0; k < regions.size(); ++k) {
    const PlaneRegion& r = regions[k];
    total_area += r.area;
    const Eigen::Vector3f nf = R * r.normal;
    if (r.points.empty()) continue;
    // A band a few centimetres tall along a level axis (a riser's strip at the image's edge, a
    // kerb's face) fixes its plane only up to a turn about that axis: its tilt may be off by
    // degrees, its axis and so its yaw are not (a single step's riser corner, 7 cm tall and 0.4 m
    // long, 13 deg from vertical, yaw 0.3 deg off). Tilted more than vertical_tolerance, it votes
    // only where the image edges confirm it (confirm()), its heading taken from the axis.
    bool tilted = false;
    float heading = std::atan2(nf.x(), nf.z());
    if (std::fabs(nf.y()) > sin_tol) {
      const Eigen::Vector3f axis = R * r.rect_axis_major;
      if (std::fabs(nf.y()) > std::sin(cfg_.level_band_max_tilt) ||
          !(r.rect_length_minor < cfg_.level_band_max_height) ||
          std::fabs(axis.y()) > std::sin(cfg_.level_band_max_slope))
        continue;
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
      clipped_points += q.z() > clip_depth;
    }
    base += camera_height;
    top += camera_height;
    const float width = hi - lo;
    // The yaw of a plane fit is as precise as the plane is wide (lever arm): a person's front,
    // a post or the side of a box a few decimetres wide is off by degrees where a wall or a
    // riser is not. Votes weigh area * (width / full width)^2, the inverse of that variance.
    const float s = std::min(1.f, width / full_w);
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
    votes.push_back({a, w, r.area, width, heading, below, grounded, clipped, static_cast<int>(k), sliver});
    // A band a few centimetres thick (a handrail, a stringer, a riser strip) fixes its plane only up
    // to a turn about its long axis. Along a horizontal axis (a riser strip) that turn moves the
    // tilt and leaves the yaw; along an axis that slopes with a flight it moves the yaw too: the
    // handrails beside an open-sided descent, seen against the floor below, made frames 4-5 deg off
    // with the staircase in view (synthetic held-out views). Such a band votes but makes no frame.
    votes.back().tilted = tilted;
    votes.back().sloped_band = r.area < cfg_.band_max_thickness * r.rect_length_major &&
                               std::fabs((R * r.rect_axis_major).y()) > std::sin(cfg_.band_min_slope);
    votes.back().range = r.centroid.norm();
    votes.back().far = votes.back().range >= cfg_.far_wall_range && width < cfg_.far_wall_width;
    votes.back().base = base;
    votes.back().top = top;
  }
  if (votes.empty()) {
    est.why = "no vertical plane";
    return est;
  }
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
  for (Vote& v : votes) {
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
    for (const FloorSample& f : floor_pts)
      if (v.nx * f.x + v.nz * f.z < v.limit) floor_beyond += f.area;
    v.inside = v.inside || floor_beyond >= cfg_.floor_beyond_area;
  }
  if (cfg_.riser_agreement > 0.f) mark_risers(regions, T_floor_camera);
  // Square metres of the other regions' samples beyond a vertical plane's extension (see `limit`),
  // among samples [from, to).
  auto area_beyond = [&](const Vote& v, std::size_t from, std::size_t to) {
    float sum = 0.f;
    for (std::size_t i = from; i < to; ++i) {
      const StructureSample& q = struct_pts[i];
      if (q.region != v.region && v.nx * q.x + v.nz * q.z < v.limit) sum += q.area;
    }
    return sum;
  };
  // A plane on the floor narrower than min_plane_width makes the walls' frame alone only as a wall
  // does: with nothing beyond it (a corridor's wall seen as a strip past a door frame). A person's
  // shins 0.22 m wide at the top of a descent, with the flight and the wall below it beyond them,
  // made a frame 23 deg off with the staircase in view (real-like noise, seed 1 people #13; the only
  // view so changed on seeds 1-12 real-like and 1-20 white, the kitchen's unchanged).
  for (Vote& v : votes)
    if (v.has_side && v.grounded && v.width < cfg_.min_plane_width)
      v.structure_beyond = area_beyond(v, 0, struct_pts.size()) >= cfg_.structure_beyond_area;
  // Planes that bound the room (walls) make the frame when they can; the rest (furniture turned
  // against the room, risers, people) vote only when the bounding planes alone make no frame.
  bool any_bounding = false;
  for (const Vote& v : votes) any_bounding = any_bounding || (!v.inside && !v.tilted);
  bool bounding_only = any_bounding;
  ManhattanEstimate frame;
  if (any_bounding) frame = solve(votes, total_area, Voters::kBounding);
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
  // Does a wall that `is_far` does not set aside, wide enough to make the walls' frame, agree with it?
  auto near_wall_agrees = [&](auto is_far) {
    for (const Vote& v : votes)
      if (!v.inside && !v.tilted && !v.clipped && !v.sloped_band && !is_far(v) &&
          v.width >= min_width(v, /*bounding_only=*/true) &&
          std::fabs(wrap_quarter(v.a - frame.yaw)) <= cfg_.cluster_tolerance)
        return true;
    return false;
  };
  bool riser_frame = false;
  if (frame.found && cfg_.riser_agreement > 0.f) {
    if (!near_wall_agrees([&](const Vote& v) { return v.range >= cfg_.far_wall_range; })) {
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
    if (!near_wall_agrees([](const Vote& v) { return v.far; })) {
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
  if (!frame.found && compass && cfg_.compass_min_support < 1.f) {
    // The planes alone are too narrow or too small to trust: planes that the image's edges agree
    // with (an independent witness) make the frame, checked by the walls below as any other.
    const EdgeCompassResult& c = ask_compass();
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
    if (vf.inside || (vf.has_side && area_beyond(vf, 0, struct_pts.size()) >= cfg_.structure_beyond_area)) continue;
    const std::size_t f0 = first[static_cast<std::size_t>(vf.region)];
    const std::size_t f1 = first[static_cast<std::size_t>(vf.region) + 1];
    for (const Vote& vn : votes) {
      if (&vn == &vf || !vn.has_side || vn.tilted) continue;
      if (bounding_only && vn.inside) continue;  // did not make this frame
      if (std::fabs(wrap_quarter(vn.a - frame.yaw)) > cfg_.cluster_tolerance) continue;
      if (std::fabs(wrap_quarter(vf.a - vn.a)) <= std::max(disagree_tolerance(vn), disagree_tolerance(vf))) continue;
      // Seen beyond it: structure_beyond_area of the wall, or half of a smaller wall (a strip of
      // wall 0.2 to 0.3 m wide seen past a sofa or shelves has 0.01 to 0.02 m^2 in view: synthetic
      // views 9 to 14 degrees off before).
      if (area_beyond(vn, f0, f1) < std::min(cfg_.structure_beyond_area, 0.5f * vf.area)) continue;
      vetoes.push_back(&vf);
      break;
    }
  }
  if (!vetoes.empty()) {
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
      const EdgeCompassResult& c = ask_compass();
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
      for (const Vote& v : votes) {
        if (v.inside || v.tilted || std::fabs(wrap_quarter(v.a - veto->a)) > cfg_.cluster_tolerance) continue;
        sc += v.w * std::cos(4.f * v.a);
        ss += v.w * std::sin(4.f * v.a);
        agree += v.area;
      }
      set_frame(frame, manhattan_keep_branch(wrap_quarter(0.25f * std::atan2(ss, sc)), prev_yaw_), agree,
                total_area);
    } else if (!edges_give_frame) {
      est.why = "a wall seen beyond the planes that make the frame disagrees with them (furniture turned against "
                "the room in front of it)";
      est.fraction = frame.fraction;
      est.vertical_area = frame.vertical_area;
      return est;
    }
  }
  prev_yaw_ = frame.yaw;
  return frame;
}

ManhattanEstimate ManhattanTracker::confirm(const std::vector<Vote>& votes, float total_area,
                                            const EdgeCompassResult& compass) const {
  ManhattanEstimate est;
  if (!compass.valid) return confirm_by_lines(votes, total_area, compass);
  // Edges with less support than compass_min_support, down to compass_wall_min_support, confirm
  // only wall strips (wall_strip()): planes whose own evidence already says wall, short only of
  // area (a strip of wall 0.29 x 0.11 m in a corner of the view, 0.5 deg off: people #14 on the
  // suite's seed). There the edges only need to be clear of a chance peak (a uniform spread gives
  // 0.04) and agree within compass_agreement; without them, such strips made frames 2.7 and
  // 4.7 deg off with the real-like noise (a single step and a curb seen in part).
  const bool weak = compass.support < cfg_.compass_min_support;
  if (weak && compass.support < cfg_.compass_wall_min_support)
    return confirm_by_lines(votes, total_area, compass);
  // The planes within compass_agreement of the edges' direction, one of them compass_min_width
  // wide (narrower ones, a person's limbs, agree with anything to degrees). Bands along a slope
  // and slivers at the depth cut-off, whose yaw may be off by degrees, neither make nor join it.
  // The frame's yaw is the planes' (their weighted mean), not the edges': the compass only says
  // which planes to believe. The wide one may not hang (hangs()): a table's edge is the table's,
  // however its own edges confirm it (real-like suite seed, table #15: 2.12 deg off before).
  float sc = 0.f, ss = 0.f, agree = 0.f;
  bool wide = false;
  for (const Vote& v : votes) {
    if (v.sloped_band || v.sliver) continue;
    if (weak && !wall_strip(v)) continue;
    if (std::fabs(wrap_quarter(v.a - compass.yaw)) > cfg_.compass_agreement) continue;
    sc += v.w * std::cos(4.f * v.a);
    ss += v.w * std::sin(4.f * v.a);
    agree += v.area;
    wide = wide || (!hangs(v) && v.width >= cfg_.compass_min_width);
  }
  if (!wide) return confirm_by_lines(votes, total_area, compass);
  set_frame(est, manhattan_keep_branch(wrap_quarter(0.25f * std::atan2(ss, sc)), prev_yaw_), agree,
            total_area);
  return est;
}

// The image's long straight edges on the floor (EdgeCompassResult::lines) are a second witness,
// asked when the edges' dominant direction confirms no plane: a long edge on the floor is the foot
// of a wall (seen even beyond the depth cut-off, where the wall's own readings are gone), a joint of
// the floor's boards or tiles, or the edge of a rug, and each runs along the room. On a floor of
// random texture the edges' dominant direction is no more than a chance peak (the floor fills most
// of the view), while the foot of a wall 6 m away is one straight edge across the image: on the
// suite's seed, floor_only #17 sees a sliver of wall 0.55 m wide at the cut-off and that foot,
// 518 px long and 0.03 deg off, and had no frame before.
// A line confirms the planes within compass_agreement of it when one of them, compass_min_width
// wide, stands for a wall: nothing is seen beyond it (not `inside`). Furniture, people and risers
// have straight edges along themselves, which say nothing of the room, and a line never makes a
// frame alone: the real kitchen's tile joints lie up to 4.4 deg from its walls' frame
// (EdgeCompassRealData.KitchenFloorLinesAgreeWithTheWalls). The frame takes the line's direction:
// a line hundreds of pixels long is sharper than the plane it confirms (white noise, seeds 5 and 17:
// ascending #7 and room_clutter #0 were 2.07 and 2.01 deg off with the planes' own yaw, their lines
// 0.12 and 0.02; on seeds 1-20, with the line's, 11 more views right and none off).
ManhattanEstimate ManhattanTracker::confirm_by_lines(const std::vector<Vote>& votes, float total_area,
                                                     const EdgeCompassResult& compass) const {
  ManhattanEstimate est;
  for (const EdgeLine& line : compass.lines) {  // longest first
    float agree = 0.f;
    bool wall = false;
    for (const Vote& v : votes) {
      if (v.sloped_band || v.sliver) continue;
      if (std::fabs(wrap_quarter(v.a - line.heading)) > cfg_.compass_agreement) continue;
      agree += v.area;
      wall = wall || (v.has_side && !v.inside && v.width >= cfg_.compass_min_width);
    }
    if (!wall) continue;
    set_frame(est, manhattan_keep_branch(wrap_quarter(line.heading), prev_yaw_), agree, total_area);
    return est;
  }
  return est;
}

float ManhattanTracker::disagree_tolerance(const Vote& v) const {
  // A sliver seen at the depth cut-off may be off by up to 10 degrees (see `sliver`): it
  // contradicts another direction only by more than that.
  return v.sliver ? std::max(cfg_.cluster_tolerance, cfg_.clipped_disagreement) : cfg_.cluster_tolerance;
}

// Inside the room, furniture and people hang above the floor: a seat's apron, a chair's back, a
// table's edge, shelf boards, a person's chest. Their plane, however wide, is the furniture's, often
// turned against the room (a bench's apron 1.3 m wide and 6 cm tall made frames 2.5-6 deg off with
// a wall in view), so it votes, joins a frame and makes one in a pair with a plane that does not
// hang (open risers' tread fronts, the lowest on the floor), but makes none alone nor with another
// hanging plane. Walls have no floor beyond them, and a flight's risers, which hang too, are marked
// as such (mark_risers). On seeds 1-20 of the static presets (white noise) and 1-12 (real-like),
// with segmentation's curved_facet_size_ratio: frames off with a wall in view 41 -> 34 and
// 113 -> 102 (no view more), right frames 4599 -> 4600 and 2666 -> 2667.
bool ManhattanTracker::hangs(const Vote& v) const {
  return cfg_.hanging_min_height > 0.f && v.inside && !v.riser && v.base > cfg_.hanging_min_height;
}

bool ManhattanTracker::wall_strip(const Vote& v) const {
  return v.grounded && !v.inside && !v.tilted && !v.clipped && !v.far && !v.sloped_band && v.has_side &&
         v.width < cfg_.min_plane_width && !v.structure_beyond;
}

float ManhattanTracker::min_width(const Vote& v, bool bounding_only) const {
  return bounding_only && v.grounded && !v.structure_beyond ? cfg_.min_bounding_width : cfg_.min_plane_width;
}

// A riser is told from furniture by what it carries. A vertical plane up to riser_max_height tall
// (a riser, or an open riser's tread front, a few centimetres) is a candidate when a horizontal
// plane at its top edge's height (its tread) starts at its plane (up to 8 cm in front of it, a
// nosing, or 12 cm beyond, the samples' spacing) and goes on beyond it, with next to nothing in
// front of it. A sofa's back cushion on its seat, shelves' plinth under their bottom board or a
// table's edge are candidates too. So a candidate is a riser only:
//  - in a flight: another candidate, parallel within 3 deg, riser_going_min to riser_going_max
//    beyond it, carries a tread riser_min_height to riser_max_height above its own (a sofa's
//    cushions are one candidate, a shelf's boards lie one above the other);
//  - alone, standing on the floor (a single step, a curb): riser_min_height tall or more,
//    single_riser_min_width wide and its tread seen to go on single_riser_min_depth beyond it (a
//    shelf's plinth and bottom board, 0.87 m wide and 0.34 m deep in a synthetic view, are none).
// A drop's face (below) stands with the risers too, though it carries no tread.
// Open risers' tread fronts made one more frame right of the 2906 real-like views on seeds 1-12
// (a flight's fronts 1 m wide within 0.35 deg, against a far wall 2.7 deg off).
// The tests use the sampled points (StructureSample), 48 per region.
void ManhattanTracker::mark_risers(const std::vector<PlaneRegion>& regions, const Pose& T_floor_camera) {
  std::vector<Vote>& votes = votes_;
  const std::vector<StructureSample>& struct_pts = struct_pts_;
  const std::vector<std::size_t>& first = region_samples_;
  const Eigen::Matrix3f R = T_floor_camera.linear();
  const float cos_tol = std::cos(cfg_.vertical_tolerance);
  constexpr float kNosing = 0.08f;   // m, a tread may start this far in front of its riser ...
  constexpr float kSpacing = 0.12f;  // m, ... or this far beyond it (its samples are ~0.1 m apart)
  constexpr float kBeyond = 0.1f;    // m, samples this far beyond the plane are the tread going on
  constexpr int kMinSamples = 3;     // samples that show a tread (of 48)
  const float tol = cfg_.riser_tread_tolerance;
  for (Vote& v : votes) {
    v.riser = false;
    v.tread_depth = 0.f;
    if (!v.has_side || v.tilted || v.clipped || v.sloped_band || v.top - v.base > cfg_.riser_max_height)
      continue;
    for (std::size_t k = 0; k < regions.size(); ++k) {
      const PlaneRegion& r = regions[k];
      if (r.points.empty() || std::fabs((R * r.normal).y()) < cos_tol) continue;
      if (std::fabs((T_floor_camera * r.centroid).y() - v.top) > tol) continue;
      int beside = 0, beyond = 0, in_front = 0;
      float nearest = std::numeric_limits<float>::max(), deepest = 0.f;
      for (std::size_t i = first[k]; i < first[k + 1]; ++i) {
        const StructureSample& q = struct_pts[i];
        const float dx = q.x - v.cx, dz = q.z - v.cz;
        if (std::fabs(-v.nz * dx + v.nx * dz) > 0.5f * v.width + 0.05f) continue;  // not beside it
        const float d = -(v.nx * dx + v.nz * dz);  // beyond the plane (< 0: in front of it)
        ++beside;
        if (d > -kNosing) nearest = std::min(nearest, d);
        deepest = std::max(deepest, d);
        beyond += d > kBeyond;
        in_front += d < -kNosing;
      }
      if (beyond >= kMinSamples && 10 * in_front <= beside && nearest <= kSpacing) {
        v.riser = true;  // a candidate
        v.tread_depth = std::max(v.tread_depth, deepest);
      }
    }
  }
  std::vector<char>& stacked = stacked_;
  stacked.assign(votes.size(), 0);
  const float parallel = 3.f * kPi / 180.f;
  for (std::size_t i = 0; i < votes.size(); ++i) {
    const Vote& p = votes[i];
    if (!p.riser) continue;
    for (std::size_t j = 0; j < votes.size(); ++j) {
      const Vote& q = votes[j];
      if (j == i || !q.riser) continue;
      const float rise = q.top - p.top;
      if (rise < cfg_.riser_min_height - tol || rise > cfg_.riser_max_height + tol) continue;
      float d = std::fmod(std::fabs(p.heading - q.heading), kPi);  // modulo 180 degrees
      d = std::min(d, kPi - d);
      if (d > parallel) continue;
      const float dx = q.cx - p.cx, dz = q.cz - p.cz;
      const float going = -(p.nx * dx + p.nz * dz);
      if (going < cfg_.riser_going_min || going > cfg_.riser_going_max) continue;
      if (std::fabs(-p.nz * dx + p.nx * dz) > 0.5f * (p.width + q.width)) continue;  // side by side
      stacked[i] = stacked[j] = 1;
    }
  }
  for (std::size_t i = 0; i < votes.size(); ++i) {
    Vote& v = votes[i];
    const bool single = std::fabs(v.base) <= cfg_.floor_beyond_height &&
                        v.top - v.base >= cfg_.riser_min_height && v.width >= cfg_.single_riser_min_width &&
                        v.tread_depth >= cfg_.single_riser_min_depth;
    // The face of a drop (the floor's edge over a descent, a stairwell's side): its top edge at the
    // floor's height, going down a riser or more, as wide as a wall. Furniture stands on a floor; it
    // does not hang from the user's. (Real-like seeds 1-12: 2 more views right, people #20 seed 5
    // among them, 6.1 deg off before by a far wall's frame; white noise and the kitchen unchanged.)
    const bool drop = !v.tilted && !v.clipped && !v.sloped_band &&
                      std::fabs(v.top) <= cfg_.floor_beyond_height && v.base < -cfg_.riser_min_height &&
                      v.width >= cfg_.min_plane_width;
    v.riser = (v.riser && (stacked[i] || single)) || drop;
  }
}

ManhattanEstimate ManhattanTracker::solve(const std::vector<Vote>& votes, float total_area, Voters voters) {
  ManhattanEstimate est;
  const bool bounding_only = voters == Voters::kBounding;
  auto counts = [&](const Vote& v) {
    return !v.tilted && !(bounding_only && v.inside) && (voters != Voters::kRisers || v.riser);
  };
  // Votes: angle of each vertical normal in the floor plane, modulo 90 degrees.
  ManhattanHistogram hist;
  for (const Vote& v : votes)
    if (counts(v)) hist.add(v.a, v.w);
  const float mode = hist.mode();
  // Circular mean of 4*angle among votes near the mode (period 90 degrees).
  float sc = 0.f, ss = 0.f, agree = 0.f, wsum_agree = 0.f;
  bool wide = false;
  std::vector<const Vote*>& candidates = pair_candidates_;
  candidates.clear();
  for (const Vote& v : votes) {
    if (!counts(v)) continue;
    if (std::fabs(wrap_quarter(v.a - mode)) > cfg_.cluster_tolerance) continue;
    sc += v.w * std::cos(4.f * v.a);
    ss += v.w * std::sin(4.f * v.a);
    agree += v.area;
    wsum_agree += v.w;
    // A plane seen mostly at the depth cut-off cannot make a frame of walls alone (see `clipped`).
    if (bounding_only && v.clipped) continue;
    if (v.sloped_band) continue;
    // A wall standing on the floor is trusted from a narrower strip than other planes: people and
    // posts, whose yaw is off by degrees, have floor beside them or do not stand at its height.
    wide = wide || (!hangs(v) && v.width >= min_width(v, bounding_only));
    // Pairs (below) are made of planes whose fit is not biased by the depth cut-off.
    if (v.width >= cfg_.pair_min_width && v.has_side && !v.clipped) candidates.push_back(&v);
  }
  // Without a wide plane, two agreeing planes parallel to each other (modulo 180 degrees) are
  // structure when each is wide enough for its own yaw to mean something (a person's legs and
  // arms, 3 to 4 cm, agree with anything within degrees; risers seen at a grazing angle on a turn
  // are 5 cm and right to a degree) and they agree tightly:
  //  - strips of one plane (a riser or a wall cut by something in front of it) lie on one line
  //    seen from above: the line between them is the lever arm of their yaw, and they count as
  //    one plane as wide as they span;
  //  - two distinct planes a tread's going or more apart (two risers, a wall and a riser).
  // Between the two (two parts of one person a few centimetres apart, or anything not on one line
  // with its own direction) they prove nothing. Two faces of one box at right angles (a person,
  // a bin) agree modulo 90 degrees by construction and prove nothing either.
  bool parallel_pair = false;
  const float tan_pair = std::tan(cfg_.pair_tolerance);
  for (std::size_t i = 0; i < candidates.size() && !wide; ++i) {
    const Vote& p = *candidates[i];
    for (std::size_t j = i + 1; j < candidates.size() && !wide; ++j) {
      const Vote& q = *candidates[j];
      float d = std::fmod(std::fabs(p.heading - q.heading), kPi);  // modulo 180 degrees
      d = std::min(d, kPi - d);
      if (d > cfg_.pair_tolerance) continue;
      if (hangs(p) && hangs(q)) continue;
      const float dx = q.cx - p.cx, dz = q.cz - p.cz;
      const float along_normal = std::fabs(p.nx * dx + p.nz * dz);
      const float along_plane = std::fabs(-p.nz * dx + p.nx * dz);
      if (along_normal >= cfg_.pair_min_separation) {
        // Two people turned alike, 10 cm strips of them, agree as well as two risers do (synthetic
        // view, 32 degrees off): one of the two must be half a wide plane's width (a riser or a
        // wall seen in part).
        parallel_pair = parallel_pair || std::max(p.width, q.width) >= 0.5f * cfg_.min_plane_width;
      } else if (along_normal <= along_plane * tan_pair) {
        const float span = along_plane + 0.5f * (p.width + q.width);
        wide = span >= std::max(min_width(p, bounding_only), min_width(q, bounding_only));
      }
    }
  }
  est.vertical_area = agree;
  est.fraction = total_area > 0.f ? agree / total_area : 0.f;
  // No share of the planar area is asked for (the paper's "Manhattan World scene" threshold):
  // a curb's or a single step's riser 1.3 m wide is a sure frame even where the floor around it
  // makes it 2 % of the planar area. Stair modelling asks for its own share before it trusts
  // the frame (StairModellingConfig::manhattan_min_fraction).
  if (agree < cfg_.min_area) {
    est.why = "too little vertical plane area for a Manhattan frame";
    return est;
  }
  // A frame is trusted when a wide plane (a wall, a riser, or strips of one on a line as wide)
  // supports it, or when the agreeing planes agree tightly and two of them are distinct parallel
  // planes (the risers of a flight seen in part, a wall and a riser; one narrow plane, a post or a
  // person, agrees with itself and proves nothing, and a leg or an arm beside it no more).
  // People, posts and the sides of boxes are narrow and agree only to degrees: their yaw is no
  // frame. (The spread check alone refused most real kitchen views, whose walls and
  // cupboards agree only to a few degrees; the width check alone refused a corridor seen as a
  // 35 cm strip of wall.)
  const float wsum = std::max(wsum_agree, 1e-12f);
  const float rbar = std::min(1.f, std::sqrt(sc * sc + ss * ss) / wsum);
  const float spread = 0.25f * std::sqrt(std::max(0.f, -2.f * std::log(std::max(rbar, 1e-6f))));
  if (!wide && (!parallel_pair || spread > cfg_.max_spread)) {
    est.why = "no wide vertical plane, and the narrow ones are one, too narrow or disagree by degrees (no wall or "
              "riser in view, or too little of one to trust)";
    return est;
  }
  const float yaw = manhattan_keep_branch(wrap_quarter(0.25f * std::atan2(ss, sc)), prev_yaw_);
  est.found = true;
  est.yaw = yaw;
  est.T_manhattan_floor = manhattan_pose_from_yaw(yaw);
  return est;
}

}  // namespace stairguide
