#include "stairguide/stairs/drop_detection.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <vector>

namespace stairguide {

namespace {

// m, how far past the floor's last reading the rays are asked what lies beyond the edge: long
// enough that a ray grazing the edge of a drop deeper than a step has fallen below it (it drops
// camera-height per distance-to-edge), short enough that the far side of the drop is not asked.
constexpr float kLookAhead = 0.8f;
// Samples beyond the edge needed to judge it; the first ones seen there (what the rays meet first).
constexpr int kMinBeyond = 3;
constexpr int kFirstSeen = 4;
// m, two columns' edge points farther apart than this (plus their spacing) are two edges.
constexpr float kJoin = 0.25f;
// Rays within this of the horizontal never meet the floor within any range: the scan stops there.
constexpr float kMinDown = 0.02f;
// cos of the incidence beyond which a floor gives no reading (grazing: 80 deg).
constexpr float kMinCosIncidence = 0.17f;

// The height tolerance of a floor reading at depth z: the sensor's noise grows with z^2.
float floor_tol(float z) { return 0.04f + 0.004f * z * z; }

// One sampled pixel, in the floor frame F (x left, y up, z forward; y = 0 on the floor).
struct Sample {
  bool valid = false;            // a depth reading
  float y = 0.f;                 // m, height of the reading above the floor
  Eigen::Vector2f xz{0.f, 0.f};  // m, the reading's ground position (x, z) relative to the camera foot
  float floor_range = 0.f;       // m, where the ray would meet the floor (continued), from the camera foot
  float floor_depth = 0.f;       // m, camera depth at which it would meet it
  bool floor_seen = false;       // that floor point would be read (in range, not grazing)
};

// What one column says: the floor's last reading before what lies beyond it.
struct ColumnEdge {
  bool edge = false;  // the floor ends before a drop (deep) or before nothing (missing)
  bool deep = false;  // a surface seen more than min_depth below the floor beyond it
  Eigen::Vector2f xz{0.f, 0.f};
  float depth = 0.f;  // m below the floor (median of the deep readings)
};

struct Geometry {
  Pose T;  // T_floor_camera
  Eigen::Vector3f c;
  const CameraIntrinsics* K;
};

Sample sample_at(const Geometry& g, const cv::Mat& depth, int u, int v, const DropConfig& cfg) {
  Sample s;
  const Eigen::Vector3f r((static_cast<float>(u) - g.K->cx) / g.K->fx,
                          (static_cast<float>(v) - g.K->cy) / g.K->fy, 1.f);
  const Eigen::Vector3f d = g.T.linear() * r;
  if (d.y() < -kMinDown * r.norm()) {
    const float t = -g.c.y() / d.y();
    s.floor_depth = t;
    s.floor_range = t * std::hypot(d.x(), d.z());
    const float cos_inc = -d.y() / d.norm();
    s.floor_seen = t <= cfg.sensor_range && cos_inc >= kMinCosIncidence;
  } else {
    s.floor_range = s.floor_depth = std::numeric_limits<float>::infinity();
  }
  const float z = depth.at<float>(v, u);
  if (z > 0.f && std::isfinite(z)) {
    const Eigen::Vector3f p = g.c + z * d;
    s.valid = true;
    s.y = p.y();
    s.xz = Eigen::Vector2f(p.x() - g.c.x(), p.z() - g.c.z());
  }
  return s;
}

// Whether the valid sample `k` of `beyond` (within a step below the floor) lies on a level (a
// tread, a lowered floor: its neighbours spread more along the floor than in height) rather than
// on a vertical face (the far wall of a hole, the rays' flying pixels at the edge).
bool on_a_level(const std::vector<const Sample*>& beyond, std::size_t k) {
  const Sample& a = *beyond[k > 0 ? k - 1 : k];
  const Sample& b = *beyond[k + 1 < beyond.size() ? k + 1 : k];
  if (&a == &b) return true;
  return std::fabs(b.y - a.y) < std::fabs(b.xz.norm() - a.xz.norm());
}

// Judges the samples beyond the floor's last reading `last` (index into `col`): true with the
// edge filled in when they show a drop (or nothing where the floor would be seen), false when
// the floor resumes, something stands on it, or a level within a step below it is seen.
bool judge_beyond(const std::vector<Sample>& col, std::size_t last, const DropConfig& cfg, ColumnEdge& out,
                  std::size_t& resume) {
  const float limit = col[last].floor_range + kLookAhead;
  int n = 0, missing = 0, floor = 0, unseen = 0;
  std::vector<const Sample*> beyond;  // the valid readings, nearest first
  std::size_t i = last + 1;
  for (; i < col.size() && (col[i].floor_range <= limit || n < kMinBeyond); ++i) {
    const Sample& s = col[i];
    ++n;
    if (!s.valid) {
      ++missing;
      unseen += s.floor_seen ? 0 : 1;
    } else if (std::fabs(s.y) <= floor_tol(s.floor_depth)) {
      if (++floor >= 2) break;  // the floor resumes
    } else {
      beyond.push_back(&s);
    }
  }
  resume = i;
  // The floor resuming within the look-ahead is a gap in the readings, unless surfaces deeper than
  // a step were seen in the gap: then it is a hole narrower than the look-ahead (its bottom or
  // its far wall seen below the floor between its edges), a drop all the same.
  const bool resumed = floor >= 2;
  if (n < kMinBeyond) return false;
  int deep = 0, other = 0, classified = 0, first_levels = 0;
  std::vector<float> depths;
  for (std::size_t k = 0; k < beyond.size(); ++k) {
    const float y = beyond[k]->y;
    if (y < -cfg.min_depth) {
      ++deep;
      depths.push_back(-y);
    } else if (y > 0.f) {
      ++other;  // above the floor: something stands on it
    } else if (on_a_level(beyond, k)) {
      ++other;  // a level within a step below it
      first_levels += classified < kFirstSeen ? 1 : 0;
    } else {
      continue;  // a vertical face (the far wall of a hole, flying pixels at the edge)
    }
    ++classified;
  }
  // What the rays meet first beyond the edge decides: a level within a step below (the first
  // tread of a descent, a curb) makes it a step, whatever deeper treads lie further on.
  if (first_levels >= 2) return false;
  if (deep >= 2 && deep >= 3 * other) {
    out.edge = out.deep = true;
    std::nth_element(depths.begin(), depths.begin() + static_cast<long>(depths.size() / 2), depths.end());
    out.depth = depths[depths.size() / 2];
    return true;
  }
  // No reading beyond the edge where the floor would have been read: consistent with a drop.
  if (!resumed && deep + other <= 1 && unseen == 0 && missing >= 2) {
    out.edge = true;
    return true;
  }
  return false;
}

// Follows one column from the bottom of the view outwards: the first floor edge that the rays
// beyond it show to be a drop; none when the column meets anything else first.
ColumnEdge scan_column(const Geometry& g, const cv::Mat& depth, int u, int dv, const DropConfig& cfg) {
  std::vector<Sample> col;
  col.reserve(static_cast<std::size_t>(depth.rows / dv + 1));
  for (int v = depth.rows - 1; v >= 0; v -= dv) {
    Sample s = sample_at(g, depth, u, v, cfg);
    if (!std::isfinite(s.floor_range)) break;  // at and above the horizon
    col.push_back(s);
  }
  ColumnEdge e;
  std::size_t i = 0, last = 0;
  int floor_run = 0;
  while (i < col.size()) {
    const Sample& s = col[i];
    if (s.valid && std::fabs(s.y) <= floor_tol(s.floor_depth)) {
      ++floor_run;
      last = i++;
      continue;
    }
    if (floor_run < 2) {  // below the floor's first readings (the wearer's feet, a gap): go on
      ++i;
      continue;
    }
    if (col[last].floor_range > cfg.max_distance + kLookAhead) return e;
    std::size_t resume = i;
    ColumnEdge c;
    if (judge_beyond(col, last, cfg, c, resume)) {
      c.xz = col[last].xz;
      return c;
    }
    // The floor resumed (a gap in the readings): keep following it. Otherwise something stands on
    // it or a level within a step below it is seen: what lies behind is not known from here.
    if (resume >= col.size() || !col[resume].valid ||
        std::fabs(col[resume].y) > floor_tol(col[resume].floor_depth))
      return e;
    i = resume;
  }
  return e;
}

struct Edge {
  int columns = 0, deep = 0;
  float width = 0.f;
  Eigen::Vector2f nearest{0.f, 0.f};
  std::vector<float> depths;
};

// Columns whose edge points join (neighbouring samples, points close) make one edge.
std::vector<Edge> join_columns(const std::vector<ColumnEdge>& cols, float spacing_at_1m) {
  std::vector<Edge> edges;
  Edge cur;
  const ColumnEdge* prev = nullptr;
  Eigen::Vector2f first{0.f, 0.f};
  int gap = 0;
  auto close = [&] {
    if (cur.columns > 0) edges.push_back(cur);
    cur = Edge{};
    prev = nullptr;
  };
  for (const ColumnEdge& c : cols) {
    if (!c.edge) {
      if (++gap > 2) close();
      continue;
    }
    const float r = c.xz.norm();
    if (prev && (c.xz - prev->xz).norm() > kJoin + spacing_at_1m * static_cast<float>(gap + 1) * r) close();
    gap = 0;
    if (cur.columns == 0) first = c.xz, cur.nearest = c.xz;
    ++cur.columns;
    // Each column stands for a strip one spacing wide: the edge runs half a spacing past its end columns.
    cur.width = std::max(cur.width, (c.xz - first).norm() + spacing_at_1m * 0.5f * (r + first.norm()));
    if (c.deep) ++cur.deep, cur.depths.push_back(c.depth);
    if (r < cur.nearest.norm()) cur.nearest = c.xz;
    prev = &c;
  }
  close();
  return edges;
}

}  // namespace

const char* to_string(DropVerdict v) {
  switch (v) {
    case DropVerdict::kDetected: return "drop";
    case DropVerdict::kDisabled: return "disabled";
    case DropVerdict::kNoFloor: return "no floor";
    case DropVerdict::kNoEdge: return "no edge";
    case DropVerdict::kNoDepthSeen: return "nothing seen below the edge";
    case DropVerdict::kTooNarrow: return "edge too short";
    case DropVerdict::kTooFar: return "too far";
  }
  return "?";
}

DropResult detect_drop(const RgbdFrame& frame, const SceneResult& scene, const DropConfig& cfg) {
  const auto t0 = std::chrono::steady_clock::now();
  DropResult r;
  auto done = [&](DropVerdict v) {
    r.verdict = v;
    r.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    return r;
  };
  if (!cfg.enabled) return done(DropVerdict::kDisabled);
  if (!scene.floor_found || frame.depth.empty() || frame.depth.type() != CV_32FC1)
    return done(DropVerdict::kNoFloor);
  r.ok = true;
  const CameraIntrinsics& K = frame.intrinsics;
  const Geometry g{scene.T_floor_camera, scene.T_floor_camera.translation(), &K};
  // About 160 columns and 240 rows whatever the image size.
  const int du = std::max(1, frame.depth.cols / 160), dv = std::max(1, frame.depth.rows / 240);
  std::vector<ColumnEdge> cols;
  for (int u = du / 2; u < frame.depth.cols; u += du) cols.push_back(scan_column(g, frame.depth, u, dv, cfg));
  const std::vector<Edge> edges = join_columns(cols, static_cast<float>(du) / K.fx);
  DropVerdict why = DropVerdict::kNoEdge;
  const Edge* best = nullptr;
  for (const Edge& e : edges) {
    if (e.deep < std::max(2, e.columns / 5)) {
      if (why == DropVerdict::kNoEdge) why = DropVerdict::kNoDepthSeen;
      continue;
    }
    if (e.width < cfg.min_width) {
      if (why != DropVerdict::kTooFar) why = DropVerdict::kTooNarrow;
      continue;
    }
    if (e.nearest.norm() > cfg.max_distance) {
      why = DropVerdict::kTooFar;
      continue;
    }
    if (!best || e.nearest.norm() < best->nearest.norm()) best = &e;
  }
  if (!best) return done(why);
  r.detected = true;
  r.distance_m = best->nearest.norm();
  // The bearing from the camera's own forward direction on the floor (F's z may be an earlier
  // view's when the floor is carried by the odometry); x_F points left.
  Eigen::Vector2f fwd(g.T.linear()(0, 2), g.T.linear()(2, 2));
  if (fwd.norm() < 1e-3f) fwd = Eigen::Vector2f(0.f, 1.f);
  fwd.normalize();
  const Eigen::Vector2f right(-fwd.y(), fwd.x());  // in (x left, z forward): right of (0, 1) is (-1, 0)
  r.bearing_rad = std::atan2(best->nearest.dot(right), best->nearest.dot(fwd));
  std::vector<float> d = best->depths;
  std::nth_element(d.begin(), d.begin() + static_cast<long>(d.size() / 2), d.end());
  r.depth_m = d[d.size() / 2];
  r.width_m = best->width;
  r.columns = best->columns;
  r.deep_columns = best->deep;
  return done(DropVerdict::kDetected);
}

DropSummary summarize_drop(const DropResult& drop, const StairResult& stairs) {
  DropSummary s;
  if (!drop.detected) return s;
  if (stairs.detected && stairs.direction() < 0) {
    s.by_stairs = true;
    return s;
  }
  s.detected = true;
  s.distance_m = drop.distance_m;
  s.bearing_rad = drop.bearing_rad;
  s.depth_m = drop.depth_m;
  return s;
}

}  // namespace stairguide
