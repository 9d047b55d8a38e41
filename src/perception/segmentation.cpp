#include "stairguide/perception/segmentation.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <opencv2/imgproc.hpp>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace stairguide {

namespace {
/// A region is planar when its residual RMS is within this share of the inlier tolerance.
constexpr float kPlanarRms = 0.6f;
}  // namespace

PlaneFit fit_plane_pca(const PointMoments& m) {
  PlaneFit f;
  if (!(m.w > 0.0)) return f;
  const double iw = 1.0 / m.w;
  const Eigen::Vector3d mean(m.sx * iw, m.sy * iw, m.sz * iw);
  Eigen::Matrix3d C;
  C(0, 0) = m.sxx * iw - mean.x() * mean.x();
  C(0, 1) = C(1, 0) = m.sxy * iw - mean.x() * mean.y();
  C(0, 2) = C(2, 0) = m.sxz * iw - mean.x() * mean.z();
  C(1, 1) = m.syy * iw - mean.y() * mean.y();
  C(1, 2) = C(2, 1) = m.syz * iw - mean.y() * mean.z();
  C(2, 2) = m.szz * iw - mean.z() * mean.z();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(C);
  if (es.info() != Eigen::Success) return f;
  Eigen::Vector3d n = es.eigenvectors().col(0).normalized();
  if (n.dot(mean) > 0.0) n = -n;  // face the camera
  f.ok = true;
  f.normal = n.cast<float>();
  f.d = static_cast<float>(-n.dot(mean));
  f.mean = mean.cast<float>();
  f.eigenvalues = es.eigenvalues().cwiseMax(0.0).cast<float>();
  f.eigenvectors = es.eigenvectors().cast<float>();
  f.eigenvectors.col(0) = f.normal;
  return f;
}

namespace {
/// The plane 1/z = a u' + b v' + c of moments `m` by the centred normal equations (better
/// conditioned for small cells far from the image centre), with what fit_plane and the cell tests
/// take from it: g = |(a, b, c)|, the residual rms and 1/z at the mean pixel (wm). False for fewer
/// than three points, points on a line, or a degenerate plane.
struct CentredPlane {
  double a, b, c, g, rms_w, wm, mu, mv;
};
bool solve_centred_plane(const InvDepthMoments& m, CentredPlane& p) {
  if (m.n < 3.0) return false;
  const double in = 1.0 / m.n;
  const double mu = m.su * in, mv = m.sv * in, mw = m.sw * in;
  const double cuu = m.suu * in - mu * mu, cuv = m.suv * in - mu * mv, cvv = m.svv * in - mv * mv;
  const double cuw = m.suw * in - mu * mw, cvw = m.svw * in - mv * mw, cww = m.sww * in - mw * mw;
  const double det = cuu * cvv - cuv * cuv;
  if (!(det > 1e-6 * (cuu * cvv + 1e-30)) || !(det > 1e-24)) return false;  // points on a line
  const double a = (cuw * cvv - cvw * cuv) / det;
  const double b = (cvw * cuu - cuw * cuv) / det;
  const double c = mw - a * mu - b * mv;
  const double g = std::sqrt(a * a + b * b + c * c);
  if (!(g > 1e-9)) return false;
  p = {a, b, c, g, std::sqrt(std::max(0.0, cww - a * cuw - b * cvw)), a * mu + b * mv + c, mu, mv};
  return true;
}
}  // namespace

PlaneFit fit_plane(const InvDepthMoments& m) {
  PlaneFit f;
  CentredPlane p;
  if (!solve_centred_plane(m, p)) return f;
  f.ok = true;
  f.d = static_cast<float>(1.0 / p.g);
  f.normal = Eigen::Vector3f(static_cast<float>(-p.a / p.g), static_cast<float>(-p.b / p.g), static_cast<float>(-p.c / p.g));
  f.a = static_cast<float>(p.a);
  f.b = static_cast<float>(p.b);
  f.c = static_cast<float>(p.c);
  f.rms_w = static_cast<float>(p.rms_w);
  // The plane's point on the ray of the mean pixel stands in for the centroid.
  if (p.wm > 1e-9)
    f.mean = Eigen::Vector3f(static_cast<float>(p.mu / p.wm), static_cast<float>(p.mv / p.wm), static_cast<float>(1.0 / p.wm));
  return f;
}

namespace {
/// fit_plane's ok, rms_w and mean.z() alone (the same solve), for the cell tests that keep nothing
/// else of the fit: thousands of cells a frame, and the rest of a fit (normal, offset, centroid:
/// six more divisions, a struct of 30 floats) was most of its cost.
bool plane_rms_depth(const InvDepthMoments& m, float& rms_w, float& mean_z) {
  CentredPlane p;
  if (!solve_centred_plane(m, p)) return false;
  rms_w = static_cast<float>(p.rms_w);
  mean_z = p.wm > 1e-9 ? static_cast<float>(1.0 / p.wm) : 0.f;
  return true;
}

/// The one unknown of a plane with its normal n fixed: 1/z = g s, s = -(n . (u', v', 1)),
/// g = 1/d. False when the moments are empty or the points would lie behind the camera on such a
/// plane; ssw is the sum of s w the residual needs.
bool fixed_normal_gain(const InvDepthMoments& m, const Eigen::Vector3f& n, double& g, double& ssw) {
  if (m.n < 1.0) return false;
  const double nx = n.x(), ny = n.y(), nz = n.z();
  ssw = -(nx * m.suw + ny * m.svw + nz * m.sw);
  const double sss = nx * nx * m.suu + ny * ny * m.svv + nz * nz * m.n + 2.0 * nx * ny * m.suv + 2.0 * nx * nz * m.su +
                     2.0 * ny * nz * m.sv;
  if (!(sss > 1e-30)) return false;
  g = ssw / sss;
  return g > 1e-9;
}

/// fit_plane_fixed_normal's ok and rms_w alone (what the cell tests need), by the same expressions.
bool fixed_normal_rms(const InvDepthMoments& m, const Eigen::Vector3f& n, float& rms_w) {
  double g = 0.0, ssw = 0.0;
  if (!fixed_normal_gain(m, n, g, ssw)) return false;
  rms_w = static_cast<float>(std::sqrt(std::max(0.0, (m.sww - g * ssw) / m.n)));
  return true;
}
}  // namespace

PlaneFit fit_plane_fixed_normal(const InvDepthMoments& m, const Eigen::Vector3f& n) {
  PlaneFit f;
  double g = 0.0, ssw = 0.0;
  if (!fixed_normal_gain(m, n, g, ssw)) return f;
  const double nx = n.x(), ny = n.y(), nz = n.z();
  f.ok = true;
  f.d = static_cast<float>(1.0 / g);
  f.normal = n;
  f.a = static_cast<float>(-g * nx);
  f.b = static_cast<float>(-g * ny);
  f.c = static_cast<float>(-g * nz);
  f.rms_w = static_cast<float>(std::sqrt(std::max(0.0, (m.sww - g * ssw) / m.n)));
  const double in = 1.0 / m.n, mu = m.su * in, mv = m.sv * in;
  const double wm = f.a * mu + f.b * mv + f.c;
  if (wm > 1e-9) f.mean = Eigen::Vector3f(static_cast<float>(mu / wm), static_cast<float>(mv / wm), static_cast<float>(1.0 / wm));
  return f;
}

Segmentation::Segmentation(const SegmentationConfig& config) : cfg_(config) {}

void Segmentation::find_dominant_directions(const std::vector<Grow>& grows) {
  // Normals of the big regions of the cell pass, biggest first; one per direction (a tread and
  // the floor give one). Their fits span hundreds of rows, so their tilt is the precise one.
  dirs_.clear();
  const double min_px = std::max<double>(cfg_.region_min_pixels, cfg_.dominant_min_fraction * stats_.valid_pixels);
  std::vector<int>& idx = sorted_;
  idx.clear();
  for (int r = 0; r < static_cast<int>(grows.size()); ++r)
    if (grows[r].count >= min_px && grows[r].plane.ok) idx.push_back(r);
  std::sort(idx.begin(), idx.end(), [&](int a, int b) { return grows[a].count > grows[b].count; });
  const float same = std::cos(3.f * 3.14159265f / 180.f);
  for (int r : idx) {
    const Eigen::Vector3f& n = grows[r].plane.normal;
    bool dup = false;
    for (const Eigen::Vector3f& d : dirs_) dup |= d.dot(n) > same;
    if (!dup) dirs_.push_back(n);
    if (dirs_.size() >= 8) break;
  }
  stats_.dominant_directions = static_cast<int>(dirs_.size());
}

int Segmentation::best_direction(const InvDepthMoments& m, PlaneFit& fit) const {
  // A few rows cannot tell directions that differ by a tilt about the image rows: several may
  // fit within the noise, and the lowest residual among them is chance. The direction with the
  // most support (dirs_ is ordered by region size: the floor first) is the likelier one.
  // (The directions are tried by their residual alone; the whole fit is made for the one taken.)
  const float limit = 0.5f * tolerance_w();
  for (int i = 0; i < static_cast<int>(dirs_.size()); ++i) {
    float rms_w;
    if (!fixed_normal_rms(m, dirs_[i], rms_w) || rms_w > limit) continue;
    fit = fit_plane_fixed_normal(m, dirs_[i]);
    return i;
  }
  return -1;
}

PlaneFit Segmentation::region_plane(const InvDepthMoments& m, int& dir) const {
  const PlaneFit free = fit_plane(m);
  if (dir < 0 || dir >= static_cast<int>(dirs_.size())) {
    dir = -1;
    return free;
  }
  const PlaneFit fixed = fit_plane_fixed_normal(m, dirs_[dir]);
  // Only regions wider than tall (in pixels) take a direction: their tilt is what a few rows
  // leave open, and far treads, curbs and tread slivers at the image border are such strips
  // (the camera's roll is small). A tall, narrow region (a post, a leg, a door frame) leaves its
  // yaw open instead, and a borrowed yaw would mislead the Manhattan frame.
  const double in = 1.0 / m.n;
  const double su2 = (m.suu * in - (m.su * in) * (m.su * in)) * double(K_.fx) * K_.fx;
  const double sv2 = (m.svv * in - (m.sv * in) * (m.sv * in)) * double(K_.fy) * K_.fy;
  // Two more parameters always lower the residual a little; the fixed normal stays while the
  // free fit is not clearly better (the region is parallel to the direction within the noise).
  if (fixed.ok && sv2 <= su2 &&
      (!free.ok || fixed.rms_w <= 1.1f * free.rms_w + 0.1f * cfg_.depth_noise_coeff))
    return fixed;
  dir = -1;
  return free;
}

void Segmentation::backproject(const RgbdFrame& frame) {
  K_ = frame.intrinsics;
  W_ = frame.depth.cols;
  H_ = frame.depth.rows;
  div_magic_ = ((std::uint64_t(1) << 44) + static_cast<std::uint64_t>(W_) - 1) / static_cast<std::uint64_t>(W_);
  const std::size_t n = static_cast<std::size_t>(W_) * static_cast<std::size_t>(H_);
  z_.resize(n);
  w_.resize(n);
  un_.resize(static_cast<std::size_t>(W_));
  vn_.resize(static_cast<std::size_t>(H_));
  // label_ (-1) and tried_ (0) are initialised in the pass below, while each row is in cache.
  label_.resize(n);
  tried_.resize(n);
  queue_.resize(n);
  const float ifx = 1.f / K_.fx, ify = 1.f / K_.fy;
  for (int u = 0; u < W_; ++u) un_[u] = (static_cast<float>(u) - K_.cx) * ifx;
  for (int v = 0; v < H_; ++v) vn_[v] = (static_cast<float>(v) - K_.cy) * ify;
  int valid = 0;
  for (int v = 0; v < H_; ++v) {
    const float* d = frame.depth.ptr<float>(v);
    const std::size_t row = static_cast<std::size_t>(v) * static_cast<std::size_t>(W_);
    std::fill(label_.begin() + static_cast<long>(row), label_.begin() + static_cast<long>(row + W_), -1);
    std::memset(&tried_[row], 0, static_cast<std::size_t>(W_));
    int u = 0;
#if defined(__SSE2__)
    {
      // Four pixels at a time (the scalar loop does not vectorise: its division is conditional).
      // 1/z of a valid reading is the same correctly rounded quotient as the scalar division.
      const __m128 zero = _mm_setzero_ps(), one = _mm_set1_ps(1.f), big = _mm_set1_ps(1e6f);
      __m128i cnt = _mm_setzero_si128();
      for (; u + 4 <= W_; u += 4) {
        const __m128 dz = _mm_loadu_ps(d + u);
        const __m128 ok = _mm_and_ps(_mm_cmpgt_ps(dz, zero), _mm_cmplt_ps(dz, big));
        const __m128 z = _mm_and_ps(ok, dz);
        const __m128 safe = _mm_or_ps(z, _mm_andnot_ps(ok, one));
        _mm_storeu_ps(&z_[row + u], z);
        _mm_storeu_ps(&w_[row + u], _mm_and_ps(ok, _mm_div_ps(one, safe)));
        cnt = _mm_sub_epi32(cnt, _mm_castps_si128(ok));
      }
      alignas(16) int c4[4];
      _mm_store_si128(reinterpret_cast<__m128i*>(c4), cnt);
      valid += c4[0] + c4[1] + c4[2] + c4[3];
    }
#endif
    for (; u < W_; ++u) {
      float z = d[u];
      if (!(z > 0.f && z < 1e6f)) z = 0.f;  // no reading, NaN or infinite
      z_[row + u] = z;
      w_[row + u] = z > 0.f ? 1.f / z : 0.f;

      valid += z > 0.f;
    }
  }
  stats_ = {};
  stats_.valid_pixels = valid;
}

namespace {
/// line_pass: a pixel's neighbours in the rows above and below reach this many columns either
/// way (as far as a seed window is long, at the default strip_length_px). A far tread seen as a
/// line one pixel row tall has runs that meet the next row's only at their ends or across a gap
/// (the end pixels of each run are lost to the sensor's jump and shadow holes): gaps of 2-3
/// columns between runs of 7 at 3 m, of 6-7 between runs of 20 in a view rolled by some degrees.
constexpr int kLineReach = 8;
}  // namespace

