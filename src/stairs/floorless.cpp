#include "stairguide/stairs/floorless.hpp"

#include "stairguide/stairs/stair_checks.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

namespace stairguide {
namespace {

constexpr int kMinRegionPixels = 100;   // px, smaller regions have too noisy a normal to vote for up
constexpr std::size_t kFitPoints = 500; // points per region in the fit of the common normal
constexpr float kLandingDepth = 0.6f;   // m, a level deeper than this is a landing or a floor
constexpr float kRiserBandSlack = 0.03f;  // m, a riser's height band may pass its levels' heights by this
constexpr float kMinRise = 0.05f;       // m, a higher level's near boundary this much farther (nearer)
                                        // than the lower one's says ascending (descending)
constexpr float kFloorDepthSlack = 0.08f;  // m, a level cut by the image border and seen deeper than
                                           // the tread by this is no tread (nosing, edge noise)
// With the chest moved towards the next level beyond the anchor tolerance (run_anchored), the user
// stands at the first edge: it lies at most kLeanReach ahead of the camera's vertical (the lean
// starts within the last stride before the edge: half a tread in the walks, plus the edge's noise)
// and at most kLeanBehind behind it (a chest camera hangs 10-15 cm ahead of the feet, more when
// leaning; the feet are still before the edge).
constexpr float kLeanReach = 0.35f;   // m
constexpr float kLeanBehind = 0.20f;  // m

float clampf(float x, float lo, float hi) { return std::min(hi, std::max(lo, x)); }

/// Pitch below horizontal and roll of a camera whose "up" is `u` (camera frame: x right, y down,
/// z forward).
void tilt_roll(const Eigen::Vector3f& u, float& tilt, float& roll) {
  tilt = std::asin(clampf(-u.z(), -1.f, 1.f));
  roll = std::atan2(u.x(), -u.y());
}

void copy_region(const PlaneRegion& src, PlaneRegion& dst) {
  // Everything modelling reads; the full-resolution pixel list is not needed and is the bulk.
  dst.id = src.id;
  dst.normal = src.normal;
  dst.offset = src.offset;
  dst.centroid = src.centroid;
  dst.points.assign(src.points.begin(), src.points.end());
  dst.pixels.clear();
  dst.pixel_count = src.pixel_count;
  dst.area = src.area;
  dst.curvature = src.curvature;
  dst.rect_center = src.rect_center;
  dst.rect_axis_major = src.rect_axis_major;
  dst.rect_axis_minor = src.rect_axis_minor;
  dst.rect_length_major = src.rect_length_major;
  dst.rect_length_minor = src.rect_length_minor;
  dst.hull_extent = src.hull_extent;
}

}  // namespace

FloorlessStairs::FloorlessStairs(const ClassificationConfig& classification, const StairDetectionConfig& detection,
                                 const StairModellingConfig& modelling, const FloorConfig& floor)
    : cls_(classification),
      det_(detection),
      mod_(modelling),
      floor_(floor),
      modelling_(classification, detection, modelling) {}

bool FloorlessStairs::find_up(const SceneResult& scene) {
  cand_.clear();
  for (std::size_t i = 0; i < scene.regions.size(); ++i) {
    const PlaneRegion& r = scene.regions[i];
    if (r.points.size() < 10 || r.pixel_count < kMinRegionPixels) continue;
    float tilt = 0.f, roll = 0.f;
    tilt_roll(r.normal, tilt, roll);
    if (std::fabs(roll) > floor_.roll_max || tilt < det_.floorless_tilt_min || tilt > det_.floorless_tilt_max) continue;
    cand_.push_back(static_cast<int>(i));
  }
  if (cand_.empty()) return false;
  // The family with the most pixels: each plausible normal votes with the pixels of the regions
  // parallel to it.
  const float cos_par = std::cos(cls_.parallel_threshold);
  long best_pix = -1;
  int best = -1;
  for (int c : cand_) {
    const Eigen::Vector3f& nc = scene.regions[static_cast<std::size_t>(c)].normal;
    long pix = 0;
    for (int j : cand_)
      if (nc.dot(scene.regions[static_cast<std::size_t>(j)].normal) >= cos_par)
        pix += scene.regions[static_cast<std::size_t>(j)].pixel_count;
    if (pix > best_pix) {
      best_pix = pix;
      best = c;
    }
  }
  const Eigen::Vector3f n0 = scene.regions[static_cast<std::size_t>(best)].normal;
  // The common normal of all the family's planes (paper 5.2): each region centred on its own mean,
  // the direction of least spread of them all. One region's normal is noisy; the family's is not.
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  Eigen::Vector3f mean_normal = Eigen::Vector3f::Zero();
  std::size_t total = 0;
  for (int j : cand_) {
    const PlaneRegion& r = scene.regions[static_cast<std::size_t>(j)];
    if (n0.dot(r.normal) < cos_par) continue;
    mean_normal += r.normal * static_cast<float>(r.pixel_count);
    const std::size_t stride = std::max<std::size_t>(1, r.points.size() / kFitPoints);
    Eigen::Vector3d m = Eigen::Vector3d::Zero();
    std::size_t n = 0;
    for (std::size_t i = 0; i < r.points.size(); i += stride, ++n) m += r.points[i].cast<double>();
    m /= static_cast<double>(n);
    for (std::size_t i = 0; i < r.points.size(); i += stride) {
      const Eigen::Vector3d d = r.points[i].cast<double>() - m;
      scatter += d * d.transpose();
    }
    total += n;
  }
  Eigen::Vector3f up = mean_normal.normalized();
  if (total >= 50) {
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(scatter);
    Eigen::Vector3f fit = es.eigenvectors().col(0).cast<float>().normalized();
    if (fit.dot(up) < 0.f) fit = -fit;
    // A fit far from the normals means the family is not one set of parallel planes.
    if (fit.dot(up) >= std::cos(deg2rad(3.f))) up = fit;
  }
  family_.clear();
  for (int j : cand_)
    if (up.dot(scene.regions[static_cast<std::size_t>(j)].normal) >= cos_par) family_.push_back(j);
  trace_.up = up;
  tilt_roll(up, trace_.tilt, trace_.roll);
  trace_.family_regions = static_cast<int>(family_.size());
  if (std::fabs(trace_.roll) > floor_.roll_max || trace_.tilt < det_.floorless_tilt_min ||
      trace_.tilt > det_.floorless_tilt_max || family_.empty())
    return false;
  trace_.up_found = true;
  return true;
}

void FloorlessStairs::add_to_node(const SceneResult& scene, int region, Node& node) const {
  const PlaneRegion& r = scene.regions[static_cast<std::size_t>(region)];
  const std::size_t n = r.points.size();
  const std::size_t cap = static_cast<std::size_t>(std::max(1, det_.connection_max_points));
  // An even stride keeps the sample spread over the region, as the neighbour test needs; the
  // required count is scaled by the stride so "10 points" keeps its meaning.
  const int stride = std::max(1, static_cast<int>((n + cap - 1) / cap));
  node.stride = std::max(node.stride, stride);
  for (std::size_t i = 0; i < n; i += static_cast<std::size_t>(stride)) {
    node.sample.push_back(r.points[i]);
    node.lo = node.lo.cwiseMin(r.points[i]);
    node.hi = node.hi.cwiseMax(r.points[i]);
  }
  node.regions.push_back(region);
}

bool FloorlessStairs::connected(const Node& a, const Node& b) const {
  const float rad = det_.connection_radius, r2 = rad * rad;
  const int need = std::max(1, (det_.connection_min_points + a.stride - 1) / a.stride);
  const Eigen::Vector3f gap = (b.lo - a.hi).cwiseMax(a.lo - b.hi).cwiseMax(Eigen::Vector3f::Zero());
  if (gap.squaredNorm() > r2) return false;
  const Eigen::Vector3f blo = b.lo.array() - rad, bhi = b.hi.array() + rad;
  int found = 0;
  for (const Eigen::Vector3f& p : a.sample) {
    if ((p.array() < blo.array()).any() || (p.array() > bhi.array()).any()) continue;
    for (const Eigen::Vector3f& q : b.sample) {
      if ((p - q).squaredNorm() <= r2) {
        if (++found >= need) return true;
        break;
      }
    }
  }
  return false;
}

void FloorlessStairs::build_nodes(const SceneResult& scene) {
  const Eigen::Vector3f up = trace_.up;
  height_.resize(family_.size());
  for (std::size_t i = 0; i < family_.size(); ++i)
    height_[i] = up.dot(scene.regions[static_cast<std::size_t>(family_[i])].centroid);
  order_.resize(family_.size());
  std::iota(order_.begin(), order_.end(), 0);
  std::sort(order_.begin(), order_.end(), [&](int a, int b) { return height_[static_cast<std::size_t>(a)] < height_[static_cast<std::size_t>(b)]; });

  std::size_t used = 0;
  auto new_node = [&]() -> Node& {
    if (used >= nodes_.size()) nodes_.emplace_back();
    Node& n = nodes_[used++];
    n.regions.clear();
    n.sample.clear();
    n.height = 0.f;
    n.pixels = 0;
    n.stride = 1;
    n.lo.setConstant(std::numeric_limits<float>::max());
    n.hi.setConstant(-std::numeric_limits<float>::max());
    return n;
  };
  // Heights within the same-level tolerance of a cluster's running mean form one height cluster;
  // inside it, regions joined by connectivity (Algorithm 1's test) form one level. A table top at
  // a tread's height across the room is a level of its own.
  std::size_t i = 0;
  while (i < order_.size()) {
    std::size_t j = i + 1;
    double sum_h = height_[static_cast<std::size_t>(order_[i])];
    long sum_w = 1;
    {
      const int px = scene.regions[static_cast<std::size_t>(family_[static_cast<std::size_t>(order_[i])])].pixel_count;
      sum_h *= px;
      sum_w = px;
    }
    while (j < order_.size()) {
      const std::size_t m = static_cast<std::size_t>(order_[j]);
      if (height_[m] - static_cast<float>(sum_h / static_cast<double>(sum_w)) > det_.same_level_tolerance) break;
      const int px = scene.regions[static_cast<std::size_t>(family_[m])].pixel_count;
      sum_h += static_cast<double>(height_[m]) * px;
      sum_w += px;
      ++j;
    }
    // One node per region of the cluster, then merged while any two are connected.
    const std::size_t first = used;
    for (std::size_t k = i; k < j; ++k) {
      const std::size_t m = static_cast<std::size_t>(order_[k]);
      Node& n = new_node();
      add_to_node(scene, family_[m], n);
      n.pixels = scene.regions[static_cast<std::size_t>(family_[m])].pixel_count;
      n.height = height_[m];
    }
    bool merged = true;
    while (merged) {
      merged = false;
      for (std::size_t a = first; a < used && !merged; ++a) {
        for (std::size_t b = a + 1; b < used && !merged; ++b) {
          if (!connected(nodes_[a], nodes_[b]) && !connected(nodes_[b], nodes_[a])) continue;
          Node& A = nodes_[a];
          Node& B = nodes_[b];
          A.height = (A.height * static_cast<float>(A.pixels) + B.height * static_cast<float>(B.pixels)) /
                     static_cast<float>(A.pixels + B.pixels);
          A.pixels += B.pixels;
          A.regions.insert(A.regions.end(), B.regions.begin(), B.regions.end());
          A.sample.insert(A.sample.end(), B.sample.begin(), B.sample.end());
          A.lo = A.lo.cwiseMin(B.lo);
          A.hi = A.hi.cwiseMax(B.hi);
          A.stride = std::max(A.stride, B.stride);
          std::swap(nodes_[b], nodes_[used - 1]);
          --used;
          merged = true;
        }
      }
    }
    i = j;
  }
  // Levels too small to be a tread seen in part are left out (a box top, a book).
  std::size_t keep = 0;
  for (std::size_t k = 0; k < used; ++k) {
    if (nodes_[k].pixels < det_.floorless_min_level_pixels) continue;
    if (k != keep) std::swap(nodes_[k], nodes_[keep]);
    ++keep;
  }
  order_.resize(keep);
  std::iota(order_.begin(), order_.end(), 0);
  std::sort(order_.begin(), order_.end(),
            [&](int a, int b) { return nodes_[static_cast<std::size_t>(a)].height < nodes_[static_cast<std::size_t>(b)].height; });
  trace_.levels = static_cast<int>(keep);
}

float FloorlessStairs::near_distance(const Node& n) {
  // Distance from the camera's vertical of the level's nearest points (a low quantile: a few
  // strays do not count).
  const Eigen::Vector3f up = trace_.up;
  dist_.clear();
  for (const auto& p : n.sample) dist_.push_back((p - up * up.dot(p)).norm());
  if (dist_.empty()) return 0.f;
  const std::size_t i = dist_.size() / 20;
  std::nth_element(dist_.begin(), dist_.begin() + static_cast<long>(i), dist_.end());
  return dist_[i];
}

void FloorlessStairs::riser_positions(const SceneResult& scene, const StairResult& r, int n, float level0_plane) {
  // Vertical regions facing the user, between two consecutive levels (k: below level k) or above
  // the top one (n + 1), within the staircase's lateral span: where each step starts.
  riser_pos_.assign(static_cast<std::size_t>(n + 2), std::numeric_limits<float>::quiet_NaN());
  riser_n_.assign(static_cast<std::size_t>(n + 2), 0);
  const Eigen::Vector3f xs = r.T_camera_stair.linear().col(0), up = r.T_camera_stair.linear().col(1),
                        zs = r.T_camera_stair.linear().col(2);
  const Eigen::Vector3f o = r.T_camera_stair.translation();
  const float sin_vert = std::sin(cls_.parallel_threshold), cos_face = std::cos(cls_.parallel_threshold);
  const float half = 0.5f * r.width_m;
  for (const PlaneRegion& reg : scene.regions) {
    if (reg.points.size() < 40 || std::fabs(reg.normal.dot(up)) > sin_vert || std::fabs(reg.normal.dot(zs)) < cos_face)
      continue;
    const std::size_t stride = std::max<std::size_t>(1, reg.points.size() / 300);
    tmp_.clear();
    dist_.clear();
    float a_sum = 0.f;
    std::size_t cnt = 0;
    for (std::size_t i = 0; i < reg.points.size(); i += stride, ++cnt) {
      const Eigen::Vector3f d = reg.points[i] - o;
      tmp_.push_back(up.dot(reg.points[i]) - level0_plane);
      dist_.push_back(zs.dot(d));
      a_sum += xs.dot(d);
    }
    const float a_mid = a_sum / static_cast<float>(cnt);
    if (a_mid < -half || a_mid > half) continue;  // beside the staircase
    std::sort(tmp_.begin(), tmp_.end());
    const float h_lo = tmp_[tmp_.size() / 10], h_hi = tmp_[tmp_.size() * 9 / 10];
    int band = 0;
    for (int k = 1; k <= n + 1; ++k) {
      const float below = k == 1 ? 0.f : r.level_data[static_cast<std::size_t>(k - 1)].height;
      const float above = k <= n ? r.level_data[static_cast<std::size_t>(k)].height : below + r.riser_m;
      if (h_lo >= below - 0.03f && h_hi <= above + 0.03f && h_hi - h_lo >= 0.3f * (above - below)) band = k;
    }
    if (band == 0) continue;
    const auto mid = dist_.begin() + static_cast<long>(dist_.size() / 2);
    std::nth_element(dist_.begin(), mid, dist_.end());
    if (static_cast<int>(reg.points.size()) > riser_n_[static_cast<std::size_t>(band)]) {
      riser_n_[static_cast<std::size_t>(band)] = static_cast<int>(reg.points.size());
      riser_pos_[static_cast<std::size_t>(band)] = *mid;
    }
  }
}

void FloorlessStairs::run(const SceneResult& scene, const CameraIntrinsics* K, StairResult& out) {
  trace_ = FloorlessTrace{};
  out.clear(StairVerdict::kNoFloor, 0);
  out.without_floor = true;
  if (!find_up(scene)) return;
  build_nodes(scene);
  const std::size_t m = order_.size();
  out.candidates = static_cast<int>(m);
  out.rejected_candidates = static_cast<int>(m);
  if (m < 2) return;

  // ---- the longest stack of levels one riser apart, each connected to the one below ----
  const float hmin = cls_.step_height_min - det_.height_tolerance;
  const float hmax = cls_.step_height_max + det_.height_tolerance;
  best_len_.assign(m, 1);
  best_prev_.assign(m, -1);
  best_pix_.assign(m, 0);
  for (std::size_t j = 0; j < m; ++j) {
    const Node& b = nodes_[static_cast<std::size_t>(order_[j])];
    best_pix_[j] = b.pixels;
    for (std::size_t i = 0; i < j; ++i) {
      const Node& a = nodes_[static_cast<std::size_t>(order_[i])];
      const float dh = b.height - a.height;
      if (dh < hmin || dh > hmax) continue;
      // A flight has one riser: the next level lies as far above this one as this one above the
      // level below it, within same_level_tolerance. With the world's riser range (8-24 cm with
      // the slack) a seat 9 cm above the last tread of a 19 cm flight would otherwise stack on it
      // (the open-riser captures of labels.csv, a chair in front).
      if (best_prev_[i] >= 0) {
        const float dh_below =
            a.height -
            nodes_[static_cast<std::size_t>(order_[static_cast<std::size_t>(best_prev_[i])])].height;
        if (std::fabs(dh - dh_below) > det_.same_level_tolerance) continue;
      }
      const int len = best_len_[i] + 1;
      const long pix = best_pix_[i] + b.pixels;
      if (len < best_len_[j] || (len == best_len_[j] && pix <= best_pix_[j])) continue;
      if (!connected(b, a) && !connected(a, b)) continue;
      best_len_[j] = len;
      best_pix_[j] = pix;
      best_prev_[j] = static_cast<int>(i);
    }
  }
  std::size_t end = 0;
  for (std::size_t j = 1; j < m; ++j)
    if (best_len_[j] > best_len_[end] || (best_len_[j] == best_len_[end] && best_pix_[j] > best_pix_[end])) end = j;
  chain_.clear();
  for (int j = static_cast<int>(end); j >= 0; j = best_prev_[static_cast<std::size_t>(j)]) chain_.push_back(order_[static_cast<std::size_t>(j)]);
  std::reverse(chain_.begin(), chain_.end());  // lowest first
  trace_.stacked = static_cast<int>(chain_.size());
  for (int c : chain_) trace_.level_heights.push_back(nodes_[static_cast<std::size_t>(c)].height);
  if (static_cast<int>(chain_.size()) < std::max(2, det_.floorless_min_levels)) return;

  // ---- direction: do the levels rise away from the camera or towards it? ----
  // Votes of the pairs below the top level, and the top pair's apart (see below).
  int votes_up = 0, votes_down = 0, top_vote = 0;
  float prev = near_distance(nodes_[static_cast<std::size_t>(chain_[0])]);
  trace_.near_distances.assign(1, prev);
  for (std::size_t k = 1; k < chain_.size(); ++k) {
    const float d = near_distance(nodes_[static_cast<std::size_t>(chain_[k])]);
    trace_.near_distances.push_back(d);
    const int vote = d > prev + kMinRise ? 1 : (d < prev - kMinRise ? -1 : 0);
    if (k + 1 == chain_.size()) top_vote = vote;
    else if (vote > 0) ++votes_up;
    else if (vote < 0) ++votes_down;
    prev = d;
  }
  int n = static_cast<int>(chain_.size());
  // Every pair must agree, but one may tie: a floor strip a few cm deep at the bottom of the view
  // ends where the first riser starts, so its near boundary and the first tread's nearly coincide.
  int dir = 0;
  {
    const int need = std::max(1, n - 2);
    const int up_all = votes_up + (top_vote > 0 ? 1 : 0), down_all = votes_down + (top_vote < 0 ? 1 : 0);
    if (down_all == 0 && up_all >= need) dir = 1;
    if (up_all == 0 && down_all >= need) dir = -1;
  }
  // At the top of a descent seen cold, the floor around the stairwell (beside the flight, and the
  // landing beyond its sides) lies one riser above the first tread seen and joins it at the walls'
  // feet, so the stack takes it as its top level, while the floor under the user is out of view
  // below the first edge. Every lower pair says descending (a higher tread lies nearer), but that
  // level's nearest points are farther than the first tread's: no tread of the flight ahead is.
  // A chest camera's height above it (FloorConfig range), it is the user's floor level: out of the
  // stack, where the cold-start rule below (seen_floor_height) places the flight from it. Left in,
  // the direction is undecided, or modelled it would be one step too many. Two descending pairs
  // at least: one pair is no evidence (the floor strip at the foot of a short climb, seen only in a
  // corner, lies farther than the first tread: floor, tread, landing vote down then up).
  if (dir == 0 && n - 1 >= std::max(3, det_.floorless_min_levels) && top_vote > 0 && votes_up == 0 &&
      votes_down >= std::max(2, n - 3)) {
    const float cam_above = -nodes_[static_cast<std::size_t>(chain_.back())].height;
    const float tol = det_.same_level_tolerance;
    if (cam_above >= floor_.usual_height_min - tol && cam_above <= floor_.usual_height_max + tol) {
      trace_.floor_beside = true;
      chain_.pop_back();
      trace_.level_heights.pop_back();
      trace_.near_distances.pop_back();
      n = static_cast<int>(chain_.size());
      trace_.stacked = n;
      dir = -1;
    }
  }
  trace_.direction = dir;
  out.kind = StairKind::kNone;
  out.levels = n;
  if (dir == 0) {
    out.verdict = StairVerdict::kInconsistentEdges;
    return;
  }

  // ---- pseudo floor frame: the common normal, a virtual level 0 one riser beyond the first ----
  // Seen levels in stair order (ascending: lowest first; descending: highest first), their heights
  // fitted against the index; the virtual level sits where that line meets index 0, so it adds
  // nothing to modelling's fit of the riser.
  if (dir < 0) std::reverse(chain_.begin(), chain_.end());
  double sk = 0, sh = 0, skk = 0, skh = 0;
  for (int k = 1; k <= n; ++k) {
    const double h = nodes_[static_cast<std::size_t>(chain_[static_cast<std::size_t>(k - 1)])].height;
    sk += k;
    sh += h;
    skk += static_cast<double>(k) * k;
    skh += k * h;
  }
  const double slope = (n * skh - sk * sh) / (n * skk - sk * sk);
  const float level0 = static_cast<float>((sh - slope * sk) / n);
  const float riser = std::fabs(static_cast<float>(slope));
  if (scene.remembered_camera_height > 0.f) {
    run_anchored(scene, K, dir, riser, level0, scene.remembered_camera_height, out);
    out.floor_remembered = !out.without_floor;  // placed from the feet
    return;
  }
  // Cold start, but the floor the user stands on may be in view outside the stack: perception
  // refused it (the top of a descent: the treads below look nearer the user's feet; a floor strip
  // that might be a tread), and the stack does not reach it because the first steps are hidden
  // (self-occluded below a descending edge, under the view at the foot of a climb). A level a
  // chest camera's height below the camera and a whole number of risers from the first seen level
  // places the steps from the feet as a remembered height would. Without it, the checks below
  // settle whether the first seen level is the floor; otherwise its step number is unknown and the
  // stack is reported without_floor or refused.
  const float seen = seen_floor_height(dir, riser);
  if (seen > 0.f) {
    trace_.floor_seen = true;
    run_anchored(scene, K, dir, riser, level0, seen, out);
    return;
  }
  // Two levels seen cold with nothing placing the user's feet: a curb or a single step whose floor
  // perception refused because it could not tell which of the two the user stands on. The one
  // pair's direction compares where the levels come nearest the user, and on an edge seen
  // obliquely that is where the view's border cuts them: a curb going up, seen at 21 deg with the
  // sidewalk filling the view and the street only in a corner, came out as stairs going down
  // (held-out seed 1 curb #4). Going down, the face between the two levels turns away from the
  // user; an upright face seen between their heights says the step rises away from the user, and
  // a direction the scene contradicts is not reported.
  if (n == 2 && dir < 0 &&
      riser_between(scene, nodes_[static_cast<std::size_t>(chain_.back())].height,
                    nodes_[static_cast<std::size_t>(chain_.front())].height)) {
    trace_.riser_against = true;
    out.detected = false;
    out.verdict = StairVerdict::kNoFloor;  // without it, which way the step goes is not settled
    return;
  }
  model(scene, K, dir, 0, level0, out);
  // Cold start: is the first level seen the first step, or the floor the user stands on (seen, but
  // refused by the floor detector: a level camera, a floor strip at the foot of the steps)? The
  // floor runs to the user's feet, so its near boundary is the image border; a first step whose
  // nosing is in view is no floor. Cut by the border, a tread shows at most its own depth: a level
  // deeper than the tread measured on the others is the floor. Shallower, nothing in one frame
  // tells a floor strip from a tread seen from above unless the camera's height rules one out.
  // Either way a staircase lies ahead in that direction: it is reported `without_floor` (which
  // step is the first, and how far, unknown) rather than withheld (issue 39: a wearer standing at
  // the foot of a flight that fills the view was told nothing).
  if (out.level_data.size() < 2) return;
  {
    const StairLevel& l1 = out.level_data[1];
    const float y = dir > 0 ? 0.f : l1.height;  // the level's height in the stair frame
    trace_.first_near_cut = K && line_cut(*K, out, 1, y, l1.depth_min);
  }
  if (!trace_.first_near_cut) return;
  const float depth = out.level_data[1].depth_max - out.level_data[1].depth_min;
  trace_.first_depth = depth;
  // Seen at a chest camera's pitch (the floor detector's range), the floor the user stands on lies
  // a chest camera's height below it (the same detector's range): a level nearer the camera, or
  // farther, is a step whatever its depth. A camera held level (a hand-held or tripod view) says
  // nothing of its height: there the rule does not apply.
  const float cam_above = -nodes_[static_cast<std::size_t>(chain_[0])].height;
  const bool chest_view = trace_.tilt >= floor_.usual_tilt_min && trace_.tilt <= floor_.usual_tilt_max;
  // Every tread of a flight has the same depth (building codes allow about 1 cm between the
  // deepest and the shallowest), so a level seen deeper than the fitted tread plus the measuring
  // slack is no tread of this flight: it is the floor. From a chest camera the level cut by the
  // bottom border lies within a metre or so of the camera and its depth is measured to a few cm;
  // only from a camera held level, whose lowest rows look far and grazing, is anything shallower
  // than a landing left undecided.
  const float floor_depth = chest_view && out.tread_m > 0.f ? out.tread_m + kFloorDepthSlack
                                                             : std::max(kLandingDepth, out.tread_m + kFloorDepthSlack);
  const bool deep = depth > floor_depth;
  const bool floor_height = cam_above >= floor_.usual_height_min - det_.same_level_tolerance &&
                            cam_above <= floor_.usual_height_max + det_.same_level_tolerance;
  if (chest_view && !floor_height) return;
  // The other way round: were the level a first tread, the user's floor would lie one riser
  // below it (ascending) or above it (descending); outside a chest camera's height range that
  // cannot be the user's floor, so the level is.
  const float tread_cam = cam_above + static_cast<float>(dir) * out.riser_m;
  const bool tread_height = tread_cam >= floor_.usual_height_min - det_.same_level_tolerance &&
                            tread_cam <= floor_.usual_height_max + det_.same_level_tolerance;
  if (!deep && (!chest_view || tread_height)) {
    // Seen from a wearer's rig (its tilt range) the staircase is told, its first step unknown. A
    // camera held level (a hand-held or tripod view, no wearer) keeps the old refusal: its model
    // of a floor strip and open treads came out inconsistent (treads of -39 to 70 cm).
    const bool rig_view = trace_.tilt >= floor_.tilt_min && trace_.tilt <= floor_.tilt_max;
    // Modelled on the first level as the floor, the origin lies on a true edge whichever it is:
    // the level's far side is riser 1 if it is the floor, riser 2 if it is the first tread. The
    // count is what stays unknown.
    if (rig_view && model_on_floor_level(scene, K, dir, out)) {
      out.without_floor = true;
      return;
    }
    out.detected = false;
    out.verdict = StairVerdict::kNoFirstStep;
    return;
  }
  model_on_floor_level(scene, K, dir, out);
}

bool FloorlessStairs::riser_between(const SceneResult& scene, float h_lo, float h_hi) {
  const Eigen::Vector3f& up = trace_.up;
  const float sin_vert = std::sin(cls_.parallel_threshold);
  for (const PlaneRegion& r : scene.regions) {
    if (r.points.size() < 40 || std::fabs(r.normal.dot(up)) > sin_vert) continue;
    const std::size_t stride = std::max<std::size_t>(1, r.points.size() / 300);
    tmp_.clear();
    for (std::size_t i = 0; i < r.points.size(); i += stride) tmp_.push_back(up.dot(r.points[i]));
    std::sort(tmp_.begin(), tmp_.end());
    // Its height band (10th to 90th percentile) within the pair's, over a third of the riser.
    const float lo = tmp_[tmp_.size() / 10], hi = tmp_[tmp_.size() * 9 / 10];
    if (lo >= h_lo - kRiserBandSlack && hi <= h_hi + kRiserBandSlack && hi - lo >= (h_hi - h_lo) / 3.f) return true;
  }
  return false;
}

bool FloorlessStairs::model_on_floor_level(const SceneResult& scene, const CameraIntrinsics* K, int dir,
                                           StairResult& out) {
  trace_.floor_level = true;
  const int n = static_cast<int>(chain_.size());
  if (n - 1 < std::max(2, det_.floorless_min_levels)) {
    // A floor and one level on it: the single-level case needs the real floor (paper 4.1).
    out.detected = false;
    out.verdict = StairVerdict::kNoFloor;
    out.levels = n - 1;
    return false;
  }
  model(scene, K, dir, 1, nodes_[static_cast<std::size_t>(chain_[0])].height, out);
  return true;
}

float FloorlessStairs::seen_floor_height(int dir, float riser) const {
  if (chain_.empty() || riser <= 0.f) return 0.f;
  const float h0 = nodes_[static_cast<std::size_t>(chain_[0])].height;
  const float tol = det_.same_level_tolerance;
  const int kmax = 1 + std::max(0, det_.floorless_max_hidden_steps);
  float best = 0.f;
  int best_pixels = 0;
  for (int i : order_) {
    if (std::find(chain_.begin(), chain_.end(), i) != chain_.end()) continue;
    const Node& f = nodes_[static_cast<std::size_t>(i)];
    const float cam_above = -f.height;
    if (cam_above < floor_.usual_height_min - tol || cam_above > floor_.usual_height_max + tol) continue;
    // On the user's side of the flight: below its first level ascending, above it descending.
    const float a0 = static_cast<float>(dir) * (h0 - f.height);
    const int k = static_cast<int>(std::lround(a0 / riser));
    if (k < 1 || k > kmax || std::fabs(a0 - static_cast<float>(k) * riser) > det_.floorless_anchor_tolerance) continue;
    if (f.pixels > best_pixels) {
      best_pixels = f.pixels;
      best = cam_above;
    }
  }
  return best;
}

void FloorlessStairs::run_anchored(const SceneResult& scene, const CameraIntrinsics* K, int dir, float riser,
                                   float level0, float camera_height, StairResult& out) {
  // The feet lie `camera_height` below the camera along up (the camera sits at up . p = 0).
  // chain_ is in stair order: chain_[0] is the first level seen from the user.
  trace_.anchored = true;
  const int n = static_cast<int>(chain_.size());
  const float h0 = nodes_[static_cast<std::size_t>(chain_[0])].height;
  const float a0 = static_cast<float>(dir) * (h0 + camera_height);
  trace_.first_offset = a0;
  const int kmax = 1 + std::max(0, det_.floorless_max_hidden_steps);
  const float tol = det_.floorless_anchor_tolerance;
  int k = riser > 0.f ? static_cast<int>(std::lround(a0 / riser)) : -1;
  out.levels = n;
  bool lean = false;
  if (riser > 0.f && std::fabs(a0 - static_cast<float>(k) * riser) > tol) {
    // The remembered height is the camera's over the feet of a user standing upright. Stepping
    // onto the next level, the chest starts moving towards it (up a climb, down a descent) before
    // the foot leaves the floor: by the time the foot reaches the edge it has gone up to half a
    // riser. The first level seen then lies k risers from the feet less that lean: k is the
    // next whole number of risers beyond the tolerance, the lean at most half a riser (plus
    // half the tolerance). A user whose chest has moved that far must stand at the first edge,
    // which the model checks below.
    k = static_cast<int>(std::floor((a0 + tol) / riser)) + 1;
    const float d = static_cast<float>(k) * riser - a0;
    lean = d > tol && d <= 0.5f * (riser + tol);
    if (lean) trace_.lean = d;
    else k = -1;
  }
  // A chest camera hangs ahead of the feet: with the user at the first edge it is over the first
  // tread, and one more step lies under the view; going down, the levels lie deeper and the view's
  // lowest rays reach them farther ahead, one more again (a high camera sees the first level 3
  // risers up at the foot of a climb, 4 down at the top of a descent). Those are allowed only
  // where the model puts the first edge at the camera's vertical, as for a lean.
  const bool extra_hidden = k > kmax;
  if (k < 0 || k > kmax + 1 + (dir < 0 ? 1 : 0)) {
    // Not a whole number of risers from the feet (or too many steps hidden): a stack of shelves,
    // furniture, or a staircase the remembered height no longer fits. Nothing is reported.
    out.detected = false;
    out.verdict = StairVerdict::kNoFirstStep;
    return;
  }
  trace_.first_index = k;
  if (k == 0) {
    // The floor itself is in the stack (seen, but refused by the floor detector): level 0.
    if (!model_on_floor_level(scene, K, dir, out)) return;
  } else {
    // Level 0 of the fit lies one riser before the first seen level: the floor when k = 1 (the
    // fit's, within the tolerance of the remembered one), the last hidden step otherwise.
    model(scene, K, dir, 0, level0, out);
    if (k >= 2 && out.detected) {
      if (out.tread_m > 0.f) {
        add_hidden_steps(out, dir, k - 1);
      } else {
        // Where the hidden steps' edges lie needs the tread.
        out.detected = false;
        out.verdict = StairVerdict::kNoFirstStep;
      }
    }
  }
  out.without_floor = false;
  if ((lean || extra_hidden) && out.detected) {
    // The chest leans towards the next level only in the last stride before its edge: the first
    // edge must lie that near ahead of the camera's vertical (not behind it: the feet would be on
    // the step). Farther, the stack is not k risers from these feet (shelves, furniture, or a
    // remembered height that no longer fits) and nothing is reported rather than a step off.
    const Eigen::Vector3f zs = out.T_camera_stair.linear().col(2);
    const float ahead = zs.dot(out.T_camera_stair.translation());
    trace_.lean_edge_ahead = ahead;
    if (ahead < -kLeanBehind || ahead > kLeanReach) {
      out.detected = false;
      out.verdict = StairVerdict::kNoFirstStep;
      trace_.first_index = -1;
    }
  }
}

void FloorlessStairs::add_hidden_steps(StairResult& out, int dir, int hidden) {
  // The model's level 0 was step `hidden` and its origin step hidden + 1's edge (ascending) or
  // step hidden's far edge (descending): both move `hidden` treads towards the user and `hidden`
  // risers towards the floor.
  const Eigen::Vector3f ys = out.T_camera_stair.linear().col(1), zs = out.T_camera_stair.linear().col(2);
  const float dz = static_cast<float>(hidden) * out.tread_m, dy = static_cast<float>(hidden) * out.riser_m;
  const Eigen::Vector3f move = -static_cast<float>(dir) * dy * ys - dz * zs;
  out.T_camera_stair.translation() += move;
  out.edge_left += move;
  out.edge_right += move;
  for (std::size_t k = 1; k < out.level_data.size(); ++k) {
    StairLevel& l = out.level_data[k];
    l.edge += dz;
    l.depth_min += dz;
    l.depth_max += dz;
    l.height += static_cast<float>(dir) * dy;
    l.index += dir * hidden;
  }
}

void FloorlessStairs::model(const SceneResult& scene, const CameraIntrinsics* K, int dir, int first, float level0,
                            StairResult& out) {
  // Steps are chain_[first..] in stair order; level 0 is virtual, at `level0` (up . p).
  const std::size_t m = order_.size();
  const int n = static_cast<int>(chain_.size()) - first;
  level0_ = level0;
  const Eigen::Vector3f up = trace_.up;
  Eigen::Vector3f fwd = Eigen::Vector3f::UnitZ() - up * up.z();
  if (fwd.norm() < 1e-3f) fwd = -Eigen::Vector3f::UnitY() - up * (-up.y());
  fwd.normalize();
  const Eigen::Vector3f left = up.cross(fwd).normalized();
  pseudo_.floor_found = true;
  pseudo_.why.clear();
  pseudo_.T_floor_camera.setIdentity();
  pseudo_.T_floor_camera.linear().row(0) = left.transpose();
  pseudo_.T_floor_camera.linear().row(1) = up.transpose();
  pseudo_.T_floor_camera.linear().row(2) = fwd.transpose();
  pseudo_.T_floor_camera.translation() = Eigen::Vector3f(0.f, -level0, 0.f);
  pseudo_.camera_height = -level0;
  pseudo_.camera_tilt = trace_.tilt;
  pseudo_.camera_roll = trace_.roll;
  pseudo_.floor_region = -1;
  pseudo_.manhattan_found = false;  // the Manhattan frame hangs on the floor: the steps' own axes
  pseudo_.T_manhattan_floor.setIdentity();
  pseudo_.manhattan_yaw = pseudo_.manhattan_fraction = 0.f;
  pseudo_.clusters.clear();

  // Only the regions modelling reads: the stacked levels' and the vertical ones (risers).
  index_map_.clear();
  std::size_t used = 0;
  auto take = [&](int region, RegionClass cls) {
    if (used >= pseudo_.regions.size()) pseudo_.regions.emplace_back();
    PlaneRegion& dst = pseudo_.regions[used++];
    const PlaneRegion& src = scene.regions[static_cast<std::size_t>(region)];
    copy_region(src, dst);
    dst.cls = cls;
    dst.height = up.dot(src.centroid) - level0;
    index_map_.push_back(region);
    return static_cast<int>(used - 1);
  };
  hyp_.direction = dir;
  hyp_.verdict = StairVerdict::kDetected;
  hyp_.candidates = static_cast<int>(m);
  hyp_.rejected = static_cast<int>(m) - n;
  hyp_.levels.resize(static_cast<std::size_t>(n + 1));
  hyp_.levels[0].index = 0;
  hyp_.levels[0].height = 0.f;
  hyp_.levels[0].point_count = 0;
  hyp_.levels[0].regions.clear();
  for (int k = 1; k <= n; ++k) {
    const Node& node = nodes_[static_cast<std::size_t>(chain_[static_cast<std::size_t>(k - 1 + first)])];
    LevelSeed& l = hyp_.levels[static_cast<std::size_t>(k)];
    l.index = k;
    l.height = node.height - level0;
    l.point_count = node.pixels;
    l.regions.clear();
    for (int r : node.regions) l.regions.push_back(take(r, RegionClass::kStepCandidate));
  }
  const float sin_vert = std::sin(cls_.parallel_threshold);
  for (std::size_t i = 0; i < scene.regions.size(); ++i) {
    const PlaneRegion& r = scene.regions[i];
    if (r.points.size() >= 40 && std::fabs(r.normal.dot(up)) <= sin_vert) take(static_cast<int>(i), RegionClass::kVertical);
  }
  pseudo_.regions.resize(used);

  modelling_.run(pseudo_, hyp_, out, K);
  out.without_floor = true;
  out.candidates = static_cast<int>(m);
  out.rejected_candidates = hyp_.rejected;
  for (auto& l : out.level_data)
    for (int& r : l.regions) r = index_map_[static_cast<std::size_t>(r)];
  refine_edges(scene, K, dir, n, out);
}

bool FloorlessStairs::edge_cut(const CameraIntrinsics& K, const StairResult& r, int k, float y) const {
  return line_cut(K, r, k, y, r.level_data[static_cast<std::size_t>(k)].edge);
}

bool FloorlessStairs::line_cut(const CameraIntrinsics& K, const StairResult& r, int k, float y, float z) const {
  // Samples along the line across the level: where most lie on (or beyond) the image border, the
  // level's boundary there is where the view ends, not where the level does.
  const StairLevel& l = r.level_data[static_cast<std::size_t>(k)];
  const float margin = 0.03f * static_cast<float>(std::max(K.width, K.height));
  int cut = 0;
  constexpr int kSamples = 9;
  for (int i = 0; i < kSamples; ++i) {
    const float a = l.lateral_min + (l.lateral_max - l.lateral_min) * (static_cast<float>(i) + 0.5f) / kSamples;
    const Eigen::Vector3f p = r.T_camera_stair * Eigen::Vector3f(a, y, z);
    if (p.z() < 0.05f) {
      ++cut;
      continue;
    }
    const float u = K.fx * p.x() / p.z() + K.cx, v = K.fy * p.y() / p.z() + K.cy;
    if (u < margin || v < margin || u > static_cast<float>(K.width) - margin || v > static_cast<float>(K.height) - margin)
      ++cut;
  }
  return 2 * cut >= kSamples;
}

void FloorlessStairs::refine_edges(const SceneResult& scene, const CameraIntrinsics* K, int dir, int n, StairResult& out) {
  // Modelling measured each level's step edge from its points. Without a floor the first seen
  // level often runs out of the image (the tread under the camera, or the floor itself when the
  // floor detector refused it), and its "edge" is then the image border: the tread and the origin
  // would follow it. Only edges seen inside the image are used here, with the risers facing the
  // user (ascending), including the one above the top level, which modelling does not use.
  const StairVerdict v = out.verdict;
  const bool refit = v == StairVerdict::kDetected || v == StairVerdict::kTreadTooShort ||
                     v == StairVerdict::kBlondelOutOfRange || v == StairVerdict::kInconsistentEdges;
  if (!refit || static_cast<int>(out.level_data.size()) != n + 1) return;
  const float y_origin = dir > 0 ? out.level_data[1].height : 0.f;
  edge_k_.clear();
  edge_e_.clear();
  if (dir > 0) {
    riser_positions(scene, out, n, level0_);
  } else {
    riser_pos_.assign(static_cast<std::size_t>(n + 2), std::numeric_limits<float>::quiet_NaN());
  }
  // Nosing: the tread edge's offset from its riser where both are seen and agree.
  tmp_.clear();
  for (int k = 1; k <= n; ++k) {
    const float d = out.level_data[static_cast<std::size_t>(k)].edge - riser_pos_[static_cast<std::size_t>(k)];
    const bool seen = !K || !edge_cut(*K, out, k, out.level_data[static_cast<std::size_t>(k)].height - y_origin);
    if (seen && std::isfinite(d) && d >= -0.02f && d <= 0.05f) tmp_.push_back(d);
  }
  float nosing = 0.f;
  if (!tmp_.empty()) {
    std::sort(tmp_.begin(), tmp_.end());
    nosing = tmp_[tmp_.size() / 2];
  }
  const int last = dir > 0 ? n + 1 : n;
  for (int k = 1; k <= last; ++k) {
    const float rk = riser_pos_[static_cast<std::size_t>(k)];
    float e = std::numeric_limits<float>::quiet_NaN();
    if (std::isfinite(rk)) {
      e = rk + nosing;
    } else if (k <= n) {
      const StairLevel& l = out.level_data[static_cast<std::size_t>(k)];
      // The lowest level of an ascending stack deeper than a landing is the floor (or a landing)
      // seen from on it: its near side is the user's side, no step edge.
      const bool floor_like = dir > 0 && k == 1 && l.depth_max - l.depth_min > kLandingDepth;
      if (!floor_like && (!K || !edge_cut(*K, out, k, l.height - y_origin))) e = l.edge;
    }
    if (!std::isfinite(e)) continue;
    edge_k_.push_back(static_cast<float>(k));
    edge_e_.push_back(e);
  }
  trace_.edges_seen = static_cast<int>(edge_k_.size());
  float shift = 0.f;  // new origin along z_S, in the current stair frame
  if (edge_k_.size() >= 2) {
    // Consensus, as modelling does: the line through two edges that most edges lie near (within
    // edge_max_residual), refitted to those; two thirds of the edges must agree.
    const std::size_t q = edge_k_.size();
    std::size_t best_in = 0;
    float best_res = std::numeric_limits<float>::max(), best_slope = 0.f, best_icpt = 0.f;
    for (std::size_t i = 0; i < q; ++i) {
      for (std::size_t j = i + 1; j < q; ++j) {
        const float sl = (edge_e_[j] - edge_e_[i]) / (edge_k_[j] - edge_k_[i]);
        const float ic = edge_e_[i] - sl * edge_k_[i];
        std::size_t in = 0;
        float res = 0.f;
        for (std::size_t k = 0; k < q; ++k) {
          const float d = std::fabs(edge_e_[k] - (ic + sl * edge_k_[k]));
          if (d <= mod_.edge_max_residual) {
            ++in;
            res += d;
          }
        }
        if (in > best_in || (in == best_in && res < best_res)) {
          best_in = in;
          best_res = res;
          best_slope = sl;
          best_icpt = ic;
        }
      }
    }
    double sk = 0, se = 0, skk = 0, ske = 0, cnt = 0;
    for (std::size_t i = 0; i < q; ++i) {
      if (std::fabs(edge_e_[i] - (best_icpt + best_slope * edge_k_[i])) > mod_.edge_max_residual) continue;
      sk += edge_k_[i];
      se += edge_e_[i];
      skk += static_cast<double>(edge_k_[i]) * edge_k_[i];
      ske += static_cast<double>(edge_k_[i]) * edge_e_[i];
      cnt += 1;
    }
    const double den = cnt * skk - sk * sk;
    const float slope = std::fabs(den) > 1e-9 ? static_cast<float>((cnt * ske - sk * se) / den) : best_slope;
    const float icpt = std::fabs(den) > 1e-9 ? static_cast<float>((se - slope * sk) / cnt) : best_icpt;
    out.tread_m = slope;
    shift = dir > 0 ? icpt + slope : icpt;
    if (best_in < 2 || 3 * best_in < 2 * q) {
      out.detected = false;
      out.verdict = StairVerdict::kInconsistentEdges;
      return;
    }
  } else {
    // One edge or none seen: the tread is unknown. The origin stays on the first level's seen
    // boundary unless its edge is seen.
    out.tread_m = 0.f;
    if (edge_k_.size() == 1 && edge_k_[0] == 1.f) shift = edge_e_[0];
  }
  if (shift != 0.f) {
    const Eigen::Vector3f zs = out.T_camera_stair.linear().col(2);
    out.T_camera_stair.translation() += zs * shift;
    out.edge_left += zs * shift;
    out.edge_right += zs * shift;
    for (int k = 1; k <= n; ++k) {
      StairLevel& l = out.level_data[static_cast<std::size_t>(k)];
      l.edge -= shift;
      l.depth_min -= shift;
      l.depth_max -= shift;
    }
  }
  // Validation again, as modelling does, with the tread from the seen edges (none when unknown).
  StairDimensions dims;
  dims.riser = out.riser_m;
  dims.tread = out.tread_m;
  dims.tread_known = edge_k_.size() >= 2;
  dims.width = out.width_m;
  dims.width_complete = out.width_complete;
  dims.range = out.T_camera_stair.translation().norm();
  out.verdict = check_walkable(dims, mod_.dimension_tolerance, mod_.tread_tolerance_per_m2);
  out.code_notes = describe_against_code(dims, true, mod_);
  out.detected = out.verdict == StairVerdict::kDetected;
}

}  // namespace stairguide
