#include "stairguide/perception/manhattan_frame.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "manhattan/internal.hpp"

namespace stairguide {

using namespace manhattan_detail;

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
                                                   const Eigen::Vector3f& up,
                                                   const Eigen::Vector3f& n_upright, float clear_depth) {
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
  if (max_range_ > 0.f)
    clear_depth_ = max_range_ - 3.f * std::max(0.f, depth_noise_coeff) * max_range_ * max_range_;
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
    est.why =
        "no wide vertical plane, and the narrow ones are one, too narrow or disagree by degrees (no wall or "
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