template <int kReach>
int Segmentation::grow_pixels(int region, const std::vector<int>& seed_pixels, Grow& g) {
  int head = 0, tail = 0;
  for (int p : seed_pixels) {
    label_[p] = region;
    queue_[tail++] = p;
    const int v = row_of(p), u = p - v * W_;
    g.m.add(un_[u], vn_[v], w_[p]);
  }
  g.count = tail;
  PlaneFit f = g.dir >= 0 ? fit_plane_fixed_normal(g.m, dirs_[g.dir]) : fit_plane(g.m);
  if (f.ok) g.plane = f;
  int fit_count = g.count;
  float a = g.plane.a, b = g.plane.b, c = g.plane.c;
  const float kc = cfg_.inlier_sigmas * cfg_.depth_noise_coeff;
  // Local continuity: the step in 1/z between two neighbours must match the plane's slope within
  // the noise of two readings. This stops growth at occlusion edges, e.g. between the visible
  // strips of far descending treads, whose nosings line up on one sloped "pitch plane".
  const float kl = 1.41421356f * kc;
  // The moments and the count in locals during the growth (the region's struct in memory made
  // every accepted pixel wait on the last one's stores); the same additions in the same order.
  InvDepthMoments m = g.m;
  int count = g.count;
  while (head < tail) {
    const int p = queue_[head++];
    const int v = row_of(p), u = p - v * W_;
    const float wp = w_[p];
    const float up = un_[u], vp = vn_[v];
    // One neighbour (unrolled four times below, left, right, up, down, as a loop over a list
    // of them was: the order decides which region takes a contested pixel).
    auto visit = [&](int q, float uq, float vq) {
      if (label_[q] != -1) return;
      const float wq = w_[q];
      if (wq <= 0.f) return;
      const float res = wq - (a * uq + b * vq + c);
      if (std::fabs(res) > kc) return;
      const float step = (wq - wp) - (a * (uq - up) + b * (vq - vp));
      if (std::fabs(step) > kl) return;
      label_[q] = region;
      queue_[tail++] = q;
      m.add(uq, vq, wq);
      if (++count >= 2 * fit_count) {
        // Refit whenever the region doubled: the seed cell's plane is rough at range, the grown
        // region's is not, and doubling keeps the refits O(log n).
        const PlaneFit nf = g.dir >= 0 ? fit_plane_fixed_normal(m, dirs_[g.dir]) : fit_plane(m);
        if (nf.ok) {
          g.plane = nf;
          a = nf.a, b = nf.b, c = nf.c;
        }
        fit_count = count;
      }
    };
    if (u > 0) visit(p - 1, un_[u - 1], vp);
    if (u + 1 < W_) visit(p + 1, un_[u + 1], vp);
    if constexpr (kReach == 0) {
      if (v > 0) visit(p - W_, up, vn_[v - 1]);
      if (v + 1 < H_) visit(p + W_, up, vn_[v + 1]);
    } else {
      const int ua = std::max(0, u - kReach), ub = std::min(W_ - 1, u + kReach);
      if (v > 0)
        for (int uq = ua; uq <= ub; ++uq) visit(p - W_ + (uq - u), un_[uq], vn_[v - 1]);
      if (v + 1 < H_)
        for (int uq = ua; uq <= ub; ++uq) visit(p + W_ + (uq - u), un_[uq], vn_[v + 1]);
    }
  }
  g.m = m;
  g.count = count;
  const PlaneFit nf = region_plane(g.m, g.dir);
  if (nf.ok) g.plane = nf;
  return tail;
}

bool Segmentation::release_growth(int tail, Grow& g, int dir) {
  // Too small to be a region, or grown on a dominant direction its pixels reject: give its
  // pixels back for later seeds and for clustering.
  for (int i = 0; i < tail; ++i) label_[queue_[i]] = -1;
  released_ = tail;
  g.count = 0;
  g.m = {};
  ++stats_.regions_dropped;
  return dir >= 0 && g.dir < 0;
}

bool Segmentation::grow_region(int region, const std::vector<int>& seed_pixels, Grow& g) {
  const int dir = g.dir;
  const int tail = grow_pixels<0>(region, seed_pixels, g);
  if (g.count < cfg_.region_min_pixels || (dir >= 0 && g.dir < 0)) return release_growth(tail, g, dir);
  return false;
}

void Segmentation::seed_pass(int cell, std::vector<Grow>& grows) {
  if (cell < 2) return;
  cells_.clear();
  const int need = (cell * cell * 4) / 5;
  for (int v0 = 0; v0 + cell <= H_; v0 += cell) {
    for (int u0 = 0; u0 + cell <= W_; u0 += cell) {
      // A fine cell wholly inside a coarse cell that joined a region has no free pixel left.
      const int cu = ucell_[u0], cv = vcell_[v0];
      if (cu == ucell_[u0 + cell - 1] && cv == vcell_[v0 + cell - 1] && cu < CW_ && cv < CH_ &&
          cell_label_[static_cast<std::size_t>(cv * CW_ + cu)] >= 0)
        continue;
      // Count the free pixels first (integer work only): on real frames most fine cells left
      // over are edges and speckle that fail here.
      int cnt = 0;
      for (int v = v0; v < v0 + cell; ++v) {
        const int* lab = &label_[static_cast<std::size_t>(v) * W_ + u0];
        const float* z = &z_[static_cast<std::size_t>(v) * W_ + u0];
        for (int i = 0; i < cell; ++i) cnt += (lab[i] == -1) & (z[i] > 0.f);
      }
      if (cnt < need) continue;
      InvDepthMoments m;
      for (int v = v0; v < v0 + cell; ++v) {
        const int row = v * W_;
        for (int u = u0; u < u0 + cell; ++u) {
          const int p = row + u;
          if (label_[p] != -1 || z_[p] <= 0.f) continue;
          m.add(un_[u], vn_[v], w_[p]);
        }
      }
      float rms_w, mean_z;
      if (!plane_rms_depth(m, rms_w, mean_z)) continue;
      // Planar when the residual is within the depth noise (constant in 1/z for a Kinect).
      const float limit = 0.5f * tolerance_w();
      if (rms_w > limit) continue;
      // Nearer cells first: their planes are the most precise seeds.
      const float score = rms_w / limit + mean_z;
      cells_.push_back({u0, v0, score});
    }
  }
  stats_.planar_cells += static_cast<int>(cells_.size());
  sort_cells();
  for (const Cell& c : cells_) {
    // Re-fit on the pixels still free: an earlier region may have taken part of the cell.
    InvDepthMoments m;
    seed_pixels_.clear();
    int tried = 0;
    for (int v = c.v0; v < c.v0 + cell; ++v)
      for (int u = c.u0; u < c.u0 + cell; ++u) {
        const int p = v * W_ + u;
        if (label_[p] != -1 || z_[p] <= 0.f) continue;
        seed_pixels_.push_back(p);
        tried += tried_[p];
        m.add(un_[u], vn_[v], w_[p]);
      }
    // Mostly on pixels a seed before already grew into a region too small to keep: clutter
    // (real frames: hundreds of such seeds, each regrowing the same pixels).
    if (static_cast<int>(seed_pixels_.size()) < need || 2 * tried > static_cast<int>(seed_pixels_.size())) continue;
    const PlaneFit f = fit_plane(m);
    if (!f.ok) continue;
    Grow g;
    // A small cell's own tilt is rough at range (and a thin strip cut by the image border gives
    // no better): grow on a dominant direction when the cell lies on one within the noise.
    PlaneFit fc;
    g.dir = best_direction(m, fc);
    g.plane = g.dir >= 0 ? fc : f;
    ++stats_.seeds_used;
    released_ = 0;
    if (grow_region(static_cast<int>(grows.size()), seed_pixels_, g)) {
      // Its pixels reject the direction: the seed's own plane, then.
      g = Grow{};
      g.plane = f;
      released_ = 0;
      grow_region(static_cast<int>(grows.size()), seed_pixels_, g);
    }
    if (g.count == 0)
      for (int i = 0; i < released_; ++i) tried_[static_cast<std::size_t>(queue_[i])] = 1;
    // Dropped regions stay as empty slots: ids are stable.
    grows.push_back(g);
  }
}

void Segmentation::strip_pass(std::vector<Grow>& grows) {
  // Far treads seen from above, and treads cut by the image border, are strips of 2-3 rows: no
  // square cell fits in them. A window of two rows fixes a plane's offset but not its tilt, so
  // only dominant directions are tried here (one unknown, tested against 2 * len pixels).
  const int len = cfg_.strip_length_px;
  if (len < 2 || dirs_.empty()) return;
  cells_.clear();
  const int need = (2 * len * 3) / 4, need_row = len / 2;
  const float limit = 0.5f * tolerance_w();
  auto gather = [&](int u0, int v0, InvDepthMoments& m, std::vector<int>* pix) {
    // Count the free pixels first (cheap): most windows on real frames fail here. Pixels a fine
    // seed already grew into a too-small region (clutter) do not count.
    for (int v = v0; v < v0 + 2; ++v) {
      int cnt = 0;
      const std::size_t row = static_cast<std::size_t>(v) * W_ + u0;
      const int* lab = &label_[row];
      const float* z = &z_[row];
      const std::uint8_t* tried = &tried_[row];
      for (int i = 0; i < len; ++i) cnt += (lab[i] == -1) & (z[i] > 0.f) & (tried[i] == 0);
      if (cnt < need_row) return false;
    }
    int rows_ok = 0;
    for (int v = v0; v < v0 + 2; ++v) {
      int cnt = 0;
      const int row = v * W_;
      for (int u = u0; u < u0 + len; ++u) {
        const int p = row + u;
        if (label_[p] != -1 || z_[p] <= 0.f) continue;
        m.add(un_[u], vn_[v], w_[p]);
        if (pix) pix->push_back(p);
        ++cnt;
      }
      rows_ok += cnt >= need_row;
    }
    return rows_ok == 2 && m.n >= need;
  };
  for (int v0 = 0; v0 + 2 <= H_; ++v0) {
    const int cv0 = vcell_[v0], cv1 = vcell_[v0 + 1];
    for (int u0 = 0; u0 + len <= W_; u0 += len) {
      // Windows inside coarse cells that joined a region have no free pixel left.
      const int cu0 = ucell_[u0], cu1 = ucell_[u0 + len - 1];
      if (cu0 == cu1 && cu0 < CW_ && cv1 < CH_ && cell_label_[static_cast<std::size_t>(cv0 * CW_ + cu0)] >= 0 &&
          cell_label_[static_cast<std::size_t>(cv1 * CW_ + cu0)] >= 0)
        continue;
      InvDepthMoments m;
      if (!gather(u0, v0, m, nullptr)) continue;
      PlaneFit fc;
      if (best_direction(m, fc) < 0) continue;
      cells_.push_back({u0, v0, fc.rms_w / limit + fc.mean.z()});
    }
  }
  sort_cells();
  for (const Cell& c : cells_) {
    InvDepthMoments m;
    seed_pixels_.clear();
    if (!gather(c.u0, c.v0, m, &seed_pixels_)) continue;
    Grow g;
    g.dir = best_direction(m, g.plane);
    if (g.dir < 0) continue;
    ++stats_.seeds_used;
    grow_region(static_cast<int>(grows.size()), seed_pixels_, g);
    grows.push_back(g);
  }
}


bool Segmentation::grow_line(int region, const std::vector<int>& seed_pixels, Grow& g) {
  // grow_region's tests (plane within the noise, local continuity against the plane's slope) and
  // its refits on doubling, over the wider neighbourhood; the normal stays fixed to g.dir.
  const int dir = g.dir;
  const int tail = grow_pixels<kLineReach>(region, seed_pixels, g);
  const float kl = 1.41421356f * cfg_.inlier_sigmas * cfg_.depth_noise_coeff;  // two readings' noise
  // A far tread's line lies between two occlusion edges: below it in the image the nosing of the
  // tread before (nearer), above it its own nosing and the drop to the next tread (farther); both
  // are depth jumps or shadows. A line that continues without a jump into the pixels above or
  // below it is the edge of a surface seen at a crease (a shelf board's or a worktop's front
  // face, a rim a few centimetres below a top), which a plane through its middle explains within
  // the noise: not a level of its own. Counted over the line's pixels whose pixel above or below
  // is not in the line: a reading there within two readings' noise of it is a continuation.
  int sides = 0, smooth = 0;
  if (g.count >= cfg_.region_min_pixels && g.dir >= 0)
    for (int i = 0; i < tail; ++i) {
      const int p = queue_[i];
      const int v = row_of(p);
      const float wp = w_[p];
      for (int q : {p - W_, p + W_}) {
        if ((q < p && v == 0) || (q > p && v + 1 >= H_) || label_[q] == region) continue;
        ++sides;
        smooth += w_[q] > 0.f && std::fabs(w_[q] - wp) <= kl;
      }
    }
  if (g.count < cfg_.region_min_pixels || g.dir < 0 || 4 * smooth > sides) return release_growth(tail, g, dir);
  return false;
}

void Segmentation::line_pass(std::vector<Grow>& grows) {
  // What the strip windows miss: a tread of a descending flight at 3-5 m, seen from above over
  // the nosing before it, is a line one pixel row tall per column (its visible depth is a few
  // centimetres). Where the flight runs at an angle across the image, each row holds a run of a
  // few pixels that overlaps the next row's by a pixel or two, or not at all: no 2-row window
  // holds enough of it. A run of free pixels in one row fixes a plane's offset on a dominant
  // direction (one unknown, as the strip windows), and its growth reaches across the gaps
  // between rows. Only dominant directions: a line cannot fix a tilt.
  const int len = cfg_.strip_length_px;
  if (len < 2 || dirs_.empty()) return;
  const int need = std::max(3, (3 * len) / 4);
  const int cs = std::max(2, cfg_.cell_size_px);
  const float limit = 0.5f * tolerance_w();
  const float kl = 1.41421356f * cfg_.inlier_sigmas * cfg_.depth_noise_coeff;  // two readings' noise
  std::vector<LineSeed>& seeds = line_seeds_;
  seeds.clear();
  auto free_px = [&](int p) { return label_[p] == -1 && z_[p] > 0.f && tried_[p] == 0; };
  for (int v = 0; v < H_; ++v) {
    const int row = v * W_;
    const int cv = vcell_[v];
    for (int u = 0; u < W_;) {
      // A coarse cell that joined a region has no free pixel left.
      const int cu = ucell_[u];
      if (u == cu * cs && cv < CH_ && cu < CW_ && cell_label_[static_cast<std::size_t>(cv * CW_ + cu)] >= 0) {
        u += cs;
        continue;
      }
#if defined(__SSE2__)
      if (u + 4 <= W_ && v > 0 && v + 1 < H_) {
        // Most pixels here are taken (fine seeds, strips, edge pixels of the cell pass), holes, or
        // free pixels of clutter continuing into the rows above and below: four at a time while
        // none is free with a hole or a depth jump both above and below (see the windows below).
        const __m128 zero = _mm_setzero_ps();
        const __m128 absmask = _mm_castsi128_ps(_mm_set1_epi32(0x7FFFFFFF)), kl4 = _mm_set1_ps(kl);
        const __m128i lab = _mm_loadu_si128(reinterpret_cast<const __m128i*>(&label_[row + u]));
        const __m128 w = _mm_loadu_ps(&w_[row + u]);
        const __m128 wu = _mm_loadu_ps(&w_[row + u - W_]), wd = _mm_loadu_ps(&w_[row + u + W_]);
        const __m128 up = _mm_and_ps(_mm_cmpgt_ps(wu, zero), _mm_cmple_ps(_mm_and_ps(_mm_sub_ps(wu, w), absmask), kl4));
        const __m128 down = _mm_and_ps(_mm_cmpgt_ps(wd, zero), _mm_cmple_ps(_mm_and_ps(_mm_sub_ps(wd, w), absmask), kl4));
        const __m128 fr = _mm_and_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(lab, _mm_set1_epi32(-1))), _mm_cmpgt_ps(w, zero));
        if (_mm_movemask_ps(_mm_andnot_ps(_mm_or_ps(up, down), fr)) == 0) {
          u += 4;
          continue;
        }
      }
#endif
      if (!free_px(row + u)) {
        ++u;
        continue;
      }
      int e = u + 1;
      while (e < W_ && free_px(row + e)) ++e;
      // Windows of len columns along the run (a long run may bend), the last one if long enough.
      for (int s = u; s + need <= e; s += len) {
        const int n = std::min(len, e - s);
        // A line's pixels have a hole or a depth jump both above and below, but where it meets
        // the next row's run: a window with few such pixels is a row of a surface (clutter, the
        // rest of a region's edge), and its growth would be released (grow_line) at a cost.
        int enclosed = 0;
        for (int k = s; k < s + n; ++k) {
          const float wk = w_[row + k];
          const bool up = v > 0 && w_[row + k - W_] > 0.f && std::fabs(w_[row + k - W_] - wk) <= kl;
          const bool down = v + 1 < H_ && w_[row + k + W_] > 0.f && std::fabs(w_[row + k + W_] - wk) <= kl;
          enclosed += !up && !down;
        }
        if (4 * enclosed < n) continue;
        InvDepthMoments m;
        for (int k = s; k < s + n; ++k) m.add(un_[k], vn_[v], w_[row + k]);
        PlaneFit fc;
        if (best_direction(m, fc) < 0) continue;
        seeds.push_back({s, v, n, fc.rms_w / limit + fc.mean.z()});
      }
      u = e;
    }
  }
  // Nearer and better-fitting seeds first (as the other passes).
  // Ties in the order they were found (row, then column), as a stable sort gives, without the
  // buffer std::stable_sort allocates on every frame.
  std::sort(seeds.begin(), seeds.end(), [](const LineSeed& x, const LineSeed& y) {
    if (x.score != y.score) return x.score < y.score;
    return x.v != y.v ? x.v < y.v : x.u0 < y.u0;
  });
  for (const LineSeed& sd : seeds) {
    InvDepthMoments m;
    seed_pixels_.clear();
    const int row = sd.v * W_;
    for (int k = sd.u0; k < sd.u0 + sd.n; ++k) {
      if (!free_px(row + k)) continue;
      seed_pixels_.push_back(row + k);
      m.add(un_[k], vn_[sd.v], w_[row + k]);
    }
    if (static_cast<int>(seed_pixels_.size()) < need) continue;
    Grow g;
    g.dir = best_direction(m, g.plane);
    if (g.dir < 0) continue;
    ++stats_.seeds_used;
    released_ = 0;
    grow_line(static_cast<int>(grows.size()), seed_pixels_, g);
    if (g.count == 0)
      for (int i = 0; i < released_; ++i) tried_[static_cast<std::size_t>(queue_[i])] = 1;
    else
      ++stats_.line_regions;
    grows.push_back(g);
  }
}

