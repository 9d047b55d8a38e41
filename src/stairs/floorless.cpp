#include "stairguide/stairs/floorless.hpp"

#include "floorless_internal.hpp"

#include "stairguide/stairs/stair_checks.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

namespace stairguide {

using namespace floorless;

namespace {

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

// m, slack on a foot's depth (WalkableLimits::tread_min) for a level's mean depth (its area over
// its length: hull areas of noisy points).
constexpr float kFootSlack = 0.02f;
// A region reaches the bottom of the view when its lowest row (as y/z) is within this of the
// lowest any region reaches (about 10 px at a 525 px focal length).
constexpr float kViewBottomSlack = 0.02f;

// Going up with the tread unknown (fewer than two step edges seen), a level below the top one,
// seen whole (not cut by the bottom of the view), whose mean depth (area over its length) is less
// than a foot's: nothing stands on it. A bed frame's rim 3-5 cm wide round the mattress was the
// first "step" of a two-level flight (world2_bed seed 1003 #8: rim pieces 3.6 and 1.3 cm deep on
// average, perception's floor doubted, the remembered camera height placing the flight).
bool level_too_shallow(const SceneResult& scene, int dir, int n, const StairResult& out) {
  if (dir <= 0 || n < 2 || static_cast<int>(out.level_data.size()) != n + 1) return false;
  auto lowest_row = [](const PlaneRegion& r) {
    float low = -std::numeric_limits<float>::max();
    for (const Eigen::Vector3f& p : r.points)
      if (p.z() > 0.05f) low = std::max(low, p.y() / p.z());
    return low;
  };
  float bottom = -std::numeric_limits<float>::max();
  for (const PlaneRegion& r : scene.regions) bottom = std::max(bottom, lowest_row(r));
  for (int k = 1; k < n; ++k) {
    float area = 0.f, length = 0.f;
    bool cut = false;
    for (int i : out.level_data[static_cast<std::size_t>(k)].regions) {
      if (i < 0 || i >= static_cast<int>(scene.regions.size())) return false;
      const PlaneRegion& r = scene.regions[static_cast<std::size_t>(i)];
      area += r.area;
      length = std::max(length, r.rect_length_major);
      cut = cut || lowest_row(r) >= bottom - kViewBottomSlack;
    }
    if (!cut && length > 0.f && area / length < WalkableLimits{}.tread_min - kFootSlack) return true;
  }
  return false;
}

}  // namespace

FloorlessStairs::FloorlessStairs(const ClassificationConfig& classification,
                                 const StairDetectionConfig& detection, const StairModellingConfig& modelling,
                                 const FloorConfig& floor)
    : cls_(classification),
      det_(detection),
      mod_(modelling),
      floor_(floor),
      modelling_(classification, detection, modelling) {}

void FloorlessStairs::riser_positions(const SceneResult& scene, const StairResult& r, int n,
                                      float level0_plane) {
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
    if (reg.points.size() < 40 || std::fabs(reg.normal.dot(up)) > sin_vert ||
        std::fabs(reg.normal.dot(zs)) < cos_face)
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
  build_stack();
  if (static_cast<int>(chain_.size()) < std::max(2, det_.floorless_min_levels)) return;
  const StackDirection sd = stack_direction();
  const int dir = sd.dir, n = sd.n;
  trace_.direction = dir;
  out.kind = StairKind::kNone;
  out.levels = n;
  if (dir == 0) {
    out.verdict = StairVerdict::kInconsistentEdges;
    return;
  }
  const StackFit fit = fit_stack_heights(dir, n);
  if (scene.remembered_camera_height > 0.f) {
    run_anchored(scene, K, dir, fit.riser, fit.level0, scene.remembered_camera_height, out);
    out.floor_remembered = !out.without_floor;  // placed from the feet
    return;
  }
  run_cold(scene, K, dir, n, fit, out);
}

void FloorlessStairs::model(const SceneResult& scene, const CameraIntrinsics* K, int dir, int first,
                            float level0, StairResult& out) {
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
    if (r.points.size() >= 40 && std::fabs(r.normal.dot(up)) <= sin_vert)
      take(static_cast<int>(i), RegionClass::kVertical);
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

bool FloorlessStairs::line_cut(const CameraIntrinsics& K, const StairResult& r, int k, float y,
                               float z) const {
  // Samples along the line across the level: where most lie on (or beyond) the image border, the
  // level's boundary there is where the view ends, not where the level does.
  const StairLevel& l = r.level_data[static_cast<std::size_t>(k)];
  const float margin = 0.03f * static_cast<float>(std::max(K.width, K.height));
  int cut = 0;
  constexpr int kSamples = 9;
  for (int i = 0; i < kSamples; ++i) {
    const float a =
        l.lateral_min + (l.lateral_max - l.lateral_min) * (static_cast<float>(i) + 0.5f) / kSamples;
    const Eigen::Vector3f p = r.T_camera_stair * Eigen::Vector3f(a, y, z);
    if (p.z() < 0.05f) {
      ++cut;
      continue;
    }
    const float u = K.fx * p.x() / p.z() + K.cx, v = K.fy * p.y() / p.z() + K.cy;
    if (u < margin || v < margin || u > static_cast<float>(K.width) - margin ||
        v > static_cast<float>(K.height) - margin)
      ++cut;
  }
  return 2 * cut >= kSamples;
}

void FloorlessStairs::refine_edges(const SceneResult& scene, const CameraIntrinsics* K, int dir, int n,
                                   StairResult& out) {
  // Modelling measured each level's step edge from its points. Without a floor the first seen
  // level often runs out of the image (the tread under the camera, or the floor itself when the
  // floor detector refused it), and its "edge" is then the image border: the tread and the origin
  // would follow it. Only edges seen inside the image are used here, with the risers facing the
  // user (ascending), including the one above the top level, which modelling does not use.
  const StairVerdict v = out.verdict;
  const bool refit = v == StairVerdict::kDetected || v == StairVerdict::kTreadTooShort ||
                     v == StairVerdict::kBlondelOutOfRange || v == StairVerdict::kInconsistentEdges;
  if (!refit || static_cast<int>(out.level_data.size()) != n + 1) return;
  collect_seen_edges(scene, K, dir, n, out);
  float shift = 0.f;  // new origin along z_S, in the current stair frame
  if (edge_k_.size() >= 2) {
    if (!fit_seen_edges(dir, out, shift)) return;
  } else {
    // One edge or none seen: the tread is unknown. The origin stays on the first level's seen
    // boundary unless its edge is seen.
    out.tread_m = 0.f;
    if (edge_k_.size() == 1 && edge_k_[0] == 1.f) shift = edge_e_[0];
  }
  if (shift != 0.f) shift_origin(n, shift, out);
  // Validation again, as modelling does, with the tread from the seen edges (none when unknown).
  StairDimensions dims;
  dims.riser = out.riser_m;
  dims.tread = out.tread_m;
  dims.tread_known = edge_k_.size() >= 2;
  dims.width = out.width_m;
  dims.width_complete = out.width_complete;
  dims.range = out.T_camera_stair.translation().norm();
  out.verdict = check_walkable(dims, mod_.dimension_tolerance, mod_.tread_tolerance_per_m2);
  if (out.verdict == StairVerdict::kDetected && !dims.tread_known && level_too_shallow(scene, dir, n, out))
    out.verdict = StairVerdict::kTreadTooShort;
  out.code_notes = describe_against_code(dims, true, mod_);
  out.detected = out.verdict == StairVerdict::kDetected;
}

void FloorlessStairs::collect_seen_edges(const SceneResult& scene, const CameraIntrinsics* K, int dir, int n,
                                         StairResult& out) {
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
    const float d =
        out.level_data[static_cast<std::size_t>(k)].edge - riser_pos_[static_cast<std::size_t>(k)];
    const bool seen =
        !K || !edge_cut(*K, out, k, out.level_data[static_cast<std::size_t>(k)].height - y_origin);
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
}

bool FloorlessStairs::fit_seen_edges(int dir, StairResult& out, float& shift) const {
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
    return false;
  }
  return true;
}

void FloorlessStairs::shift_origin(int n, float shift, StairResult& out) {
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

}  // namespace stairguide
