#include "stairguide/perception/manhattan_frame.hpp"

#include <algorithm>
#include <cmath>

namespace stairguide {

namespace {
constexpr float kPi = 3.14159265358979f;
constexpr float kHalfPi = 0.5f * kPi;
// Wraps to (-pi/4, pi/4]: the representative of a direction modulo 90 degrees.
float wrap_quarter(float a) {
  while (a > 0.25f * kPi) a -= kHalfPi;
  while (a <= -0.25f * kPi) a += kHalfPi;
  return a;
}
}  // namespace

Pose manhattan_pose_from_yaw(float yaw) {
  Pose T = Pose::Identity();
  T.linear() = Eigen::AngleAxisf(-yaw, Eigen::Vector3f::UnitY()).toRotationMatrix();
  return T;
}

ManhattanTracker::ManhattanTracker(const ManhattanConfig& config) : cfg_(config) {}

ManhattanEstimate ManhattanTracker::estimate(const std::vector<PlaneRegion>& regions, const Pose& T_floor_camera) {
  ManhattanEstimate est;
  const Eigen::Matrix3f R = T_floor_camera.linear();
  const float sin_tol = std::sin(cfg_.vertical_tolerance);
  // Votes: angle of each vertical normal in the floor plane, modulo 90 degrees.
  constexpr int kBins = 90;
  float hist[kBins] = {};
  float total_area = 0.f;
  struct Vote {
    float a, w, area, width;
    float heading;  // the normal's direction in the floor plane, rad, (-pi, pi]
  };
  std::vector<Vote> votes;
  votes.reserve(regions.size());
  // Up in camera coordinates: the horizontal direction within a vertical plane is up x normal.
  const Eigen::Vector3f up_c = R.transpose() * Eigen::Vector3f::UnitY();
  const float full_w = std::max(cfg_.yaw_full_width, 1e-3f);
  for (const PlaneRegion& r : regions) {
    total_area += r.area;
    const Eigen::Vector3f nf = R * r.normal;
    if (std::fabs(nf.y()) > sin_tol) continue;
    const float heading = std::atan2(nf.x(), nf.z());
    const float a = wrap_quarter(heading);
    // Horizontal width of the region: the spread of its points along the horizontal in its plane.
    const Eigen::Vector3f hz = up_c.cross(r.normal).normalized();
    float lo = 0.f, hi = 0.f;
    if (!r.points.empty()) lo = hi = hz.dot(r.points.front());
    for (const Eigen::Vector3f& q : r.points) {
      const float t = hz.dot(q);
      lo = std::min(lo, t);
      hi = std::max(hi, t);
    }
    const float width = hi - lo;
    // The yaw of a plane fit is as precise as the plane is wide (lever arm): a person's front,
    // a post or the side of a box a few decimetres wide is off by degrees where a wall or a
    // riser is not. Votes weigh area * (width / full width)^2, the inverse of that variance.
    const float s = std::min(1.f, width / full_w);
    const float w = r.area * s * s;
    votes.push_back({a, w, r.area, width, heading});
    int bin = static_cast<int>((a + 0.25f * kPi) / kHalfPi * kBins);
    bin = (bin % kBins + kBins) % kBins;
    // Spread over neighbouring bins (1 degree each) so a peak is not split by a bin edge.
    for (int k = -2; k <= 2; ++k) hist[((bin + k) % kBins + kBins) % kBins] += w * (3 - std::abs(k));
  }
  if (votes.empty()) {
    est.why = "no vertical plane";
    return est;
  }
  int peak = 0;
  for (int b = 1; b < kBins; ++b)
    if (hist[b] > hist[peak]) peak = b;
  const float mode = -0.25f * kPi + (static_cast<float>(peak) + 0.5f) * kHalfPi / kBins;
  // Circular mean of 4*angle among votes near the mode (period 90 degrees).
  float sc = 0.f, ss = 0.f, agree = 0.f, wsum_agree = 0.f, widest = 0.f;
  // Two agreeing planes parallel to each other (modulo 180 degrees: two risers, two strips of one
  // wall, a wall and a riser) are structure; two faces of one box at right angles (a person, a
  // bin) agree modulo 90 degrees by construction and prove nothing.
  bool parallel_pair = false;
  std::vector<float>& headings = headings_;
  headings.clear();
  for (const Vote& v : votes) {
    if (std::fabs(wrap_quarter(v.a - mode)) > cfg_.cluster_tolerance) continue;
    for (const float h : headings) {
      float d = std::fmod(std::fabs(v.heading - h), kPi);  // modulo 180 degrees
      d = std::min(d, kPi - d);
      parallel_pair = parallel_pair || d <= cfg_.cluster_tolerance;
    }
    headings.push_back(v.heading);
  }
  for (const Vote& v : votes) {
    if (std::fabs(wrap_quarter(v.a - mode)) > cfg_.cluster_tolerance) continue;
    sc += v.w * std::cos(4.f * v.a);
    ss += v.w * std::sin(4.f * v.a);
    agree += v.area;
    wsum_agree += v.w;
    widest = std::max(widest, v.width);
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
  // A frame is trusted when a wide plane (a wall, a riser) supports it, or when narrow ones
  // agree tightly and two of them are parallel (strips of wall at the view's edge, the risers of a
  // flight seen in part; one narrow plane, a post or a person, agrees with itself and proves
  // nothing). People, posts and the sides of boxes are
  // narrow and agree only to degrees: their yaw is no frame. (The spread check alone refused
  // most real kitchen views, whose walls and cupboards agree only to a few degrees; the width
  // check alone refused a corridor seen as a 35 cm strip of wall.)
  const float wsum = std::max(wsum_agree, 1e-12f);
  const float rbar = std::min(1.f, std::sqrt(sc * sc + ss * ss) / wsum);
  const float spread = 0.25f * std::sqrt(std::max(0.f, -2.f * std::log(std::max(rbar, 1e-6f))));
  if (widest < cfg_.min_plane_width && (!parallel_pair || spread > cfg_.max_spread || widest < 0.5f * cfg_.min_plane_width)) {
    est.why = "no wide vertical plane, and the narrow ones disagree by degrees (no wall or riser in view)";
    return est;
  }
  float yaw = wrap_quarter(0.25f * std::atan2(ss, sc));
  // Near +-45 degrees both branches are about as close to forward: keep the previous one.
  if (prev_yaw_) {
    float best = yaw, bestd = 1e9f;
    for (int k = -1; k <= 1; ++k) {
      const float c = yaw + k * kHalfPi;
      const float dd = std::fabs(c - *prev_yaw_);
      if (dd < bestd) {
        bestd = dd;
        best = c;
      }
    }
    const float hysteresis = 0.1745f;  // 10 degrees
    if (std::fabs(best) < 0.25f * kPi + hysteresis) yaw = best;
  }
  est.found = true;
  est.yaw = yaw;
  est.T_manhattan_floor = manhattan_pose_from_yaw(yaw);
  prev_yaw_ = yaw;
  return est;
}

}  // namespace stairguide