static double InvDepthMomentsMsr(const InvDepthMoments& m, double a, double b, double c) {
  // Mean squared residual of the points under 1/z = a u' + b v' + c, from the moments.
  if (m.n <= 0) return 0.0;
  const double s = m.sww - 2 * a * m.suw - 2 * b * m.svw - 2 * c * m.sw + a * a * m.suu + 2 * a * b * m.suv +
                   b * b * m.svv + 2 * a * c * m.su + 2 * b * c * m.sv + c * c * m.n;
  return std::max(0.0, s / m.n);
}

namespace {
/// Moments of the points in `a` that are not in `b` (b a subset of a).
InvDepthMoments moments_minus(const InvDepthMoments& a, const InvDepthMoments& b) {
  InvDepthMoments m = a;
  m.n -= b.n; m.su -= b.su; m.sv -= b.sv; m.sw -= b.sw; m.suu -= b.suu; m.suv -= b.suv; m.svv -= b.svv;
  m.suw -= b.suw; m.svw -= b.svw; m.sww -= b.sww;
  return m;
}
/// Sum of squared inverse-depth residuals of a fit (rms_w is per point).
double fit_ssr(const PlaneFit& f, const InvDepthMoments& m) { return m.n * double(f.rms_w) * f.rms_w; }
// Split passes: smallest side of a split (pixels), and the drop of the summed squared residual
// (in squared noise sigmas) a split must bring. A split adds one plane offset and a choice of
// line; on one plane, noise alone lowers the residual by a few sigma^2 at most over all choices.
constexpr double kSplitMinSide = 24;
constexpr double kSplitGain = 60;
constexpr int kBorderBandRows = 6;  // slivers of up to this many rows at the top of the view
}  // namespace

bool Segmentation::move_to_new_region(std::vector<Grow>& grows, int r, const std::vector<int>& pixels, int dir) {
  Grow ng;
  for (int p : pixels) {
    const int v = row_of(p), u = p - v * W_;
    ng.m.add(un_[u], vn_[v], w_[p]);
  }
  const PlaneFit fn = fit_plane_fixed_normal(ng.m, dirs_[dir]);
  const InvDepthMoments rest = moments_minus(grows[r].m, ng.m);
  if (!fn.ok || rest.n < 3) return false;
  const int id = static_cast<int>(grows.size());
  for (int p : pixels) label_[p] = id;
  ng.plane = fn;
  ng.dir = dir;
  ng.count = static_cast<int>(pixels.size());
  Grow& g = grows[r];
  g.m = rest;
  g.count -= ng.count;
  // Cells of the region no longer hold one label: the later passes must visit their pixels.
  for (int& cl : cell_label_)
    if (cl == r) cl = -1;
  grows.push_back(ng);
  return true;
}

void Segmentation::split_creases(std::vector<Grow>& grows) {
  // At range, a cell across the edge between a tread and its riser (a few rows of each) is
  // planar within the noise: it grows into a strip whose plane is a blend of the two (tilted by
  // tens of degrees), and merging puts it into the tread or the riser, pulling that plane's edge.
  // Such a strip is split along the crease line of the two dominant directions whose blend it is:
  // the sweep across that line picks the split that best explains each side by one direction.
  if (dirs_.size() < 2) return;
  const int cs = std::max(2, cfg_.cell_size_px);
  const float cos_own = std::cos(cfg_.region_angle);
  const float cos_pair = std::cos(60.f * 3.14159265f / 180.f);
  const float sin_line = std::sin(10.f * 3.14159265f / 180.f);
  const float limit = 0.5f * tolerance_w();
  const double sig2 = double(cfg_.depth_noise_coeff) * cfg_.depth_noise_coeff;
  const int ng = static_cast<int>(grows.size());
  const int nd = static_cast<int>(dirs_.size());
  // Candidates and their direction pairs, from the moments alone.
  using Cand = SplitCand;  // r, direction pairs, image box holding the strip (moments + margin)
  std::vector<Cand>& cands = split_cands_;
  cands.clear();
  for (int r = 0; r < ng; ++r) {
    const Grow& g = grows[r];
    if (g.count < 2 * kSplitMinSide || g.dir >= 0 || !g.plane.ok) continue;
    const InvDepthMoments& m = g.m;
    const Eigen::Vector3f nr = g.plane.normal;
    bool on_dir = false;
    for (const Eigen::Vector3f& d : dirs_) on_dir |= std::fabs(d.dot(nr)) > cos_own;
    if (on_dir) continue;
    // The split can lower the summed squared residual by at most all of it.
    if (fit_ssr(g.plane, m) < kSplitGain * sig2) continue;
    // A strip one cell row tall (what the cell pass grows across a crease), wider than tall (the
    // crease runs along the image rows, give or take the staircase's yaw and the camera's roll).
    // Its height from the moments: rows spread evenly over h have variance h^2 / 12.
    const double in = 1.0 / m.n;
    const double mv = m.sv * in, mu = m.su * in;
    const double sv2 = (m.svv * in - mv * mv) * double(K_.fy) * K_.fy;
    const double su2 = (m.suu * in - mu * mu) * double(K_.fx) * K_.fx;
    if (sv2 > su2 || 12.0 * sv2 > 1.25 * 1.25 * cs * cs) continue;
    Cand c{r, 0, {}, 0, 0, 0, 0};
    // The two pairs whose crease line the strip's plane holds best (each sweep costs a pass over
    // the strip; real frames have a few hundred such strips).
    float off[2] = {sin_line, sin_line};
    for (int i = 0; i < nd; ++i)
      for (int j = i + 1; j < nd; ++j) {
        const float cij = dirs_[i].dot(dirs_[j]);
        if (std::fabs(cij) > cos_pair) continue;
        const Eigen::Vector3f t = dirs_[i].cross(dirs_[j]).normalized();
        const float o = std::fabs(t.dot(nr));
        if (o > off[1]) continue;  // the strip's plane does not hold the crease (or two hold it better)
        // The crease must run along the strip (within 30 degrees of the image rows): one across
        // it (a wall corner) does not make a strip a few rows tall.
        const Eigen::Vector3f& P = g.plane.mean;
        const float du = (t.x() * P.z() - P.x() * t.z()) * K_.fx, dv = (t.y() * P.z() - P.y() * t.z()) * K_.fy;
        if (std::fabs(dv) > 0.5f * std::sqrt(du * du + dv * dv)) continue;
        // The strip's normal must lie between the two (a blend of both), not beyond either.
        const float ci = nr.dot(dirs_[i]), cj = nr.dot(dirs_[j]);
        const float det = 1.f - cij * cij;
        const float al = (ci - cij * cj) / det, be = (cj - cij * ci) / det;
        if (!(al > 0.f && be > 0.f)) continue;
        const int at = o < off[0] ? 0 : 1;
        if (at == 0) off[1] = off[0], c.pairs[1][0] = c.pairs[0][0], c.pairs[1][1] = c.pairs[0][1];
        off[at] = o, c.pairs[at][0] = i, c.pairs[at][1] = j;
        c.np = std::min(2, c.np + 1);
      }
    if (c.np == 0) continue;
    // Uniform spread over an extent e has variance e^2 / 12: the box is 1.5 times that, plus a cell.
    const double hv = 1.5 * std::sqrt(3.0 * std::max(0.0, sv2)), hu = 1.5 * std::sqrt(3.0 * std::max(0.0, su2));
    const double vc = mv * K_.fy + K_.cy, uc = mu * K_.fx + K_.cx;
    c.v0 = std::max(0, static_cast<int>(vc - hv) - cs), c.v1 = std::min(H_ - 1, static_cast<int>(vc + hv) + cs);
    c.u0 = std::max(0, static_cast<int>(uc - hu) - cs), c.u1 = std::min(W_ - 1, static_cast<int>(uc + hu) + cs);
    cands.push_back(c);
  }
  std::vector<int>& pix = split_pixels_;
  std::vector<int>& side_a = split_side_;
  for (const Cand& cd : cands) {
    const int r = cd.r;
    pix.clear();
    for (int v = cd.v0; v <= cd.v1; ++v) {
      const int* lab = &label_[static_cast<std::size_t>(v) * W_];
      for (int u = cd.u0; u <= cd.u1; ++u)
        if (lab[u] == r) pix.push_back(v * W_ + u);
    }
    if (static_cast<int>(pix.size()) != grows[r].count) continue;  // not all inside the box: leave it
    const int p0 = 0, p1 = static_cast<int>(pix.size());
    const InvDepthMoments m = grows[r].m;
    const PlaneFit joint = fit_plane(m);
    if (!joint.ok) continue;
    const double ssr_joint = fit_ssr(joint, m);
    double best = ssr_joint;
    int best_pair = -1, best_k = 0, best_o = 0;
    float best_eu = 0, best_ev = 0, best_smin = 0;
    const Eigen::Vector3f P = grows[r].plane.mean;
    for (int pi = 0; pi < cd.np; ++pi) {
      const Eigen::Vector3f t = dirs_[cd.pairs[pi][0]].cross(dirs_[cd.pairs[pi][1]]).normalized();
      // Image direction of the crease line through the strip's centre, in pixels.
      float du = (t.x() * P.z() - P.x() * t.z()) * K_.fx, dv = (t.y() * P.z() - P.y() * t.z()) * K_.fy;
      const float ln = std::sqrt(du * du + dv * dv);
      if (!(ln > 1e-9f)) continue;
      du /= ln, dv /= ln;
      const float eu = -dv, ev = du;  // across the line
      float smin = 1e30f, smax = -1e30f;
      for (int k = p0; k < p1; ++k) {
        const int p = pix[k], v = row_of(p), u = p - v * W_;
        const float s = eu * u + ev * v;
        smin = std::min(smin, s), smax = std::max(smax, s);
      }
      const int nb = static_cast<int>(smax - smin) + 1;
      if (nb < 2 || nb > 4096) continue;
      bins_.assign(static_cast<std::size_t>(nb), InvDepthMoments{});
      for (int k = p0; k < p1; ++k) {
        const int p = pix[k], v = row_of(p), u = p - v * W_;
        bins_[static_cast<std::size_t>(eu * u + ev * v - smin)].add(un_[u], vn_[v], w_[p]);
      }
      InvDepthMoments A;
      for (int k = 1; k < nb; ++k) {
        A.add(bins_[static_cast<std::size_t>(k - 1)]);
        if (A.n < kSplitMinSide || m.n - A.n < kSplitMinSide) continue;
        const InvDepthMoments B = moments_minus(m, A);
        for (int o = 0; o < 2; ++o) {
          const PlaneFit fa = fit_plane_fixed_normal(A, dirs_[cd.pairs[pi][o]]);
          if (!fa.ok || fa.rms_w > limit) continue;
          const PlaneFit fb = fit_plane_fixed_normal(B, dirs_[cd.pairs[pi][1 - o]]);
          if (!fb.ok || fb.rms_w > limit) continue;
          const double ssr = fit_ssr(fa, A) + fit_ssr(fb, B);
          if (ssr < best) best = ssr, best_pair = pi, best_k = k, best_o = o, best_eu = eu, best_ev = ev, best_smin = smin;
        }
      }
    }
    if (best_pair < 0 || (ssr_joint - best) < kSplitGain * sig2) continue;
    // Side A (sweep bins below best_k) and side B; the bigger side keeps the region's id.
    const int da = cd.pairs[best_pair][best_o], db = cd.pairs[best_pair][1 - best_o];
    int na = 0;
    for (int k = p0; k < p1; ++k) {
      const int p = pix[k], v = row_of(p), u = p - v * W_;
      na += static_cast<int>(best_eu * u + best_ev * v - best_smin) < best_k;
    }
    const bool move_a = 2 * na <= p1 - p0;
    side_a.clear();
    for (int k = p0; k < p1; ++k) {
      const int p = pix[k], v = row_of(p), u = p - v * W_;
      if ((static_cast<int>(best_eu * u + best_ev * v - best_smin) < best_k) == move_a) side_a.push_back(p);
    }
    const int keep_dir = move_a ? db : da, move_dir = move_a ? da : db;
    if (!move_to_new_region(grows, r, side_a, move_dir)) continue;
    const PlaneFit fk = fit_plane_fixed_normal(grows[r].m, dirs_[keep_dir]);
    if (fk.ok) grows[r].plane = fk, grows[r].dir = keep_dir;
    ++stats_.crease_splits;
  }
}

