// Segmentation, finalize: the regions' planes, planarity check, area, rectangle, extent (step 5).
#include "internal.hpp"

namespace stairguide {

using namespace segmentation_detail;

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
}  // namespace

void Segmentation::finalize(std::vector<Grow>& grows, std::vector<PlaneRegion>& regions) {
  const std::size_t out = keep_regions(grows);
  hand_out_buffers(grows, regions, out);
  raster_regions(regions, out);
  const float area_k = 1.f / (K_.fx * K_.fy);
  for (std::size_t id = 0; id < out; ++id) describe_region(regions[id], id, area_k);
}

std::size_t Segmentation::keep_regions(std::vector<Grow>& grows) {
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
  return out;
}

void Segmentation::hand_out_buffers(const std::vector<Grow>& grows, std::vector<PlaneRegion>& regions,
                                    std::size_t out) {
  const int n = static_cast<int>(grows.size());
  const std::vector<int>& map = order_;
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
}

void Segmentation::raster_regions(std::vector<PlaneRegion>& regions, std::size_t out) {
  const std::vector<int>& map = order_;
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
}

void Segmentation::describe_region(PlaneRegion& R, std::size_t id, float area_k) {
  const std::vector<int>& filled = cid_;
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
  R.area =
      static_cast<float>(A.z3 * (static_cast<double>(cnt) / np) * area_k / std::max(std::fabs(f.d), 0.01f));
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

}  // namespace stairguide
