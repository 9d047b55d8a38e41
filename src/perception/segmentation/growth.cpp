// Segmentation, growth: pixel-level region growing from fine cells, strips and one-row lines (step 4).
#include "internal.hpp"

namespace stairguide {

using namespace segmentation_detail;

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
    if (static_cast<int>(seed_pixels_.size()) < need || 2 * tried > static_cast<int>(seed_pixels_.size()))
      continue;
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
      if (cu0 == cu1 && cu0 < CW_ && cv1 < CH_ &&
          cell_label_[static_cast<std::size_t>(cv0 * CW_ + cu0)] >= 0 &&
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
  if (g.count < cfg_.region_min_pixels || g.dir < 0 || 4 * smooth > sides)
    return release_growth(tail, g, dir);
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
  find_line_seeds();
  const std::vector<LineSeed>& seeds = line_seeds_;
  const int need = std::max(3, (3 * len) / 4);
  auto free_px = [&](int p) { return label_[p] == -1 && z_[p] > 0.f && tried_[p] == 0; };
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

void Segmentation::find_line_seeds() {
  const int len = cfg_.strip_length_px;
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
        const __m128 up =
            _mm_and_ps(_mm_cmpgt_ps(wu, zero), _mm_cmple_ps(_mm_and_ps(_mm_sub_ps(wu, w), absmask), kl4));
        const __m128 down =
            _mm_and_ps(_mm_cmpgt_ps(wd, zero), _mm_cmple_ps(_mm_and_ps(_mm_sub_ps(wd, w), absmask), kl4));
        const __m128 fr =
            _mm_and_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(lab, _mm_set1_epi32(-1))), _mm_cmpgt_ps(w, zero));
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
}

}  // namespace stairguide