void Segmentation::split_border_bands(std::vector<Grow>& grows) {
  // A tread seen as a sliver of one to a few rows at the top of the view, above its riser: each
  // pixel is within the noise of the riser's plane (near the crease the two planes are a few
  // millimetres apart, and at 3 m the noise is 1.5 cm), so the riser's region takes the sliver.
  // Together the sliver's pixels are clearly off the riser's plane and on a dominant direction:
  // split the band of rows off when that explains the region better by many noise sigmas.
  if (dirs_.empty() || H_ < 2 * kBorderBandRows) return;
  const int K = kBorderBandRows;
  const int n = static_cast<int>(grows.size());
  std::vector<int>& slot = cid_;
  slot.assign(static_cast<std::size_t>(n), -1);
  std::vector<int>& regs = live_;
  regs.clear();
  for (int u = 0; u < W_; ++u) {
    const int l = label_[u];
    if (l >= 0 && slot[l] < 0 && grows[l].count >= cfg_.region_min_pixels + static_cast<int>(kSplitMinSide)) {
      slot[l] = static_cast<int>(regs.size());
      regs.push_back(l);
    }
  }
  if (regs.empty()) return;
  bins_.assign(regs.size() * K, InvDepthMoments{});
  for (int v = 0; v < K; ++v) {
    const int* lab = &label_[static_cast<std::size_t>(v) * W_];
    for (int u = 0; u < W_; ++u) {
      const int l = lab[u];
      if (l < 0 || slot[l] < 0) continue;
      bins_[static_cast<std::size_t>(slot[l]) * K + v].add(un_[u], vn_[v], w_[v * W_ + u]);
    }
  }
  for (std::size_t i = 0; i < regs.size(); ++i) {
    const int r = regs[i];
    const BandSplit best = best_band_split(grows[r], &bins_[i * K], K, /*below_edge=*/false);
    if (best.dir < 0) {
      if (split_slanted_border_band(grows, r)) ++stats_.border_splits;
      continue;
    }
    std::vector<int>& pix = split_pixels_;
    pix.clear();
    for (int v = 0; v < best.rows; ++v)
      for (int u = 0; u < W_; ++u)
        if (label_[v * W_ + u] == r) pix.push_back(v * W_ + u);
    if (!move_to_new_region(grows, r, pix, best.dir)) continue;
    refit_region(grows[r]);
    ++stats_.border_splits;
  }
}

Segmentation::BandSplit Segmentation::best_band_split(const Grow& g, const InvDepthMoments* bins, int nb,
                                                      bool below_edge, int only_dir) const {
  // The band is the region's first k rows from the border or the edge (bins[0..k)), for each k up
  // to nb; it is split off onto a dominant direction when that explains the region better than
  // its one plane by kSplitGain noise sigmas.
  const int K = nb;
  // The direction a tread sliver may take against its riser's plane: square to it within 15
  // degrees below an edge (the edges found there are many, keep to treads); at the border any
  // crease of 60 degrees or more (oblique directions of clutter do not count).
  const float max_cos = below_edge ? std::sin(15.f * 3.14159265f / 180.f) : std::cos(60.f * 3.14159265f / 180.f);
  const float limit = 0.5f * tolerance_w();
  const double sig2 = double(cfg_.depth_noise_coeff) * cfg_.depth_noise_coeff;
  const int nd = static_cast<int>(dirs_.size());
  const double ssr_joint = g.m.n * InvDepthMomentsMsr(g.m, g.plane.a, g.plane.b, g.plane.c);
  double best = ssr_joint;
  BandSplit out;
  InvDepthMoments band;
  for (int k = 1; k <= K; ++k) {
    band.add(bins[k - 1]);
    if (band.n < cfg_.region_min_pixels) continue;
    // Below an edge the sliver lies behind the riser's plane (1/z below it): a convex edge.
    if (below_edge && !(band.mean_residual(g.plane.a, g.plane.b, g.plane.c) < 0.0)) continue;
    const InvDepthMoments rest = moments_minus(g.m, band);
    if (rest.n < (below_edge ? static_cast<double>(cfg_.region_min_pixels) : kSplitMinSide)) break;
    // What stays must be a plane (below an edge, one within the noise).
    const PlaneFit fr = fit_plane(rest);
    if (!fr.ok || (below_edge && fr.rms_w > limit)) continue;
    for (int d = only_dir < 0 ? 0 : only_dir; d < (only_dir < 0 ? nd : only_dir + 1); ++d) {
      if (std::fabs(dirs_[d].dot(g.plane.normal)) > max_cos) continue;
      // The sliver lies on that direction within the noise (a bent surface, a person, does not).
      const PlaneFit fb = fit_plane_fixed_normal(band, dirs_[d]);
      if (!fb.ok || fb.rms_w > limit) continue;
      // Below an edge, a convex edge as a tread's over its riser: each side lies beyond the
      // other's plane (the band's side was checked above). At a concave one (a floor meeting a
      // wall, a seat meeting its back) each lies in front of the other's: no tread there.
      if (below_edge && !(rest.mean_residual(fb.a, fb.b, fb.c) < 0.0)) continue;
      const double ssr = fit_ssr(fb, band) + fit_ssr(fr, rest);
      if (ssr < best) best = ssr, out.rows = k, out.dir = d;
    }
  }
  out.gain = ssr_joint - best;
  if (out.dir >= 0 && out.gain < kSplitGain * sig2) out = BandSplit{};
  return out;
}

bool Segmentation::split_slanted_border_band(std::vector<Grow>& grows, int r) {
  // A tread leaving the view at a slant (the staircase's yaw, the camera's roll): its sliver is a
  // wedge at the top border, a few rows deep at one end and none further along, where the riser
  // below reaches the border. A band of whole rows then holds riser pixels across the region's
  // width (several times the sliver's), and its fit on the tread's direction fails. The band here
  // is bounded by a line parallel to the crease the two planes make in the image, swept down from
  // the border; the same tests as for a band of rows decide.
  const Grow& g = grows[r];
  // The band must hold 1.5 times the smallest region and an eighth of its region at most (below).
  if (!g.plane.ok || g.count < 12 * cfg_.region_min_pixels) return false;
  const int K = 3 * kBorderBandRows;  // deepest wedge point tried, in pixels across the line
  const int R = std::min(H_, K);      // rows read
  std::vector<int>& pix = split_pixels_;
  pix.clear();
  double su0 = 0;
  int n0 = 0;
  for (int v = 0; v < R; ++v) {
    const int* lab = &label_[static_cast<std::size_t>(v) * W_];
    for (int u = 0; u < W_; ++u)
      if (lab[u] == r) {
        pix.push_back(v * W_ + u);
        if (v == 0) su0 += u, ++n0;
      }
  }
  if (n0 == 0 || static_cast<int>(pix.size()) < cfg_.region_min_pixels) return false;
  // The crease's image direction is taken where the region meets the border: the point of the
  // region's plane under its border pixels' mean column.
  const float un = (static_cast<float>(su0 / n0) - K_.cx) / K_.fx, vn = (0.f - K_.cy) / K_.fy;
  const float w = g.plane.a * un + g.plane.b * vn + g.plane.c;
  if (!(w > 1e-6f)) return false;
  const Eigen::Vector3f P(un / w, vn / w, 1.f / w);
  const float max_cos = std::cos(60.f * 3.14159265f / 180.f);
  const int nd = static_cast<int>(dirs_.size());
  BandSplit best;
  float best_eu = 0, best_ev = 0, best_smin = 0;
  for (int d = 0; d < nd; ++d) {
    if (std::fabs(dirs_[d].dot(g.plane.normal)) > max_cos) continue;
    const Eigen::Vector3f t3 = g.plane.normal.cross(dirs_[d]);
    if (!(t3.norm() > 1e-3f)) continue;
    const Eigen::Vector3f t = t3.normalized();
    float du = (t.x() * P.z() - P.x() * t.z()) * K_.fx, dv = (t.y() * P.z() - P.y() * t.z()) * K_.fy;
    const float ln = std::sqrt(du * du + dv * dv);
    if (!(ln > 1e-9f)) continue;
    du /= ln, dv /= ln;
    // Slanted, but along the rows within 30 degrees (a level band is the row pass's); steeper is
    // a wall's corner, not a tread's crease.
    if (std::fabs(dv) > 0.5f || std::fabs(dv) < 0.01f) continue;
    float eu = -dv, ev = du;  // across the line, pointing down the image
    if (ev < 0.f) eu = -eu, ev = -ev;
    float smin = 1e30f;
    for (int p : pix) {
      const int v = row_of(p), u = p - v * W_;
      smin = std::min(smin, eu * u + ev * v);
    }
    slant_bins_.assign(static_cast<std::size_t>(K), InvDepthMoments{});
    for (int p : pix) {
      const int v = row_of(p), u = p - v * W_;
      const int k = static_cast<int>(eu * u + ev * v - smin);
      if (k < K) slant_bins_[static_cast<std::size_t>(k)].add(un_[u], vn_[v], w_[p]);
    }
    const BandSplit b = best_band_split(g, slant_bins_.data(), K, /*below_edge=*/false, d);
    if (b.dir >= 0 && b.gain > best.gain) best = b, best_eu = eu, best_ev = ev, best_smin = smin;
  }
  if (best.dir < 0) return false;
  std::vector<int>& band = split_side_;
  band.clear();
  for (int p : pix) {
    const int v = row_of(p), u = p - v * W_;
    if (static_cast<int>(best_eu * u + best_ev * v - best_smin) < best.rows) band.push_back(p);
  }
  // The slanted band has more freedom than a band of rows (a direction and an offset per pixel
  // row), so it must also look like a tread's sliver over its riser: a wedge (the region holds
  // border pixels beyond it: else a band of rows would do), behind the region's plane (the convex
  // edge of a nosing seen from above it), sizeable on its own, and a small part of a region whose
  // plane it was all but lost in (clutter's small regions split on any slant otherwise).
  const int nb = static_cast<int>(band.size());
  InvDepthMoments bm;
  int b0 = 0;
  for (int p : band) {
    const int v = row_of(p), u = p - v * W_;
    bm.add(un_[u], vn_[v], w_[p]);
    b0 += v == 0;
  }
  if (b0 >= n0 || 2 * nb < 3 * cfg_.region_min_pixels || grows[r].count < 8 * nb ||
      !(bm.mean_residual(grows[r].plane.a, grows[r].plane.b, grows[r].plane.c) < 0.0))
    return false;
  if (!move_to_new_region(grows, r, band, best.dir)) return false;
  refit_region(grows[r]);
  return true;
}

void Segmentation::refit_region(Grow& g) const {
  int dir = g.dir;
  const PlaneFit f = region_plane(g.m, dir);
  if (f.ok) g.plane = f, g.dir = dir;
}

void Segmentation::split_edge_bands(std::vector<Grow>& grows) {
  // The same sliver as split_border_bands, below an occlusion edge instead of the image border:
  // the visible part of a far tread between its riser (below in the image) and the shadow of the
  // next nosing (no readings above it) is a few rows per column, each pixel within the noise of
  // the riser's plane, and the riser's region takes it. Only the top pixels of the columns of a
  // riser-like region that end under a hole can be such a sliver; the holes are found on the cell
  // grid (cells short of readings), so only their pixels are read.
  if (dirs_.size() < 2 || CW_ == 0 || cell_valid_.empty()) return;
  const int K = kBorderBandRows;
  const int cs = std::max(2, cfg_.cell_size_px);
  const int n = static_cast<int>(grows.size());
  const float cos_own = std::cos(cfg_.region_angle);
  // A tread and its riser meet at 90 degrees (give or take the build and the fits' noise).
  const float sin_cross = std::sin(15.f * 3.14159265f / 180.f);
  const float limit = 0.5f * tolerance_w();
  const double sig2 = double(cfg_.depth_noise_coeff) * cfg_.depth_noise_coeff;
  // Candidate regions: planar, parallel to a dominant direction (a riser, the front of a nosing)
  // and square to another one (the treads).
  std::vector<int>& slot = cid_;
  slot.assign(static_cast<std::size_t>(n), -1);
  std::vector<int>& regs = live_;
  regs.clear();
  for (int r = 0; r < n; ++r) {
    const Grow& g = grows[r];
    if (g.count < cfg_.region_min_pixels + static_cast<int>(kSplitMinSide) || !g.plane.ok || g.plane.rms_w > limit)
      continue;
    bool on_dir = false, square = false;
    for (const Eigen::Vector3f& d : dirs_) {
      const float c = std::fabs(d.dot(g.plane.normal));
      on_dir |= c > cos_own;
      square |= c < sin_cross;
    }
    if (!on_dir || !square) continue;
    slot[r] = static_cast<int>(regs.size());
    regs.push_back(r);
  }
  if (regs.empty()) return;
  // Tops of columns under a hole, in the cells at an occlusion edge: cells short of readings by
  // two rows' worth, or below such a cell, with readings of their own. A top is a pixel of a
  // candidate whose two upper neighbours have no reading. Per candidate and row below the edge
  // (band bins), the residuals under the candidate's plane are summed first (cheap, in floats):
  // a sliver of a tread lies behind the riser's plane (a convex edge) by many sigma^2 in all.
  const int holey = cs * cs - 2 * cs;
  std::vector<int>& tops = order_;
  tops.clear();
  std::vector<float>& acc = edge_acc_;  // per candidate and bin: count, sum and sum of squares of residuals
  acc.assign(regs.size() * static_cast<std::size_t>(3 * K), 0.f);
  // The edge over a tread's sliver runs along the image rows (give or take the staircase's yaw
  // and the camera's roll): its tops come in runs along a row. A top with no top of its region
  // beside it is on a side edge of the region (a riser's end, stepped holes down a slanted
  // border), whose pixels lie on the region's own plane and would spoil the band's fit.
  auto is_top = [&](int q, int l) { return label_[q] == l && !(z_[q - W_] > 0.f) && !(z_[q - 2 * W_] > 0.f); };
  auto edge_top = [&](int p) {
    const int l = label_[p];
    if (l < 0 || slot[l] < 0) return;
    const int v = row_of(p), u = p - v * W_;
    if (!((u > 0 && is_top(p - 1, l)) || (u + 1 < W_ && is_top(p + 1, l)))) return;
    tops.push_back(p);
    const PlaneFit& f = grows[l].plane;
    float* a = &acc[static_cast<std::size_t>(slot[l]) * 3 * K];
    for (int k = 0; k < K && v + k < H_ && label_[p + k * W_] == l; ++k) {
      const float res = w_[p + k * W_] - (f.a * un_[u] + f.b * vn_[v + k] + f.c);
      a[3 * k] += 1.f, a[3 * k + 1] += res, a[3 * k + 2] += res * res;
    }
  };
  for (int cv = 0; cv < CH_; ++cv)
    for (int cu = 0; cu < CW_; ++cu) {
      const int c = cv * CW_ + cu;
      const int nv = cell_valid_[static_cast<std::size_t>(c)];
      if (nv < cs || (nv > holey && (cv == 0 || cell_valid_[static_cast<std::size_t>(c - CW_)] > holey))) continue;
      const int u0 = cu * cs;
      // A top two rows or more down the cell has two of the cell's own pixels without a reading
      // above it; one in the first two rows has holes in the bottom rows of the cell above.
      const int v_first = cv > 0 && cell_valid_[static_cast<std::size_t>(c - CW_)] == cs * cs ? cv * cs + 2 : cv * cs;
      const int v_end = nv >= cs * cs - 1 ? cv * cs + 2 : (cv + 1) * cs;
      for (int v = std::max(2, v_first); v < v_end; ++v) {
        const int row = v * W_;
        // Columns of this row with a reading under two rows without: four at a time where the
        // cell allows (the holes make a branch per pixel mispredict; this test was most of the
        // pass's time).
        int i = 0;
#if defined(__SSE2__)
        const __m128 zero = _mm_setzero_ps();
        for (; i + 4 <= cs; i += 4) {
          const float* z0 = &z_[static_cast<std::size_t>(row + u0 + i)];
          const __m128 top = _mm_cmpgt_ps(_mm_loadu_ps(z0), zero);
          const __m128 above = _mm_or_ps(_mm_cmpgt_ps(_mm_loadu_ps(z0 - W_), zero), _mm_cmpgt_ps(_mm_loadu_ps(z0 - 2 * W_), zero));
          int mask = _mm_movemask_ps(_mm_andnot_ps(above, top));
          while (mask) {
            const int j = __builtin_ctz(static_cast<unsigned>(mask));
            mask &= mask - 1;
            edge_top(row + u0 + i + j);
          }
        }
#endif
        for (; i < cs; ++i) {
          const int p = row + u0 + i;
          if (z_[p] > 0.f && !(z_[p - W_] > 0.f) && !(z_[p - 2 * W_] > 0.f)) edge_top(p);
        }
      }
    }
  if (tops.empty()) return;
  // Candidates whose band, for some depth, holds enough pixels, lies behind the plane and is off
  // it by half the gain a split needs (the rest of the gain can come from the rest's refit).
  bool any = false;
  for (std::size_t i = 0; i < regs.size(); ++i) {
    const float* a = &acc[i * 3 * K];
    float cnt = 0.f, sr = 0.f, srr = 0.f;
    bool pass = false;
    for (int k = 0; k < K; ++k) {
      cnt += a[3 * k], sr += a[3 * k + 1], srr += a[3 * k + 2];
      pass |= cnt >= cfg_.region_min_pixels && sr < 0.f && srr >= 0.5 * kSplitGain * sig2;
    }
    if (a[0] < kSplitMinSide || !pass) slot[regs[i]] = -1;
    any |= slot[regs[i]] >= 0;
  }
  if (!any) return;
  bins_.assign(regs.size() * static_cast<std::size_t>(K), InvDepthMoments{});
  for (int p : tops) {
    const int l = label_[p];
    if (slot[l] < 0) continue;
    const int v = row_of(p), u = p - v * W_;
    InvDepthMoments* b = &bins_[static_cast<std::size_t>(slot[l]) * K];
    for (int k = 0; k < K && v + k < H_ && label_[p + k * W_] == l; ++k) b[k].add(un_[u], vn_[v + k], w_[p + k * W_]);
  }
  for (std::size_t i = 0; i < regs.size(); ++i) {
    const int r = regs[i];
    if (slot[r] < 0) continue;
    const BandSplit best = best_band_split(grows[r], &bins_[i * K], K, /*below_edge=*/true);
    if (best.dir < 0) continue;
    std::vector<int>& pix = split_pixels_;
    pix.clear();
    for (int p : tops) {
      const int v = row_of(p);
      for (int k = 0; k < best.rows && v + k < H_ && label_[p + k * W_] == r; ++k) pix.push_back(p + k * W_);
    }
    if (!move_to_new_region(grows, r, pix, best.dir)) continue;
    refit_region(grows[r]);
    ++stats_.edge_splits;
  }
}

