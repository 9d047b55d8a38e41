#include "stairguide/perception/edge_compass.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Eigenvalues>

#include <opencv2/imgproc.hpp>

#include "manhattan/internal.hpp"
#include "stairguide/perception/manhattan_frame.hpp"

namespace stairguide {

namespace {
using manhattan_detail::kPi;
constexpr float kQuarter = 0.5f * kPi;  // the period of a Manhattan direction
constexpr int kBins = 360;              // 0.25 degree bins over 90 degrees
}  // namespace

EdgeCompassResult EdgeCompass::estimate(const cv::Mat& gray, const CameraIntrinsics& K,
                                        const Eigen::Matrix3f& R_floor_camera) {
  EdgeCompassResult out;
  if (gray.empty() || gray.type() != CV_8UC1 || !K.valid() || gray.cols < 3 || gray.rows < 3) return out;
  hist_.assign(kBins, 0.f);
  votes_.clear();
  // Rows of R (camera into floor): the floor's x, y (up) and z axes in camera coordinates.
  const Eigen::Vector3f fx_c = R_floor_camera.row(0).transpose();
  const Eigen::Vector3f up_c = R_floor_camera.row(1).transpose();
  const Eigen::Vector3f fz_c = R_floor_camera.row(2).transpose();
  // Half resolution (pyrDown blurs the sensor's noise and the textures' finest grain), gradients,
  // and their structure tensor summed over a window: its dominant direction is the gradient's
  // across a straight edge, and its coherence (1 on a straight edge, 0 on isotropic texture or
  // noise) keeps only edges that run straight through the window. The window sums are running
  // sums by hand: OpenCV's float box filter took 0.4 ms for the three products, and the whole
  // compass takes 0.45 ms (one thread, a synthetic 640 x 480 view).
  cv::pyrDown(gray, half_);
  const CameraIntrinsics Kh = K.scaled(0.5f);
  // Scharr's kernel (ksize -1; / 32: grey levels per pixel), not Sobel's 3 x 3: Sobel turns an
  // edge's direction towards the image axes, by up to 2 degrees of yaw on drawn floor joints
  // (test_perception_compass), Scharr by 0.15.
  cv::Sobel(half_, gx_, CV_32F, 1, 0, -1, 1.0 / 32);
  cv::Sobel(half_, gy_, CV_32F, 0, 1, -1, 1.0 / 32);
  const int W = half_.cols, H = half_.rows;
  const int r = std::max(1, cfg_.window / 2), n = 2 * r + 1;
  if (W < n || H < n) return out;
  const float inv_n2 = 1.f / static_cast<float>(n * n);
  // Each row's horizontal window sums of (gx^2, gy^2, gx gy), valid for u in [r, W - r); the
  // border columns are never written and stay at the zero the first resize gave them.
  rows_.resize(static_cast<std::size_t>(W) * H * 3, 0.f);
  for (int v = 0; v < H; ++v) {
    const float* x = gx_.ptr<float>(v);
    const float* y = gy_.ptr<float>(v);
    float* o = &rows_[static_cast<std::size_t>(v) * W * 3];
    float sxx = 0.f, syy = 0.f, sxy = 0.f;
    for (int u = 0; u < n - 1; ++u) sxx += x[u] * x[u], syy += y[u] * y[u], sxy += x[u] * y[u];
    for (int u = r; u + r < W; ++u) {
      const int in = u + r;
      sxx += x[in] * x[in], syy += y[in] * y[in], sxy += x[in] * y[in];
      o[3 * u] = sxx, o[3 * u + 1] = syy, o[3 * u + 2] = sxy;
      const int gone = u - r;
      sxx -= x[gone] * x[gone], syy -= y[gone] * y[gone], sxy -= x[gone] * y[gone];
    }
  }
  // Vertical running sums of those: the window's sums at row v, for v in [r, H - r).
  acc_.assign(static_cast<std::size_t>(W) * 3, 0.f);
  for (int v = 0; v < n - 1; ++v) {
    const float* row = &rows_[static_cast<std::size_t>(v) * W * 3];
    for (int i = 0; i < 3 * W; ++i) acc_[static_cast<std::size_t>(i)] += row[i];
  }
  const float min_e = cfg_.min_gradient * cfg_.min_gradient;
  const float min_h2 = cfg_.min_horizontal * cfg_.min_horizontal;
  const float inv_fx = 1.f / Kh.fx, inv_fy = 1.f / Kh.fy;
  const int step = std::max(1, cfg_.stride);
  for (int v = r; v + r < H; ++v) {
    {
      const float* in = &rows_[static_cast<std::size_t>(v + r) * W * 3];
      for (int i = 0; i < 3 * W; ++i) acc_[static_cast<std::size_t>(i)] += in[i];
    }
    const float* a = acc_.data();
    const bool vote_row = (v - r) % step == 0;
    const float y = (static_cast<float>(v) - Kh.cy) * inv_fy;
    for (int u = r; vote_row && u + r < W; u += step) {
      const float xxu = a[3 * u] * inv_n2, yyu = a[3 * u + 1] * inv_n2, xyu = a[3 * u + 2] * inv_n2;
      const float e = xxu + yyu;
      if (e < min_e) continue;
      const float dxy = xxu - yyu;
      const float aniso = std::sqrt(dxy * dxy + 4.f * xyu * xyu);
      const float coherence = aniso / e;
      if (coherence < cfg_.min_coherence) continue;
      // The gradient's dominant direction (cos, sin) from the tensor's double angle (cos 2th =
      // dxy / aniso, sin 2th = 2 xy / aniso) by the half-angle formulas; the edge runs across it:
      // image direction (-sin, cos).
      const float c2 = dxy / aniso;
      const float gcos = std::sqrt(std::max(0.f, 0.5f * (1.f + c2)));
      const float gsin = std::copysign(std::sqrt(std::max(0.f, 0.5f * (1.f - c2))), xyu);
      // The edge's interpretation plane holds the viewing ray and the ray's displacement along
      // the edge t; its normal is ray x t.
      const Eigen::Vector3f ray((static_cast<float>(u) - Kh.cx) * inv_fx, y, 1.f);
      const Eigen::Vector3f t(-gsin * inv_fx, gcos * inv_fy, 0.f);
      const Eigen::Vector3f m = ray.cross(t);
      const float mx = m.dot(fx_c), my = m.dot(up_c), mz = m.dot(fz_c);
      const float n2 = mx * mx + my * my + mz * mz;
      if (!(n2 > 0.f)) continue;
      // A plane holding the vertical (my ~ 0) may hold a vertical edge: no horizontal direction.
      if (my * my < min_h2 * n2) continue;
      // The horizontal direction in the plane is m x up = (-mz, 0, mx) in the floor frame. Its
      // heading's precision falls as the plane turns horizontal (m towards up): weight by the
      // horizontal share of m, and by the edge's strength and straightness.
      const float h2 = (mx * mx + mz * mz) / n2;
      const float w = std::sqrt(e) * coherence * h2;
      const float heading = manhattan_wrap(std::atan2(-mz, mx));
      votes_.push_back({heading, w});
      const float pos = (heading + 0.25f * kPi) / kQuarter * kBins - 0.5f;
      const int b0 = static_cast<int>(std::floor(pos));
      const float f = pos - static_cast<float>(b0);
      hist_[static_cast<std::size_t>((b0 % kBins + kBins) % kBins)] += w * (1.f - f);
      hist_[static_cast<std::size_t>(((b0 + 1) % kBins + kBins) % kBins)] += w * f;
      out.weight += w;
    }
    const float* gone = &rows_[static_cast<std::size_t>(v - r) * W * 3];
    for (int i = 0; i < 3 * W; ++i) acc_[static_cast<std::size_t>(i)] -= gone[i];
  }
  out.edgels = static_cast<int>(votes_.size());
  if (votes_.empty() || !(out.weight > 0.f)) return out;
  // The fullest 1 degree window (circular), then the circular mean (period 90 degrees) of the votes
  // within peak_halfwidth of it, and their share of all.
  constexpr int kWin = 2;  // bins either side
  int best = 0;
  float best_sum = -1.f;
  for (int i = 0; i < kBins; ++i) {
    float s = 0.f;
    for (int k = -kWin; k <= kWin; ++k)
      s += hist_[static_cast<std::size_t>(((i + k) % kBins + kBins) % kBins)];
    if (s > best_sum) best_sum = s, best = i;
  }
  float yaw = -0.25f * kPi + (static_cast<float>(best) + 0.5f) * kQuarter / kBins;
  for (int iter = 0; iter < 2; ++iter) {
    float sc = 0.f, ss = 0.f, support = 0.f;
    for (const Vote& vt : votes_) {
      if (std::fabs(manhattan_wrap(vt.a - yaw)) > cfg_.peak_halfwidth) continue;
      sc += vt.w * std::cos(4.f * vt.a);
      ss += vt.w * std::sin(4.f * vt.a);
      support += vt.w;
    }
    if (!(support > 0.f)) return out;
    yaw = manhattan_wrap(0.25f * std::atan2(ss, sc));
    out.support = support / out.weight;
  }
  out.valid = true;
  out.yaw = yaw;
  return out;
}

EdgeCompassResult EdgeCompass::estimate(const cv::Mat& gray, const CameraIntrinsics& K,
                                        const Pose& T_floor_camera, const cv::Mat& depth, float max_range) {
  EdgeCompassResult out = estimate(gray, K, T_floor_camera.linear());
  if (cfg_.line_min_length > 0.f && !half_.empty() && depth.type() == CV_32FC1 && depth.size() == gray.size())
    find_lines(K, T_floor_camera, depth, max_range, out);
  return out;
}

// A line lies on the floor when, along it, the readings a few pixels to either side are the floor's
// own depth on that ray (the floor, or a wall at its foot, which meets the floor there), or there is
// none and the floor there lies beyond the depth cut-off (less 0.3 m: the cut-off drops a reading
// nearer than it where the noise pushed it beyond). The tolerance, 5 cm and 3 % of the depth, holds
// the floor's own slope across the 3 px at a grazing angle and the real sensor's noise. An edge of
// furniture, a person or a riser has something nearer than the floor on one side (an occluding
// edge) or lies above it, and fails on most of its length; 3 in 4 samples must agree.
bool EdgeCompass::on_floor(const Eigen::Vector2f& p1, const Eigen::Vector2f& p2, const CameraIntrinsics& K,
                           const Pose& T_floor_camera, const cv::Mat& depth, float max_range) const {
  const Eigen::Matrix3f R = T_floor_camera.linear();
  const float h = T_floor_camera.translation().y();
  const Eigen::Vector2f d = (p2 - p1).normalized(), nrm(-d.y(), d.x());
  const float len = (p2 - p1).norm();
  constexpr float kStep = 6.f, kSide = 3.f;  // px
  int samples = 0, agree = 0;
  for (float t = 0.5f * kStep; t < len; t += kStep) {
    const Eigen::Vector2f p = p1 + t * d;
    const Eigen::Vector3f ray((p.x() - K.cx) / K.fx, (p.y() - K.cy) / K.fy, 1.f);
    const float down = -(R * ray).y();
    ++samples;
    if (!(down > 1e-6f)) continue;  // above the horizon: not on the floor
    const float zf = h / down;      // depth of the floor point on this ray
    const float tol = 0.05f + 0.03f * zf;
    int sides = 0, pass = 0;
    for (float sgn : {-1.f, 1.f}) {
      const Eigen::Vector2f q = p + sgn * kSide * nrm;
      const int u = static_cast<int>(std::lround(q.x())), v = static_cast<int>(std::lround(q.y()));
      if (u < 0 || v < 0 || u >= depth.cols || v >= depth.rows) continue;
      ++sides;
      const float z = depth.at<float>(v, u);
      pass += z > 0.f ? std::fabs(z - zf) <= tol : (max_range > 0.f && zf > max_range - 0.3f);
    }
    agree += sides > 0 && pass == sides;
  }
  return samples > 0 && 4 * agree >= 3 * samples;
}

void EdgeCompass::find_lines(const CameraIntrinsics& K, const Pose& T_floor_camera, const cv::Mat& depth,
                             float max_range, EdgeCompassResult& out) {
  const CameraIntrinsics Kh = K.scaled(0.5f);
  const Eigen::Matrix3f Rf = T_floor_camera.linear();
  const Eigen::Vector3f fx_c = Rf.row(0).transpose(), up_c = Rf.row(1).transpose(),
                        fz_c = Rf.row(2).transpose();
  // OpenCV's line segment detector (LSD, von Gioi et al.) on the half-resolution image: 9-10 ms on a
  // synthetic view, 4x less than at full resolution, and its segments less broken by the texture's
  // grain. It breaks a long edge into pieces wherever the grain or the noise crosses it; the pieces
  // are chained below. (Refinement, LSD_REFINE_STD, breaks them further and costs more.)
  cv::Ptr<cv::LineSegmentDetector> lsd = cv::createLineSegmentDetector(cv::LSD_REFINE_NONE);
  segs_.clear();
  lsd->detect(half_, segs_);
  struct Seg {
    Eigen::Vector2f a, b, d;
    float len;
  };
  std::vector<Seg> segs;
  segs.reserve(segs_.size());
  for (const cv::Vec4f& s : segs_) {
    const Eigen::Vector2f a(s[0], s[1]), b(s[2], s[3]);
    const float len = (b - a).norm();
    if (len >= 4.f) segs.push_back({a, b, (b - a) / len, len});
  }
  // Chains, longest segment first: the segments within 3 deg of its direction whose two ends lie
  // within a pixel of its line, refitted on them (twice). A chain's length is its segments' summed
  // length (a texture's short pieces that happen to line up add little); its direction comes from
  // the fitted line's two ends, whose interpretation plane holds the 3D edge as in estimate().
  std::sort(segs.begin(), segs.end(), [](const Seg& x, const Seg& y) { return x.len > y.len; });
  std::vector<char> used(segs.size(), 0);
  std::vector<std::size_t> members;
  const float sin_par = std::sin(3.f * kPi / 180.f);
  constexpr float kTol = 1.f;  // px of the half image
  const float min_h2 = cfg_.min_horizontal * cfg_.min_horizontal;
  for (std::size_t i = 0; i < segs.size(); ++i) {
    if (used[i]) continue;
    Eigen::Vector2f c = 0.5f * (segs[i].a + segs[i].b), d = segs[i].d;
    for (int pass = 0; pass < 2; ++pass) {
      const Eigen::Vector2f nrm(-d.y(), d.x());
      members.clear();
      for (std::size_t j = 0; j < segs.size(); ++j) {
        if (used[j] && j != i) continue;
        const Seg& s = segs[j];
        if (std::fabs(s.d.x() * d.y() - s.d.y() * d.x()) > sin_par) continue;
        if (std::fabs(nrm.dot(s.a - c)) > kTol || std::fabs(nrm.dot(s.b - c)) > kTol) continue;
        members.push_back(j);
      }
      if (members.empty()) break;
      // Total least squares over the members' end points, each weighing its segment's length.
      Eigen::Vector2f mean = Eigen::Vector2f::Zero();
      float wsum = 0.f;
      for (std::size_t j : members) mean += segs[j].len * (segs[j].a + segs[j].b), wsum += 2.f * segs[j].len;
      mean /= wsum;
      Eigen::Matrix2f C = Eigen::Matrix2f::Zero();
      for (std::size_t j : members)
        for (const Eigen::Vector2f& p : {segs[j].a, segs[j].b})
          C += segs[j].len * (p - mean) * (p - mean).transpose();
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix2f> es(C);
      Eigen::Vector2f nd = es.eigenvectors().col(1);
      if (nd.dot(d) < 0.f) nd = -nd;
      c = mean, d = nd;
    }
    if (members.empty()) continue;
    float lo = std::numeric_limits<float>::max(), hi = -lo, length = 0.f;
    for (std::size_t j : members) {
      used[j] = 1;
      length += segs[j].len;
      for (const Eigen::Vector2f& p : {segs[j].a, segs[j].b})
        lo = std::min(lo, d.dot(p - c)), hi = std::max(hi, d.dot(p - c));
    }
    if (2.f * length < cfg_.line_min_length) continue;
    const Eigen::Vector2f p1 = c + lo * d, p2 = c + hi * d;
    const Eigen::Vector3f r1((p1.x() - Kh.cx) / Kh.fx, (p1.y() - Kh.cy) / Kh.fy, 1.f);
    const Eigen::Vector3f r2((p2.x() - Kh.cx) / Kh.fx, (p2.y() - Kh.cy) / Kh.fy, 1.f);
    const Eigen::Vector3f m = r1.cross(r2);
    const float mx = m.dot(fx_c), my = m.dot(up_c), mz = m.dot(fz_c);
    const float n2 = mx * mx + my * my + mz * mz;
    if (!(n2 > 0.f) || my * my < min_h2 * n2) continue;
    if (!on_floor(2.f * p1, 2.f * p2, K, T_floor_camera, depth, max_range)) continue;
    out.lines.push_back(
        {manhattan_wrap(std::atan2(-mz, mx)), 2.f * length, 2.f * (hi - lo), 2.f * p1, 2.f * p2});
  }
  std::sort(out.lines.begin(), out.lines.end(),
            [](const EdgeLine& x, const EdgeLine& y) { return x.length > y.length; });
}

}  // namespace stairguide
