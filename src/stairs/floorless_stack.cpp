// The floorless route, phases "levels", "stack" and "direction" (floorless.hpp, steps 2-4): the
// family's regions grouped into levels, the longest stack of levels one riser apart, which way it
// rises, and the stack's fitted level 0.
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "floorless_internal.hpp"
#include "stairguide/stairs/floorless.hpp"
#include "stairguide/stairs/stair_checks.hpp"

namespace stairguide {

using namespace floorless;

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

std::size_t FloorlessStairs::merge_connected_nodes(std::size_t first, std::size_t used) {
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
  return used;
}

void FloorlessStairs::build_nodes(const SceneResult& scene) {
  const Eigen::Vector3f up = trace_.up;
  height_.resize(family_.size());
  for (std::size_t i = 0; i < family_.size(); ++i)
    height_[i] = up.dot(scene.regions[static_cast<std::size_t>(family_[i])].centroid);
  order_.resize(family_.size());
  std::iota(order_.begin(), order_.end(), 0);
  std::sort(order_.begin(), order_.end(), [&](int a, int b) {
    return height_[static_cast<std::size_t>(a)] < height_[static_cast<std::size_t>(b)];
  });

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
      const int px =
          scene.regions[static_cast<std::size_t>(family_[static_cast<std::size_t>(order_[i])])].pixel_count;
      sum_h *= px;
      sum_w = px;
    }
    while (j < order_.size()) {
      const std::size_t m = static_cast<std::size_t>(order_[j]);
      if (height_[m] - static_cast<float>(sum_h / static_cast<double>(sum_w)) > det_.same_level_tolerance)
        break;
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
    used = merge_connected_nodes(first, used);
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
  std::sort(order_.begin(), order_.end(), [&](int a, int b) {
    return nodes_[static_cast<std::size_t>(a)].height < nodes_[static_cast<std::size_t>(b)].height;
  });
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

void FloorlessStairs::build_stack() {
  // ---- the longest stack of levels one riser apart, each connected to the one below ----
  const std::size_t m = order_.size();
  const float hmin = cls_.step_height_min - det_.height_tolerance;
  const float hmax = step_rise_max(cls_) + det_.height_tolerance;
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
      // level below it, within same_level_tolerance. With the physical riser range (8-27 cm with
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
    if (best_len_[j] > best_len_[end] || (best_len_[j] == best_len_[end] && best_pix_[j] > best_pix_[end]))
      end = j;
  chain_.clear();
  for (int j = static_cast<int>(end); j >= 0; j = best_prev_[static_cast<std::size_t>(j)])
    chain_.push_back(order_[static_cast<std::size_t>(j)]);
  std::reverse(chain_.begin(), chain_.end());  // lowest first
  trace_.stacked = static_cast<int>(chain_.size());
  for (int c : chain_) trace_.level_heights.push_back(nodes_[static_cast<std::size_t>(c)].height);
}

FloorlessStairs::StackDirection FloorlessStairs::stack_direction() {
  // ---- direction: do the levels rise away from the camera or towards it? ----
  // Votes of the pairs below the top level, and the top pair's apart (see below).
  int votes_up = 0, votes_down = 0, top_vote = 0;
  float prev = near_distance(nodes_[static_cast<std::size_t>(chain_[0])]);
  trace_.near_distances.assign(1, prev);
  for (std::size_t k = 1; k < chain_.size(); ++k) {
    const float d = near_distance(nodes_[static_cast<std::size_t>(chain_[k])]);
    trace_.near_distances.push_back(d);
    const int vote = d > prev + kMinRise ? 1 : (d < prev - kMinRise ? -1 : 0);
    if (k + 1 == chain_.size())
      top_vote = vote;
    else if (vote > 0)
      ++votes_up;
    else if (vote < 0)
      ++votes_down;
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
  // A rig's height above it (FloorConfig's rig range), it is the user's floor level: out of the
  // stack, where the cold-start rule below (seen_floor_height) places the flight from it. Left in,
  // the direction is undecided, or modelled it would be one step too many. Two descending pairs
  // at least: one pair is no evidence (the floor strip at the foot of a short climb, seen only in a
  // corner, lies farther than the first tread: floor, tread, landing vote down then up).
  if (dir == 0 && n - 1 >= std::max(3, det_.floorless_min_levels) && top_vote > 0 && votes_up == 0 &&
      votes_down >= std::max(2, n - 3)) {
    const float cam_above = -nodes_[static_cast<std::size_t>(chain_.back())].height;
    const float tol = det_.same_level_tolerance;
    if (cam_above >= floor_.height_min - tol && cam_above <= floor_.height_max + tol) {
      trace_.floor_beside = true;
      chain_.pop_back();
      trace_.level_heights.pop_back();
      trace_.near_distances.pop_back();
      n = static_cast<int>(chain_.size());
      trace_.stacked = n;
      dir = -1;
    }
  }
  // Still none: the user may stand on a landing between two flights.
  if (dir == 0) {
    dir = split_at_landing();
    n = static_cast<int>(chain_.size());
  }
  return {dir, n};
}

int FloorlessStairs::split_at_landing() {
  // On a landing, seen from it: a flight goes on up from it and another goes down from it (an L or
  // U staircase, the user at the turn). Stacked together the levels rise away from the user above
  // the landing and fall away below it, so no one direction holds. The level the user stands on
  // comes nearest (cut by the view's bottom border), every level above it lies farther the higher
  // it is, every level below it farther the lower it is: two flights from the user's level. The
  // one with more levels seen is told (a tie: the one going down, the fall), the landing as its
  // first level, where the cold start asks whether it is the floor (it is, when deeper than a tread).
  const int n = static_cast<int>(chain_.size());
  const std::vector<float> d = trace_.near_distances;  // a copy: trimmed below
  if (n < 3 || static_cast<int>(d.size()) != n) return 0;
  const int u = static_cast<int>(std::min_element(d.begin(), d.end()) - d.begin());
  if (u == 0 || u == n - 1) return 0;
  // A flight leading off to the side of the landing (the lower one of a U, seen past the turn)
  // need not fall away in the view's depth: only a branch that does counts as a flight ahead.
  bool up_ok = true, down_ok = true;
  for (int k = u + 1; k < n; ++k)
    up_ok = up_ok && d[static_cast<std::size_t>(k)] >= d[static_cast<std::size_t>(k - 1)] + kMinRise;
  for (int k = u - 1; k >= 0; --k)
    down_ok = down_ok && d[static_cast<std::size_t>(k)] >= d[static_cast<std::size_t>(k + 1)] + kMinRise;
  // Two levels beyond the landing at least: one pair is no evidence (at the foot of a short climb
  // the floor strip seen in a corner lies farther than the first tread, and the landing farther
  // again: the first tread came nearest, and a flight "down" to the floor strip was told).
  const int up_levels = n - u, down_levels = u + 1;
  up_ok = up_ok && up_levels >= 3;
  down_ok = down_ok && down_levels >= 3;
  if (!up_ok && !down_ok) return 0;
  const bool up = up_ok && (!down_ok || up_levels > down_levels);
  const std::size_t first = up ? static_cast<std::size_t>(u) : 0,
                    last = up ? chain_.size() : static_cast<std::size_t>(u) + 1;
  const std::vector<int> chain = chain_;  // copies: a vector is not assigned from its own range
  chain_.assign(chain.begin() + static_cast<long>(first), chain.begin() + static_cast<long>(last));
  const std::vector<float> heights = trace_.level_heights;
  trace_.level_heights.assign(heights.begin() + static_cast<long>(first),
                              heights.begin() + static_cast<long>(last));
  trace_.near_distances.assign(d.begin() + static_cast<long>(first), d.begin() + static_cast<long>(last));
  trace_.stacked = static_cast<int>(chain_.size());
  trace_.landing_split = true;
  return up ? 1 : -1;
}

FloorlessStairs::StackFit FloorlessStairs::fit_stack_heights(int dir, int n) {
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
  StackFit fit;
  fit.level0 = static_cast<float>((sh - slope * sk) / n);
  fit.riser = std::fabs(static_cast<float>(slope));
  return fit;
}

}  // namespace stairguide