void Segmentation::sort_cells() {
  // Seeds in ascending score, sorted as 64-bit keys (the score's bits made monotonic as an
  // unsigned integer: negatives flipped, positives with the sign bit set; then the index) instead
  // of as 12-byte cells with a float compare: a fifth faster. The compare looks at the score bits
  // only: the same outcomes as comparing the scores, so the same introsort steps and the same
  // order, ties included. (A stable radix sort was 4 times faster still but orders ties another
  // way; real depth is quantised, ties are common, and the seed order moved up to 16 of ~100
  // regions a kitchen frame.)
  const std::size_t n = cells_.size();
  if (n < 2) return;
  sort_keys_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    std::uint32_t b;
    const float sc = cells_[i].score + 0.f;  // -0 -> +0: the two compare equal as floats
    std::memcpy(&b, &sc, sizeof b);
    b = (b & 0x80000000u) ? ~b : (b | 0x80000000u);
    sort_keys_[i] = (static_cast<std::uint64_t>(b) << 32) | static_cast<std::uint64_t>(i);
  }
  std::sort(sort_keys_.begin(), sort_keys_.end(),
            [](std::uint64_t x, std::uint64_t y) { return (x >> 32) < (y >> 32); });
  const std::uint64_t* a = sort_keys_.data();
  cells_tmp_.resize(n);
  for (std::size_t i = 0; i < n; ++i) cells_tmp_[i] = cells_[static_cast<std::size_t>(a[i] & 0xFFFFFFFFu)];
  cells_.swap(cells_tmp_);
}

void Segmentation::cell_pass(std::vector<Grow>& grows) {
  const int cs = std::max(2, cfg_.cell_size_px);
  CW_ = W_ / cs;
  CH_ = H_ / cs;
  const int nc = CW_ * CH_;
  // Cell of each column / row (the later passes look these up instead of dividing per pixel).
  ucell_.resize(static_cast<std::size_t>(W_));
  vcell_.resize(static_cast<std::size_t>(H_));
  for (int u = 0; u < W_; ++u) ucell_[u] = u / cs;
  for (int v = 0; v < H_; ++v) vcell_[v] = v / cs;
  cell_m_.assign(static_cast<std::size_t>(nc), InvDepthMoments{});
  cell_label_.assign(static_cast<std::size_t>(nc), -1);
  cell_planar_.assign(static_cast<std::size_t>(nc), 0);
  cell_valid_.assign(static_cast<std::size_t>(nc), 0);
  cells_.clear();
  const int need = (cs * cs * 4) / 5;
  const float limit = 0.5f * tolerance_w();
  // Offsets of the normalised coordinates inside a cell, and their sums over a full cell.
  std::vector<float>& gu = gu_;
  std::vector<float>& gv = gv_;
  gu.resize(static_cast<std::size_t>(cs));
  gv.resize(static_cast<std::size_t>(cs));
  float full[5] = {0, 0, 0, 0, 0};  // Su, Sv, Suu, Suv, Svv
  for (int i = 0; i < cs; ++i) {
    gu[i] = static_cast<float>(i) / K_.fx;
    gv[i] = static_cast<float>(i) / K_.fy;
  }
  for (int j = 0; j < cs; ++j)
    for (int i = 0; i < cs; ++i) {
      full[0] += gu[i];
      full[1] += gv[j];
      full[2] += gu[i] * gu[i];
      full[3] += gu[i] * gv[j];
      full[4] += gv[j] * gv[j];
    }
  // Float sums centred on the cell (exact enough for a few dozen pixels, and twice as fast),
  // shifted to the global double moments afterwards. The reference value w0 is the cell's first
  // valid reading (0: the cell has none).
  auto first_w = [&](int cu, int cv) {
    const int u0 = cu * cs, v0 = cv * cs;
    for (int v = v0; v < v0 + cs; ++v)
      for (int u = u0; u < u0 + cs; ++u)
        if (w_[static_cast<std::size_t>(v) * W_ + u] > 0.f) return w_[static_cast<std::size_t>(v) * W_ + u];
    return 0.f;
  };
  // The rest of a cell once its sums with w are known (n: count of valid pixels).
  auto finish = [&](int cu, int cv, float w0, float n, float Sw, float Suw, float Svw, float Sww) {
    if (n < need) return;
    InvDepthMoments& m = cell_m_[static_cast<std::size_t>(cv * CW_ + cu)];
    const int u0 = cu * cs, v0 = cv * cs;
    const float uc = un_[u0], vc = vn_[v0];
    // The pixel-coordinate sums: those of a full cell (most cells), else summed over the valid.
    float Su = full[0], Sv = full[1], Suu = full[2], Suv = full[3], Svv = full[4];
    if (n < static_cast<float>(cs * cs)) {
      Su = Sv = Suu = Suv = Svv = 0.f;
      for (int v = v0; v < v0 + cs; ++v) {
        const float dv = gv[v - v0];
        const float* w = &w_[static_cast<std::size_t>(v) * W_ + u0];
        for (int i = 0; i < cs; ++i) {
          const float ok = w[i] > 0.f ? 1.f : 0.f;
          const float du = gu[i] * ok, dvv = dv * ok;
          Su += du; Sv += dvv;
          Suu += du * du; Suv += du * dvv; Svv += dvv * dvv;
        }
      }
    }
    const double U = uc, V = vc, Wc = w0;
    m.n = n;
    m.su = Su + n * U;
    m.sv = Sv + n * V;
    m.sw = Sw + n * Wc;
    m.suu = Suu + 2 * U * Su + n * U * U;
    m.suv = Suv + U * Sv + V * Su + n * U * V;
    m.svv = Svv + 2 * V * Sv + n * V * V;
    m.suw = Suw + U * Sw + Wc * Su + n * U * Wc;
    m.svw = Svw + V * Sw + Wc * Sv + n * V * Wc;
    m.sww = Sww + 2 * Wc * Sw + n * Wc * Wc;
    float rms_w, mean_z;
    // Planar when the residual is within the depth noise (constant in 1/z for a Kinect).
    if (!plane_rms_depth(m, rms_w, mean_z) || rms_w > limit) return;
    cell_planar_[static_cast<std::size_t>(cv * CW_ + cu)] = 1;
    // Nearer cells first: their planes are the most precise seeds.
    cells_.push_back({cu, cv, rms_w / limit + mean_z});
  };
  for (int cv = 0; cv < CH_; ++cv) {
    const int v0 = cv * cs;
    int cu = 0;
#if defined(__SSE2__)
    // Four horizontally adjacent cells at once, one per SIMD lane: each lane adds its cell's
    // pixels in the same order as the scalar loop below, so the sums are bit-identical.
    if (cs % 4 == 0) {
      const __m128 zero = _mm_setzero_ps(), one = _mm_set1_ps(1.f);
      for (; cu + 4 <= CW_; cu += 4) {
        alignas(16) float w0s[4];
        for (int k = 0; k < 4; ++k) w0s[k] = first_w(cu + k, cv);
        if (w0s[0] == 0.f && w0s[1] == 0.f && w0s[2] == 0.f && w0s[3] == 0.f) continue;
        const __m128 w0 = _mm_load_ps(w0s);
        __m128 n = zero, Sw = zero, Suw = zero, Svw = zero, Sww = zero;
        for (int v = v0; v < v0 + cs; ++v) {
          const __m128 dv = _mm_set1_ps(gv[v - v0]);
          const float* base = &w_[static_cast<std::size_t>(v) * W_ + static_cast<std::size_t>(cu * cs)];
          for (int i = 0; i < cs; i += 4) {
            __m128 r0 = _mm_loadu_ps(base + i), r1 = _mm_loadu_ps(base + cs + i);
            __m128 r2 = _mm_loadu_ps(base + 2 * cs + i), r3 = _mm_loadu_ps(base + 3 * cs + i);
            _MM_TRANSPOSE4_PS(r0, r1, r2, r3);  // r<j>: pixel i + j of the four cells
            const __m128 px[4] = {r0, r1, r2, r3};
            for (int j = 0; j < 4; ++j) {
              const __m128 w = px[j];
              const __m128 ok = _mm_and_ps(_mm_cmpgt_ps(w, zero), one);
              const __m128 dw = _mm_mul_ps(_mm_sub_ps(w, w0), ok);
              const __m128 g = _mm_set1_ps(gu[i + j]);
              n = _mm_add_ps(n, ok);
              Sw = _mm_add_ps(Sw, dw);
              Suw = _mm_add_ps(Suw, _mm_mul_ps(g, dw));
              Svw = _mm_add_ps(Svw, _mm_mul_ps(dv, dw));
              Sww = _mm_add_ps(Sww, _mm_mul_ps(dw, dw));
            }
          }
        }
        alignas(16) float an[4], asw[4], asuw[4], asvw[4], asww[4];
        _mm_store_ps(an, n);
        _mm_store_ps(asw, Sw);
        _mm_store_ps(asuw, Suw);
        _mm_store_ps(asvw, Svw);
        _mm_store_ps(asww, Sww);
        for (int k = 0; k < 4; ++k) {
          cell_valid_[static_cast<std::size_t>(cv * CW_ + cu + k)] = static_cast<std::uint16_t>(an[k]);
          if (w0s[k] != 0.f) finish(cu + k, cv, w0s[k], an[k], asw[k], asuw[k], asvw[k], asww[k]);
        }
      }
    }
#endif
    for (; cu < CW_; ++cu) {
      const int u0 = cu * cs;
      const float w0 = first_w(cu, cv);
      if (w0 == 0.f) continue;
      // Sums with w first: an invalid pixel has dw = 0, so only the count needs the mask there.
      float n = 0, Sw = 0, Suw = 0, Svw = 0, Sww = 0;
      for (int v = v0; v < v0 + cs; ++v) {
        const float dv = gv[v - v0];
        const float* w = &w_[static_cast<std::size_t>(v) * W_ + u0];
        for (int i = 0; i < cs; ++i) {
          const float ok = w[i] > 0.f ? 1.f : 0.f;
          const float dw = (w[i] - w0) * ok;
          n += ok;
          Sw += dw;
          Suw += gu[i] * dw;
          Svw += dv * dw;
          Sww += dw * dw;
        }
      }
      cell_valid_[static_cast<std::size_t>(cv * CW_ + cu)] = static_cast<std::uint16_t>(n);
      finish(cu, cv, w0, n, Sw, Suw, Svw, Sww);
    }
  }
  stats_.planar_cells = static_cast<int>(cells_.size());
  sort_cells();

  // Region growing over the cell grid: a planar neighbour joins when the region's plane explains
  // its pixels within the noise (mean squared residual from the moments: no pixel is touched).
  const double thr = 4.0 * double(cfg_.depth_noise_coeff) * cfg_.depth_noise_coeff;  // (2 sigma)^2
  std::vector<int>& q = next_;
  for (const Cell& seed : cells_) {
    const int c0 = seed.v0 * CW_ + seed.u0;
    if (cell_label_[c0] != -1) continue;
    const int r = static_cast<int>(grows.size());
    Grow g;
    g.m = cell_m_[c0];
    g.plane = fit_plane(g.m);
    if (!g.plane.ok) continue;
    ++stats_.seeds_used;
    q.clear();
    q.push_back(c0);
    cell_label_[c0] = r;
    double fit_n = g.m.n;
    for (std::size_t h = 0; h < q.size(); ++h) {
      const int c = q[h];
      const int cv = c / CW_, cu = c - cv * CW_;
      const int nb[4] = {cu > 0 ? c - 1 : -1, cu + 1 < CW_ ? c + 1 : -1, cv > 0 ? c - CW_ : -1,
                         cv + 1 < CH_ ? c + CW_ : -1};
      for (int k : nb) {
        if (k < 0 || !cell_planar_[k] || cell_label_[k] != -1) continue;
        if (InvDepthMomentsMsr(cell_m_[k], g.plane.a, g.plane.b, g.plane.c) > thr) continue;
        cell_label_[k] = r;
        q.push_back(k);
        g.m.add(cell_m_[k]);
        if (g.m.n >= 2 * fit_n) {
          const PlaneFit f = fit_plane(g.m);
          if (f.ok) g.plane = f;
          fit_n = g.m.n;
        }
      }
    }
    const PlaneFit f = fit_plane(g.m);
    if (f.ok) g.plane = f;
    g.count = static_cast<int>(g.m.n);
    if (q.size() < 2 && g.count < cfg_.region_min_pixels) {
      // A lone cell: leave its pixels to the pixel-level passes.
      cell_label_[c0] = -1;
      cell_planar_[c0] = 0;
      continue;
    }
    grows.push_back(g);
  }
  // Pixels of the region cells.
  for (int c = 0; c < nc; ++c) {
    const int r = cell_label_[c];
    if (r < 0) continue;
    const int cv = c / CW_, cu = c - cv * CW_;
    for (int v = cv * cs; v < (cv + 1) * cs; ++v) {
      int* l = &label_[static_cast<std::size_t>(v) * W_];
      const float* w = &w_[static_cast<std::size_t>(v) * W_];
      // Branch-free (vectorised): these pixels are all still -1.
      for (int u = cu * cs; u < (cu + 1) * cs; ++u) l[u] = w[u] > 0.f ? r : -1;
    }
  }
  // Pixel-level refinement of the other cells next to regions (edges between planes, holes,
  // partial cells): each pixel joins the neighbouring region whose plane fits it best, if any fits.
  const float tw = tolerance_w();
  const int cell_px = cs * cs;
  cell_pix_.resize(static_cast<std::size_t>(2 * cell_px));
  cell_sel_.resize(static_cast<std::size_t>(cell_px));
  int* row_in_cell = cell_pix_.data() + cell_px;  // k / cs for k < cs * cs
  for (int k = 0; k < cell_px; ++k) row_in_cell[k] = k / cs;
  for (int c = 0; c < nc; ++c) {
    if (cell_label_[c] >= 0) continue;
    const int cv = c / CW_, cu = c - cv * CW_;
    int cand[8], nk = 0;
    for (int dv = -1; dv <= 1; ++dv)
      for (int du = -1; du <= 1; ++du) {
        const int u2 = cu + du, v2 = cv + dv;
        if ((du == 0 && dv == 0) || u2 < 0 || v2 < 0 || u2 >= CW_ || v2 >= CH_) continue;
        const int r = cell_label_[v2 * CW_ + u2];
        if (r < 0) continue;
        bool dup = false;
        for (int i = 0; i < nk; ++i) dup |= cand[i] == r;
        if (!dup) cand[nk++] = r;
      }
    if (nk == 0) continue;
    // The candidates' plane coefficients in registers.
    float pa[8], pb[8], pc[8];
    int lab_of[9];
    for (int i = 0; i < nk; ++i) {
      const PlaneFit& f = grows[cand[i]].plane;
      pa[i] = f.a, pb[i] = f.b, pc[i] = f.c;
      lab_of[i] = cand[i];
    }
    lab_of[nk] = -1;
    // Two steps, both without data-dependent branches (which pixels fit which plane is noise on
    // real frames: a branch per pixel mispredicted about every other pixel, and the per-pixel
    // update of a region's moments in memory chained each pixel to the last). First each pixel's
    // best candidate (slot nk: none, also for pixels without a reading: bres < 0 admits none);
    // then each candidate's moments, held in registers, take its pixels in raster order: every
    // region's sums see the same additions in the same order as one pass adding pixel by pixel,
    // so they are bit-identical to it.
    int* lists = cell_pix_.data();
    std::uint8_t* sel = cell_sel_.data();
    const int u0 = cu * cs, v0 = cv * cs;
    for (int v = v0; v < v0 + cs; ++v) {
      const float vv = vn_[v];
      const float* wr = &w_[static_cast<std::size_t>(v) * W_];
      int* lr = &label_[static_cast<std::size_t>(v) * W_];
      int u = u0;
#if defined(__SSE2__)
      // Four pixels at a time: the scan over the candidates is a chain of compares through the
      // best residual, one chain per pixel; four chains run side by side in the lanes. Each lane
      // computes the same float expression as the scalar loop below (same operations, same
      // order, no FMA): the choices are bit-identical.
      {
        const __m128 vvv = _mm_set1_ps(vv), zero = _mm_setzero_ps(), tw4 = _mm_set1_ps(tw), neg = _mm_set1_ps(-1.f);
        const __m128 absmask = _mm_castsi128_ps(_mm_set1_epi32(0x7FFFFFFF));
        for (; u + 4 <= u0 + cs; u += 4) {
          const __m128 w = _mm_loadu_ps(wr + u);
          const __m128 uu = _mm_loadu_ps(&un_[static_cast<std::size_t>(u)]);
          const __m128 valid = _mm_cmpgt_ps(w, zero);
          __m128 bres = _mm_or_ps(_mm_and_ps(valid, tw4), _mm_andnot_ps(valid, neg));
          __m128i best = _mm_set1_epi32(nk);
          for (int i = 0; i < nk; ++i) {
            const __m128 au = _mm_mul_ps(_mm_set1_ps(pa[i]), uu), bv = _mm_mul_ps(_mm_set1_ps(pb[i]), vvv);
            const __m128 pl = _mm_add_ps(_mm_add_ps(au, bv), _mm_set1_ps(pc[i]));
            const __m128 res = _mm_and_ps(_mm_sub_ps(w, pl), absmask);
            const __m128 le = _mm_cmple_ps(res, bres);
            bres = _mm_or_ps(_mm_and_ps(le, res), _mm_andnot_ps(le, bres));
            const __m128i lei = _mm_castps_si128(le);
            best = _mm_or_si128(_mm_and_si128(lei, _mm_set1_epi32(i)), _mm_andnot_si128(lei, best));
          }
          alignas(16) int b4[4];
          _mm_store_si128(reinterpret_cast<__m128i*>(b4), best);
          for (int k = 0; k < 4; ++k) {
            lr[u + k] = lab_of[b4[k]];
            sel[(v - v0) * cs + u + k - u0] = static_cast<std::uint8_t>(b4[k]);
          }
        }
      }
#endif
      for (; u < u0 + cs; ++u) {
        const float w = wr[u];
        const float uu = un_[u];
        int best = nk;
        float bres = w > 0.f ? tw : -1.f;
        for (int i = 0; i < nk; ++i) {
          const float res = std::fabs(w - (pa[i] * uu + pb[i] * vv + pc[i]));
          if (res <= bres) bres = res, best = i;
        }
        lr[u] = lab_of[best];  // -1 (as before) when none fits
        sel[(v - v0) * cs + u - u0] = static_cast<std::uint8_t>(best);
      }
    }
    for (int i = 0; i < nk; ++i) {
      // This candidate's pixels, in raster order (a branch-free compaction).
      int n = 0;
      for (int k = 0; k < cell_px; ++k) {
        lists[n] = k;
        n += sel[k] == i;
      }
      if (n == 0) continue;
      Grow& g = grows[cand[i]];
      InvDepthMoments m = g.m;
      for (int j = 0; j < n; ++j) {
        const int dv = row_in_cell[lists[j]], u = u0 + lists[j] - dv * cs, v = v0 + dv;
        m.add(un_[u], vn_[v], w_[static_cast<std::size_t>(v) * W_ + u]);
      }
      g.m = m;
      g.count += n;
    }
  }
  // Pixels of the image margin not covered by whole cells are left to the fine pass.
}

namespace {
/// End of the run of equal labels starting at lab[u] (first index in (u, end) with another label,
/// or end). Labels come in long runs (a tread spans hundreds of pixels of a row): four at a time
/// with one compare, where a pixel-by-pixel loop was a fifth of the region pass on real frames.
inline int run_end(const int* lab, int u, int end) {
  const int l = lab[u];
  int e = u + 1;
#if defined(__SSE2__)
  const __m128i vl = _mm_set1_epi32(l);
  for (; e + 4 <= end; e += 4) {
    const __m128i x = _mm_loadu_si128(reinterpret_cast<const __m128i*>(lab + e));
    const int eq = _mm_movemask_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(x, vl)));
    if (eq != 0xF) return e + __builtin_ctz(static_cast<unsigned>(~eq & 0xF));
  }
#endif
  while (e < end && lab[e] == l) ++e;
  return e;
}

int find_root(std::vector<int>& parent, int a) {
  while (parent[a] != a) {
    parent[a] = parent[parent[a]];
    a = parent[a];
  }
  return a;
}
}  // namespace

void Segmentation::merge_regions(std::vector<Grow>& grows) {
  const int n = static_cast<int>(grows.size());
  // Dropped seeds leave empty slots (often most of them on cluttered real frames): the pair
  // tables below are over the live regions only.
  std::vector<int>& cid = cid_;
  std::vector<int>& live = live_;
  cid.assign(static_cast<std::size_t>(n), -1);
  live.clear();
  for (int r = 0; r < n; ++r)
    if (grows[r].count > 0) cid[r] = static_cast<int>(live.size()), live.push_back(r);
  const int m = static_cast<int>(live.size());
  seams_.clear();
  if (m < 2 || m > 4096) return;
  std::vector<std::uint8_t>& adj = mask_;
  adj.assign(static_cast<std::size_t>(m) * m, 0);
  // The seam samples (pixel pairs of two regions) are kept for drop_curved_tiles.
  std::vector<int>& seams = seams_;
  seams.clear();
  auto mark = [&](int p, int q) {
    const int a = label_[p], b = label_[q];
    if (b < 0 || a == b) return;
    seams.push_back(p);
    seams.push_back(q);
    const int ca = cid[a], cb = cid[b];
    adj[static_cast<std::size_t>(std::min(ca, cb)) * m + std::max(ca, cb)] = 1;
  };
  // Regions touching directly or across a one-pixel gap of unassigned (noisy) pixels. Every
  // other row and column is enough to see two regions that share a border.
  // Inside a region cell every valid pixel carries the cell's label: a pixel whose right and
  // lower neighbours (and the ones beyond them) are still in the cell marks nothing, and is skipped.
  const int cs = std::max(2, cfg_.cell_size_px);
  for (int v = 0; v < H_; v += 2) {
    const int cv = vcell_[v];
    const bool inner_row = cv < CH_ && v + 2 < (cv + 1) * cs;
    for (int u = 0, cu = 0; u < W_; ++cu) {
      const int ue = cu < CW_ ? u + cs : W_;
      if (inner_row && cu < CW_ && cell_label_[static_cast<std::size_t>(cv * CW_ + cu)] >= 0) u += cs - 2;
      for (; u < ue; ++u) {
        const int p = v * W_ + u;
        const int a = label_[p];
        if (a < 0) continue;
        if (u + 1 < W_) {
          const int b = label_[p + 1];
          if (b >= 0) {
            if (b != a) mark(p, p + 1);
          } else if (u + 2 < W_) {
            mark(p, p + 2);
          }
        }
        if ((u & 1) == 0 && v + 1 < H_) {
          const int b = label_[p + W_];
          if (b >= 0) {
            if (b != a) mark(p, p + W_);
          } else if (v + 2 < H_) {
            mark(p, p + 2 * W_);
          }
        }
      }
    }
  }
  std::vector<int> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  const float cos_max = std::cos(2.f * cfg_.region_angle);
  for (int ca = 0; ca < m; ++ca) {
    for (int cb = ca + 1; cb < m; ++cb) {
      if (!adj[static_cast<std::size_t>(ca) * m + cb]) continue;
      const int ra = find_root(parent, live[ca]), rb = find_root(parent, live[cb]);
      if (ra == rb || grows[ra].count == 0 || grows[rb].count == 0) continue;
      const PlaneFit& pa = grows[ra].plane;
      const PlaneFit& pb = grows[rb].plane;
      if (pa.normal.dot(pb.normal) < cos_max) continue;
      InvDepthMoments m = grows[ra].m;
      m.add(grows[rb].m);
      // A part grown on a dominant direction keeps it while the union does not reject it.
      int dir = grows[ra].dir;
      if (grows[rb].dir >= 0 && (dir < 0 || grows[rb].count > grows[ra].count)) dir = grows[rb].dir;
      const PlaneFit f = region_plane(m, dir);
      if (!f.ok) continue;
      // Each part's mean residual under the union's plane within the noise. (Not under the
      // other part's plane: a small part's tilt is poorly fixed, and extrapolated over a big
      // neighbour it misses by many sigmas. On real frames that split every floor and wall into
      // a big region and a fringe of patches a few centimetres "off" it.) A step between the
      // parts shows here (the smaller part sits off the union plane) or in the residual below.
      if (std::fabs(grows[ra].m.mean_residual(f.a, f.b, f.c)) > tolerance_w() ||
          std::fabs(grows[rb].m.mean_residual(f.a, f.b, f.c)) > tolerance_w())
        continue;
      // One plane must explain both parts about as well as each part's own plane does.
      // (And no merge into what the planarity check of finalize would then drop whole.)
      if (f.rms_w > 1.25f * std::max(pa.rms_w, pb.rms_w) + 0.25f * cfg_.depth_noise_coeff ||
          f.rms_w > kPlanarRms * tolerance_w())
        continue;
      parent[rb] = ra;
      grows[ra].m = m;
      grows[ra].plane = f;
      grows[ra].dir = dir;
      grows[ra].count += grows[rb].count;
      grows[rb].count = 0;
      ++stats_.regions_merged;
    }
  }
  if (stats_.regions_merged == 0) return;
  for (int r = 0; r < n; ++r) parent[r] = find_root(parent, r);
  // Relabel. The valid pixels of a region cell all carry the cell's label (the passes after the
  // cell pass take only free pixels): a cell of an unmerged region is skipped whole. Elsewhere a
  // table lookup per pixel, without a branch (-1 maps to itself): labels change every few pixels
  // on real frames, and a test per pixel or per run mispredicted there.
  std::vector<int>& root1 = order_;  // root of label l at l + 1
  root1.resize(static_cast<std::size_t>(n) + 1);
  root1[0] = -1;
  for (int r = 0; r < n; ++r) root1[static_cast<std::size_t>(r) + 1] = parent[r];
  const int* root = root1.data() + 1;
  for (int v = 0; v < H_; ++v) {
    int* lab = &label_[static_cast<std::size_t>(v) * W_];
    const int cv = vcell_[v];
    for (int u = 0, cu = 0; u < W_; ++cu) {
      const int cl = cv < CH_ && cu < CW_ ? cell_label_[static_cast<std::size_t>(cv * CW_ + cu)] : -1;
      const int ue = cu < CW_ ? u + cs : W_;
      if (cl >= 0 && parent[cl] == cl) {
        u = ue;
        continue;
      }
      for (; u < ue; ++u) lab[u] = root[lab[u]];
    }
  }
  for (int& cl : cell_label_)
    if (cl >= 0) cl = parent[cl];
}

void Segmentation::drop_curved_tiles(std::vector<Grow>& grows) {
  // Region growing with a noise-sized inlier test tiles a curved surface (a person's back, a bag)
  // into facets a few noise widths deep: each is planar within the noise, so the planarity check
  // passes, and a corridor with five people came out as ~300 "planes". The paper's route does not
  // see them (normals vary smoothly, its growing follows the curve and RANSAC then rejects the
  // whole). The facets are recognised by their seams instead: two regions meeting without a depth
  // jump (both planes pass through the seam) at a small angle are bends of one surface, whereas
  // planes of the built world meet at creases of about 90 degrees (tread/riser, wall/floor) or
  // at occlusion edges (a depth jump).
  if (!(cfg_.curved_tile_max_area > 0.f)) return;
  const int ng = static_cast<int>(grows.size());
  std::vector<int>& cid = cid_;  // grown region -> index among the live ones (-1: empty slot)
  std::vector<int>& live = live_;
  cid.assign(static_cast<std::size_t>(ng), -1);
  live.clear();
  for (int r = 0; r < ng; ++r)
    if (grows[r].count > 0 && grows[r].plane.ok) cid[r] = static_cast<int>(live.size()), live.push_back(r);
  const int n = static_cast<int>(live.size());
  if (n < 2 || n > 4096) return;
  // Candidates: small regions not parallel to a big one (treads, risers, floor and wall pieces
  // are parallel to the floor or a wall; a facet of a curve generally is not). The directions
  // come from the big regions here, not from dirs_: facets of a near person pass the dominant
  // size in pixels.
  std::vector<std::uint8_t>& cand = cell_planar_;  // no longer needed after the cell pass
  cand.assign(static_cast<std::size_t>(n), 0);
  std::vector<float>& area = area_;
  area.assign(static_cast<std::size_t>(n), 0.f);
  const float area_k = 1.f / (K_.fx * K_.fy);
  std::vector<Eigen::Vector3f>& big = big_dirs_;
  big.clear();
  const float par = std::cos(5.f * 3.14159265f / 180.f);
  for (int r = 0; r < n; ++r) {
    const Grow& g = grows[live[r]];
    // Pixel footprint on the plane z^3 / (fx fy d), at the region's mean pixel.
    const float z = g.plane.mean.z();
    area[r] = static_cast<float>(g.count) * z * z * z * area_k / std::max(g.plane.d, 0.01f);
    if (area[r] < cfg_.curved_tile_max_area && g.dir < 0) {
      cand[r] = 1;
      continue;
    }
    bool dup = false;
    for (const Eigen::Vector3f& d : big) dup |= d.dot(g.plane.normal) > par;
    if (!dup && big.size() < 32) big.push_back(g.plane.normal);
  }
  int ncand = 0;
  for (int r = 0; r < n; ++r) {
    if (!cand[r]) continue;
    for (const Eigen::Vector3f& d : big) cand[r] &= d.dot(grows[live[r]].plane.normal) <= par;
    ncand += cand[r];
  }
  if (ncand == 0) return;
  const std::size_t nn = static_cast<std::size_t>(n) * static_cast<std::size_t>(n);
  contact_.assign(nn, 0);
  smooth_.assign(nn, 0);
  const float tw = tolerance_w();
  // The seam samples of merge_regions (pixel pairs of two regions, labels now merged).
  for (std::size_t i = 0; i + 1 < seams_.size(); i += 2) {
    const int p = seams_[i], q = seams_[i + 1];
    const int la = label_[p], lb = label_[q];
    if (la == lb || la < 0 || lb < 0) continue;
    const int a = cid[la], b = cid[lb];
    if (a < 0 || b < 0 || !(cand[a] | cand[b])) continue;
    const std::size_t k = static_cast<std::size_t>(std::min(a, b)) * n + static_cast<std::size_t>(std::max(a, b));
    if (contact_[k] == 0xFFFF) continue;
    ++contact_[k];
    // Both planes pass through the seam: no depth jump between the two regions there.
    const PlaneFit& pa = grows[la].plane;
    const PlaneFit& pb = grows[lb].plane;
    const int vp = row_of(p), up = p - vp * W_, vq = row_of(q), uq = q - vq * W_;
    const float ra = w_[q] - (pa.a * un_[uq] + pa.b * vn_[vq] + pa.c);
    const float rb = w_[p] - (pb.a * un_[up] + pb.b * vn_[vp] + pb.c);
    smooth_[k] += std::fabs(ra) <= tw && std::fabs(rb) <= tw;
  }
  // A candidate bending into another candidate, or into two regions, is a facet: a lone tilted
  // patch against one big plane (a rounded nosing, a sign) is kept. Only neighbours of a facet's
  // size count (curved_facet_size_ratio): with the real-like noise (correlated over 2 and 10 px), a
  // staircase's first riser at the image's top edge, 0.5-1.2 m wide and 3000-6000 px, met a patch
  // of 130 px bent 14 deg at its edge and went to the obstacles as a facet. On real-like seeds 1-12,
  // 11 views with 2000-6300 px of riser or wall in view had no vertical plane; 4 still have none,
  // their patch a sixth to an eighth of their size (at a quarter, the real corridor's people came
  // back as planes: 41.5 -> 38.7 % of its pixels in obstacles; unchanged at an eighth). A bench's
  // flat apron under its rounded seat edge went the same way, and on the real close-up of two
  // nosings (stair-perception-fhg) a tread of 12000 px. Five people in a corridor still come out
  // as obstacles (test_perception).
  const float cos_bend = std::cos(cfg_.curved_bend_max_angle);
  const float cos_parallel = std::cos(2.f * cfg_.region_angle);
  std::vector<int>& bends = sorted_;
  bends.assign(static_cast<std::size_t>(2 * n), 0);  // [2r]: bends to candidates, [2r+1]: all bends
  for (int a = 0; a < n; ++a) {
    for (int b = a + 1; b < n; ++b) {
      const std::size_t k = static_cast<std::size_t>(a) * n + static_cast<std::size_t>(b);
      const int c = contact_[k];
      if (c < 4 || 2 * smooth_[k] < c) continue;
      // Nearly parallel neighbours (within the merge angle) are one plane that failed to merge
      // or parallel planes, not a bend.
      const float cosab = grows[live[a]].plane.normal.dot(grows[live[b]].plane.normal);
      if (cosab < cos_bend || cosab > cos_parallel) continue;
      // Facets of one curve are of a size (a chord a few noise widths deep on the same curvature):
      // a region bends as a facet only into neighbours at least 1 / curved_facet_size_ratio its
      // area. A flat riser with a small patch of noise at its edge is no facet (see above).
      const float ratio = cfg_.curved_facet_size_ratio;
      const bool a_bends = !(ratio > 0.f) || area[b] * ratio >= area[a];
      const bool b_bends = !(ratio > 0.f) || area[a] * ratio >= area[b];
      bends[2 * a] += cand[b] && a_bends;
      bends[2 * a + 1] += a_bends;
      bends[2 * b] += cand[a] && b_bends;
      bends[2 * b + 1] += b_bends;
    }
  }
  for (int r = 0; r < n; ++r) {
    if (!cand[r] || (bends[2 * r] < 1 && bends[2 * r + 1] < 2)) continue;
    grows[live[r]].count = 0;  // finalize clears its labels: the pixels go to the obstacle clusters
    ++stats_.curved_tiles;
  }
}

void Segmentation::refine_borders(std::vector<Grow>& grows) {
  // Pixels near the edge between two planes (a tread and its riser) are within the noise of both;
  // whichever region grew first took them, which biases its plane. Each border pixel goes to the
  // neighbouring region whose plane it fits best (CAPE-style refinement), layer by layer.
  std::vector<int>& cur = seed_pixels_;
  std::vector<int>& nxt = next_;
  cur.clear();
  // Edges between planes run through the cells that were not planar (whole planar cells went to
  // one region), and through the image margin outside the cell grid.
  const int cs = std::max(2, cfg_.cell_size_px);
  const int* L = label_.data();
  int* buf = queue_.data();  // free here (holds W x H entries)
  int nb = 0;
  for (int v = 0, cv = 0, vr = 0; v < H_; ++v) {
    const bool vin = v > 0 && v + 1 < H_;
    // (cv, cu): the pixel's cell, stepped along without divisions (this scans every pixel).
    for (int u = 0, cu = 0; u < W_; cu++) {
      if (cv < CH_ && cu < CW_ && cell_label_[cv * CW_ + cu] >= 0) {
        u += cs;  // a region cell: its inside is one region
        continue;
      }
      const int ue = cu < CW_ ? u + cs : W_;
      for (; u < ue;) {
#if defined(__SSE2__)
        if (vin && u > 0 && u + 4 < W_ && u + 4 <= ue) {
          // Four pixels a step, the same test as the scalar one below in each lane; the border
          // pixels among them are written in raster order.
          const int p = v * W_ + u;
          const __m128i neg = _mm_set1_epi32(-1);
          auto ld = [&](int q) { return _mm_loadu_si128(reinterpret_cast<const __m128i*>(L + q)); };
          const __m128i a = ld(p);
          auto other = [&](__m128i x) { return _mm_andnot_si128(_mm_cmpeq_epi32(x, a), _mm_cmpgt_epi32(x, neg)); };
          const __m128i any = _mm_or_si128(_mm_or_si128(other(ld(p + 1)), other(ld(p - 1))),
                                           _mm_or_si128(other(ld(p + W_)), other(ld(p - W_))));
          const int mask = _mm_movemask_ps(_mm_castsi128_ps(_mm_and_si128(any, _mm_cmpgt_epi32(a, neg))));
          buf[nb] = p;
          nb += mask & 1;
          buf[nb] = p + 1;
          nb += (mask >> 1) & 1;
          buf[nb] = p + 2;
          nb += (mask >> 2) & 1;
          buf[nb] = p + 3;
          nb += (mask >> 3) & 1;
          u += 4;
          continue;
        }
#endif
        const int p = v * W_ + u;
        const int a = L[p];
        bool border;
        if (vin && u > 0 && u + 1 < W_) {
          // Branch-free inside the image (these tests mispredict often on real frames); the
          // pixels are written in raster order either way.
          const int r = L[p + 1], l = L[p - 1], d = L[p + W_], t = L[p - W_];
          border = (a >= 0) & (((r >= 0) & (r != a)) | ((l >= 0) & (l != a)) | ((d >= 0) & (d != a)) |
                               ((t >= 0) & (t != a)));
        } else {
          border = a >= 0 && ((u + 1 < W_ && L[p + 1] >= 0 && L[p + 1] != a) ||
                              (u > 0 && L[p - 1] >= 0 && L[p - 1] != a) ||
                              (v + 1 < H_ && L[p + W_] >= 0 && L[p + W_] != a) ||
                              (v > 0 && L[p - W_] >= 0 && L[p - W_] != a));
        }
        buf[nb] = p;
        nb += border;
        ++u;
      }
    }
    if (++vr == cs) vr = 0, ++cv;
  }
  cur.assign(buf, buf + nb);
  const float kl = 1.41421356f * tolerance_w();
  for (int iter = 0; iter < 8 && !cur.empty(); ++iter) {
    nxt.clear();
    for (int p : cur) {
      const int a = label_[p];
      if (a < 0 || grows[a].count <= 0) continue;  // dropped regions' pixels go to the clusters
      const int v = row_of(p), u = p - v * W_;
      const float wp = w_[p];
      const PlaneFit& pa = grows[a].plane;
      int best = a;
      float best_res = std::fabs(wp - (pa.a * un_[u] + pa.b * vn_[v] + pa.c));
      int nb[4], nu[4], nv[4];
      int k = 0;
      if (u > 0) nb[k] = p - 1, nu[k] = u - 1, nv[k++] = v;
      if (u + 1 < W_) nb[k] = p + 1, nu[k] = u + 1, nv[k++] = v;
      if (v > 0) nb[k] = p - W_, nu[k] = u, nv[k++] = v - 1;
      if (v + 1 < H_) nb[k] = p + W_, nu[k] = u, nv[k++] = v + 1;
      for (int i = 0; i < k; ++i) {
        const int bl = label_[nb[i]];
        if (bl < 0 || bl == a || bl == best || grows[bl].count == 0) continue;
        const PlaneFit& pb = grows[bl].plane;
        const float res = std::fabs(wp - (pb.a * un_[u] + pb.b * vn_[v] + pb.c));
        if (res >= best_res || res > tolerance_w()) continue;
        const float step = (wp - w_[nb[i]]) - (pb.a * (un_[u] - un_[nu[i]]) + pb.b * (vn_[v] - vn_[nv[i]]));
        if (std::fabs(step) > kl) continue;
        best = bl;
        best_res = res;
      }
      if (best == a) continue;
      label_[p] = best;
      grows[a].m.sub(un_[u], vn_[v], wp);
      grows[best].m.add(un_[u], vn_[v], wp);
      --grows[a].count;
      ++grows[best].count;
      ++stats_.border_pixels_moved;
      for (int i = 0; i < k; ++i)
        if (label_[nb[i]] == a) nxt.push_back(nb[i]);
    }
    std::swap(cur, nxt);
  }
}

void Segmentation::finalize(std::vector<Grow>& grows, std::vector<PlaneRegion>& regions) {
  const int n = static_cast<int>(grows.size());
  // Which grown regions survive, and their compact ids. Every pixel was accepted within the noise
  // of its region's plane; the planarity check is that the final plane's residual is noise-like
  // (a "plane" through several surfaces, e.g. the nosings of a far staircase, is not).
  std::vector<int>& map = order_;
  map.assign(static_cast<std::size_t>(n), -1);
  std::size_t out = 0;
  fits_.resize(static_cast<std::size_t>(n));
  for (int r = 0; r < n; ++r) {
    Grow& g = grows[r];
    if (g.count < cfg_.region_min_pixels) continue;
    // A strip grown with its own normal (from a cell or a fine seed, or left free by a merge) may
    // lie on a dominant direction within the noise as well: a few rows fix its tilt no better than
    // they fix a strip seed's (a far tread 3-4 rows tall came out 18 deg off, fitting the
    // disparity steps). It takes the direction on the strip seeds' terms (best_direction, then
    // region_plane's check that its own fit is not clearly better), and only when it is a strip:
    // less than a cell tall (a band of h rows has a row variance h^2 / 12) and at least 8 times
    // as wide as tall in row and column spread. Stubbier fragments leave both tilts open and
    // borrow nothing (on the real kitchen, patches 8 rows by 40 columns would turn by up to
    // 30 deg).
    if (g.dir < 0 && g.m.n > 0) {
      const double in = 1.0 / g.m.n;
      const double su2 = (g.m.suu * in - (g.m.su * in) * (g.m.su * in)) * double(K_.fx) * K_.fx;
      const double sv2 = (g.m.svv * in - (g.m.sv * in) * (g.m.sv * in)) * double(K_.fy) * K_.fy;
      const double cs = cfg_.cell_size_px;
      PlaneFit unused;
      if (12.0 * sv2 < cs * cs && su2 >= 64.0 * sv2) g.dir = best_direction(g.m, unused);
    }
    // Border refinement moved pixels: the direction is checked again on the final moments.
    const PlaneFit f = region_plane(g.m, g.dir);
    if (!f.ok || f.rms_w > kPlanarRms * tolerance_w()) {
      ++stats_.regions_dropped;
      continue;
    }
    stats_.fixed_normal_regions += g.dir >= 0;
    fits_[out] = f;
    map[r] = static_cast<int>(out++);
  }
  // The pixel and point buffers of the last frame's regions are pooled and handed out again,
  // biggest to the biggest region: a region's size changes from frame to frame, and growing
  // buffers of 10^5 entries anew each frame cost more than the raster pass filling them.
  for (PlaneRegion& R : regions) {
    pixel_pool_.push_back(std::move(R.pixels));
    point_pool_.push_back(std::move(R.points));
  }
  regions.resize(out);
  acc_.assign(out, RegionAcc{});
  std::sort(pixel_pool_.begin(), pixel_pool_.end(),
            [](const std::vector<int>& a, const std::vector<int>& b) { return a.capacity() < b.capacity(); });
  std::sort(point_pool_.begin(), point_pool_.end(),
            [](const std::vector<Eigen::Vector3f>& a, const std::vector<Eigen::Vector3f>& b) {
              return a.capacity() < b.capacity();
            });
  std::vector<int>& by_size = live_;  // surviving grown regions, biggest first
  by_size.clear();
  for (int r = 0; r < n; ++r)
    if (map[r] >= 0) by_size.push_back(r);
  std::sort(by_size.begin(), by_size.end(), [&](int a, int b) { return grows[a].count > grows[b].count; });
  for (int r : by_size) {
    PlaneRegion& R = regions[map[r]];
    if (!pixel_pool_.empty()) {
      R.pixels = std::move(pixel_pool_.back());
      pixel_pool_.pop_back();
    }
    if (!point_pool_.empty()) {
      R.points = std::move(point_pool_.back());
      point_pool_.pop_back();
    }
    R.pixels.clear();
    R.points.clear();
    const std::size_t cnt = static_cast<std::size_t>(grows[r].count);
    if (R.pixels.capacity() < cnt) R.pixels.reserve(cnt + cnt / 2);
    // Sized once here (the count is the region's pixel count) and filled through a pointer: a
    // resize per run was a library call per run, and real frames have ten thousand runs.
    R.pixels.resize(cnt);
  }
  std::vector<int>& filled = cid_;  // pixels written per region
  filled.assign(out, 0);
  // One raster pass: pixels, points, centroid, footprint area, moments for the principal axes.
  const int stride = std::max(1, cfg_.points_stride_px);
  // First column at or after u that keeps points (a table: a division per run otherwise).
  first_kept_.resize(static_cast<std::size_t>(W_));
  int* first_kept = first_kept_.data();
  for (int u = 0; u < W_; ++u) first_kept[u] = ((u + stride - 1) / stride) * stride;
  // Labels come in long horizontal runs (a tread spans hundreds of pixels of a row): handle each
  // run at once, so the per-pixel work is a label compare and a sequential store.
  for (int v = 0; v < H_; ++v) {
    const bool vrow = v % stride == 0;
    int* lab = &label_[static_cast<std::size_t>(v) * W_];
    const int row0 = v * W_;
    const float vv = vn_[v];
    const float* zr = &z_[static_cast<std::size_t>(v) * W_];
    int u = 0;
    while (u < W_) {
      const int l = lab[u];
      const int e = run_end(lab, u, W_);
      if (l < 0) {
        u = e;
        continue;
      }
      const int id = map[l];
      std::fill(lab + u, lab + e, id);
      if (id >= 0) {
        PlaneRegion& R = regions[id];
        const std::size_t old = static_cast<std::size_t>(filled[id]);
        const std::size_t len = static_cast<std::size_t>(e - u);
        if (old + len > R.pixels.size()) R.pixels.resize(old + len);  // (only if the count were short)
        int* px = R.pixels.data() + old;
        for (int k = 0, q = row0 + u; k < e - u; ++k) px[k] = q + k;
        filled[id] = static_cast<int>(old + len);
        // Centroid, footprint and axes from the point subsample (every stride-th pixel both
        // ways): smooth sums that need not visit every pixel.
        if (vrow) {
          // The sums in locals over the run (in the region's struct, each point waited on the
          // last one's stores); the same additions in the same order. The centroid is m's
          // first moments (a separate sum of x, y, z added the same values: the same bits).
          RegionAcc& A = acc_[id];
          PointMoments pm = A.m;
          double z3 = A.z3;
          for (int uu = first_kept[u]; uu < e; uu += stride) {
            const float z = zr[uu];
            const float x = un_[uu] * z, y = vv * z;
            R.points.emplace_back(x, y, z);
            z3 += double(z) * z * z;
            pm.add(x, y, z);
          }
          A.m = pm;
          A.z3 = z3;
        }
      }
      u = e;
    }
  }
  const float area_k = 1.f / (K_.fx * K_.fy);
  for (std::size_t id = 0; id < out; ++id) {
    PlaneRegion& R = regions[id];
    R.pixels.resize(static_cast<std::size_t>(filled[id]));
    RegionAcc& A = acc_[id];
    const PlaneFit& f = fits_[id];
    const int cnt = static_cast<int>(R.pixels.size());
    R.id = static_cast<int>(id);
    R.normal = f.normal;
    R.offset = f.d;
    R.pixel_count = cnt;
    if (R.points.empty()) {
      // A region thinner than the subsample grid: fall back on its pixels.
      for (int p : R.pixels) {
        const int v = row_of(p), u = p - v * W_;
        const float z = z_[p];
        R.points.emplace_back(un_[u] * z, vn_[v] * z, z);
        A.z3 += double(z) * z * z;
        A.m.add(un_[u] * z, vn_[v] * z, z);
      }
    }
    const double np = std::max<double>(1.0, static_cast<double>(R.points.size()));
    R.centroid = Eigen::Vector3f(static_cast<float>(A.m.sx / np), static_cast<float>(A.m.sy / np),
                                 static_cast<float>(A.m.sz / np));
    R.cls = RegionClass::kUnclassified;
    R.height = std::numeric_limits<float>::quiet_NaN();
    // Footprint of one pixel on the plane: z^3 / (fx fy |n.p|), and n.p = -d on the plane.
    R.area = static_cast<float>(A.z3 * (static_cast<double>(cnt) / np) * area_k / std::max(std::fabs(f.d), 0.01f));
    const PlaneFit fu = fit_plane_pca(A.m);
    Eigen::Vector3f a1 = fu.ok ? Eigen::Vector3f(fu.eigenvectors.col(2)) : f.normal.unitOrthogonal();
    R.curvature = fu.ok ? fu.eigenvalues[0] / std::max(fu.eigenvalues.sum(), 1e-12f) : 0.f;
    a1 = a1 - a1.dot(f.normal) * f.normal;
    if (a1.norm() < 1e-3f) a1 = f.normal.unitOrthogonal();
    a1.normalize();
    const Eigen::Vector3f a2 = f.normal.cross(a1).normalized();
    float mn1 = 1e9f, mx1 = -1e9f, mn2 = 1e9f, mx2 = -1e9f;
    for (const Eigen::Vector3f& q : R.points) {
      const Eigen::Vector3f dq = q - R.centroid;
      const float s1 = dq.dot(a1), s2 = dq.dot(a2);
      mn1 = std::min(mn1, s1);
      mx1 = std::max(mx1, s1);
      mn2 = std::min(mn2, s2);
      mx2 = std::max(mx2, s2);
    }
    if (R.points.empty()) mn1 = mx1 = mn2 = mx2 = 0.f;
    R.rect_axis_major = a1;
    R.rect_axis_minor = a2;
    R.rect_length_major = mx1 - mn1;
    R.rect_length_minor = mx2 - mn2;
    R.rect_center = R.centroid + a1 * (0.5f * (mn1 + mx1)) + a2 * (0.5f * (mn2 + mx2));
    const float rect_area = R.rect_length_major * R.rect_length_minor;
    R.hull_extent = rect_area > 0.f ? std::min(1.f, R.area / rect_area) : 0.f;
  }
}

void Segmentation::extract_clusters(std::vector<ObstacleCluster>& clusters) {
  const int N = W_ * H_;
  mask_.resize(static_cast<std::size_t>(N));
  {
    // Branch-free (vectorised): on real frames a third of the pixels may be left to clusters.
    const int* L = label_.data();
    const float* Z = z_.data();
    std::uint8_t* M = mask_.data();
    for (int p = 0; p < N; ++p) M[p] = static_cast<std::uint8_t>(((L[p] == -1) & (Z[p] > 0.f)) * 255);
  }
  // Erosion removes the one- or two-pixel seams left between planes (step edges): they are not
  // objects, and without it they would chain whole staircases into one "obstacle".
  cv::Mat m(H_, W_, CV_8UC1, mask_.data());
  cv::erode(m, m, cv::Mat(), cv::Point(-1, -1), 1);
  const int stride = std::max(1, cfg_.points_stride_px);
  // Which columns / rows keep points (a table: the remainders by a run-time stride were two
  // integer divisions per obstacle pixel).
  stride_keep_.resize(static_cast<std::size_t>(W_ + H_));
  std::uint8_t* keep_u = stride_keep_.data();
  std::uint8_t* keep_v = keep_u + W_;
  for (int u = 0; u < W_; ++u) keep_u[u] = u % stride == 0;
  for (int v = 0; v < H_; ++v) keep_v[v] = v % stride == 0;
  // Point buffers of the last frame's clusters are pooled (smallest first) and reused, the
  // smallest that fits each new cluster: no allocation per frame once they have grown.
  for (ObstacleCluster& c : clusters) cluster_pool_.push_back(std::move(c.points));
  std::sort(cluster_pool_.begin(), cluster_pool_.end(),
            [](const std::vector<Eigen::Vector3f>& a, const std::vector<Eigen::Vector3f>& b) {
              return a.capacity() < b.capacity();
            });
  std::size_t out = 0;
  for (int s = 0; s < N; ++s) {
    // Next unvisited obstacle pixel (memchr scans in vector steps).
    const void* hit = std::memchr(mask_.data() + s, 255, static_cast<std::size_t>(N - s));
    if (!hit) break;
    s = static_cast<int>(static_cast<const std::uint8_t*>(hit) - mask_.data());
    const int cid = static_cast<int>(out);
    int head = 0, tail = 0;
    queue_[tail++] = s;
    mask_[s] = 1;
    while (head < tail) {
      const int p = queue_[head++];
      const int v = row_of(p), u = p - v * W_;
      const float zp = z_[p];
      const float jump = cfg_.cluster_tolerance + 2.f * cfg_.depth_noise_coeff * zp * zp;
      // Left, right, up, down (the queue's order is the points' order), unrolled.
      auto visit = [&](int q) {
        if (mask_[q] != 255 || std::fabs(z_[q] - zp) > jump) return;
        mask_[q] = 1;
        queue_[tail++] = q;
      };
      if (u > 0) visit(p - 1);
      if (u + 1 < W_) visit(p + 1);
      if (v > 0) visit(p - W_);
      if (v + 1 < H_) visit(p + W_);
    }
    if (tail < cfg_.cluster_min_pixels) continue;
    if (out >= clusters.size()) clusters.emplace_back();
    ObstacleCluster& c = clusters[out++];
    {
      // Points kept: every stride-th pixel both ways, about tail / stride^2 (a bound suffices).
      const std::size_t need = static_cast<std::size_t>(tail) / static_cast<std::size_t>(stride * stride) + 64;
      auto it = std::lower_bound(cluster_pool_.begin(), cluster_pool_.end(), need,
                                 [](const std::vector<Eigen::Vector3f>& a, std::size_t k) { return a.capacity() < k; });
      if (it == cluster_pool_.end() && !cluster_pool_.empty()) --it;
      if (it != cluster_pool_.end()) {
        c.points = std::move(*it);
        cluster_pool_.erase(it);
      }
      c.points.clear();
    }
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    Eigen::Vector3f mn = Eigen::Vector3f::Constant(1e9f), mx = Eigen::Vector3f::Constant(-1e9f);
    for (int i = 0; i < tail; ++i) {
      const int p = queue_[i];
      label_[p] = -2 - cid;
      const int v = row_of(p), u = p - v * W_;
      const Eigen::Vector3f q(un_[u] * z_[p], vn_[v] * z_[p], z_[p]);
      sum += q.cast<double>();
      mn = mn.cwiseMin(q);
      mx = mx.cwiseMax(q);
      if (keep_u[u] & keep_v[v]) c.points.push_back(q);
    }
    c.centroid = (sum / tail).cast<float>();
    c.min = mn;
    c.max = mx;
  }
  clusters.resize(out);
}

bool Segmentation::run(const RgbdFrame& frame, std::vector<PlaneRegion>& regions,
                       std::vector<ObstacleCluster>& clusters, std::string* why) {
  if (frame.depth.empty() || frame.depth.type() != CV_32FC1 || !frame.intrinsics.valid()) {
    regions.clear();
    clusters.clear();
    if (why) *why = "no depth image (or not CV_32FC1, or invalid intrinsics)";
    W_ = H_ = 0;
    label_.clear();
    return false;
  }
  using Clock = std::chrono::steady_clock;
  auto t = Clock::now();
  auto lap = [&t]() {
    const auto now = Clock::now();
    const double ms = std::chrono::duration<double, std::milli>(now - t).count();
    t = now;
    return ms;
  };
  backproject(frame);
  stats_.backproject_ms = lap();
  if (stats_.valid_pixels == 0) {
    regions.clear();
    clusters.clear();
    if (why) *why = "no valid depth reading in the frame";
    return false;
  }
  grows_.clear();
  cell_pass(grows_);
  find_dominant_directions(grows_);
  stats_.cells_ms = lap();
  if (cfg_.fine_cell_size_px > 1 && cfg_.fine_cell_size_px < cfg_.cell_size_px)
    seed_pass(cfg_.fine_cell_size_px, grows_);
  stats_.seeds_ms = lap();
  strip_pass(grows_);
  line_pass(grows_);
  split_creases(grows_);
  split_border_bands(grows_);
  split_edge_bands(grows_);
  stats_.strips_ms = lap();
  stats_.grow_ms = stats_.cells_ms + stats_.seeds_ms + stats_.strips_ms;
  merge_regions(grows_);
  drop_curved_tiles(grows_);
  stats_.merge_ms = lap();
  refine_borders(grows_);
  stats_.refine_ms = lap();
  finalize(grows_, regions);
  stats_.finalize_ms = lap();
  extract_clusters(clusters);
  stats_.clusters_ms = lap();
  return true;
}

}  // namespace stairguide
