// Segmentation, cells: back-projection, the cell moments and planarity test, region growing over
// the cell grid and the pixel-level refinement of the cells beside regions (step 1-3).
#include "internal.hpp"

namespace stairguide {

using namespace segmentation_detail;

void Segmentation::backproject(const RgbdFrame& frame) {
  K_ = frame.intrinsics;
  W_ = frame.depth.cols;
  H_ = frame.depth.rows;
  div_magic_ =
      ((std::uint64_t(1) << 44) + static_cast<std::uint64_t>(W_) - 1) / static_cast<std::uint64_t>(W_);
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
  cell_grid(cs);
  cell_moments(cs);
  stats_.planar_cells = static_cast<int>(cells_.size());
  sort_cells();
  grow_cells(grows);
  label_cell_pixels(cs);
  // Pixel-level refinement of the other cells next to regions (edges between planes, holes,
  // partial cells): each pixel joins the neighbouring region whose plane fits it best, if any fits.
  const int cell_px = cs * cs;
  cell_pix_.resize(static_cast<std::size_t>(2 * cell_px));
  cell_sel_.resize(static_cast<std::size_t>(cell_px));
  int* row_in_cell = cell_pix_.data() + cell_px;  // k / cs for k < cs * cs
  for (int k = 0; k < cell_px; ++k) row_in_cell[k] = k / cs;
  const int nc = CW_ * CH_;
  for (int c = 0; c < nc; ++c) {
    if (cell_label_[c] >= 0) continue;
    refine_cell(grows, c, cs);
  }
  // Pixels of the image margin not covered by whole cells are left to the fine pass.
}

void Segmentation::cell_grid(int cs) {
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
  cell_need_ = (cs * cs * 4) / 5;
  cell_limit_ = 0.5f * tolerance_w();
  // Offsets of the normalised coordinates inside a cell, and their sums over a full cell.
  std::vector<float>& gu = gu_;
  std::vector<float>& gv = gv_;
  gu.resize(static_cast<std::size_t>(cs));
  gv.resize(static_cast<std::size_t>(cs));
  float* full = cell_full_;  // Su, Sv, Suu, Suv, Svv
  for (int i = 0; i < 5; ++i) full[i] = 0;
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
}

// Float sums centred on the cell (exact enough for a few dozen pixels, and twice as fast),
// shifted to the global double moments afterwards. The reference value w0 is the cell's first
// valid reading (0: the cell has none).
float Segmentation::cell_first_w(int cu, int cv, int cs) const {
  const int u0 = cu * cs, v0 = cv * cs;
  for (int v = v0; v < v0 + cs; ++v)
    for (int u = u0; u < u0 + cs; ++u)
      if (w_[static_cast<std::size_t>(v) * W_ + u] > 0.f) return w_[static_cast<std::size_t>(v) * W_ + u];
  return 0.f;
}

// The rest of a cell once its sums with w are known (n: count of valid pixels).
void Segmentation::cell_finish(int cu, int cv, int cs, float w0, float n, float Sw, float Suw, float Svw,
                               float Sww) {
  if (n < cell_need_) return;
  const std::vector<float>& gu = gu_;
  const std::vector<float>& gv = gv_;
  const float* full = cell_full_;
  const float limit = cell_limit_;
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
        Su += du;
        Sv += dvv;
        Suu += du * du;
        Suv += du * dvv;
        Svv += dvv * dvv;
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
}

void Segmentation::cell_moments(int cs) {
  for (int cv = 0; cv < CH_; ++cv) {
    const int v0 = cv * cs;
    const int cu0 = cell_row_simd(cv, cs);
    const std::vector<float>& gu = gu_;
    const std::vector<float>& gv = gv_;
    for (int cu = cu0; cu < CW_; ++cu) {
      const int u0 = cu * cs;
      const float w0 = cell_first_w(cu, cv, cs);
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
      cell_finish(cu, cv, cs, w0, n, Sw, Suw, Svw, Sww);
    }
  }
}

int Segmentation::cell_row_simd(int cv, int cs) {
  int cu = 0;
#if defined(__SSE2__)
  // Four horizontally adjacent cells at once, one per SIMD lane: each lane adds its cell's
  // pixels in the same order as the scalar loop of cell_moments, so the sums are bit-identical.
  if (cs % 4 == 0) {
    const int v0 = cv * cs;
    const std::vector<float>& gu = gu_;
    const std::vector<float>& gv = gv_;
    const __m128 zero = _mm_setzero_ps(), one = _mm_set1_ps(1.f);
    for (; cu + 4 <= CW_; cu += 4) {
      alignas(16) float w0s[4];
      for (int k = 0; k < 4; ++k) w0s[k] = cell_first_w(cu + k, cv, cs);
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
        if (w0s[k] != 0.f) cell_finish(cu + k, cv, cs, w0s[k], an[k], asw[k], asuw[k], asvw[k], asww[k]);
      }
    }
  }
#else
  (void)cv;
  (void)cs;
#endif
  return cu;
}

void Segmentation::grow_cells(std::vector<Grow>& grows) {
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
}

void Segmentation::label_cell_pixels(int cs) {
  // Pixels of the region cells.
  const int nc = CW_ * CH_;
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
}

void Segmentation::refine_cell(std::vector<Grow>& grows, int c, int cs) {
  const int cv = c / CW_, cu = c - cv * CW_;
  CellCands k;
  int nk = 0;
  for (int dv = -1; dv <= 1; ++dv)
    for (int du = -1; du <= 1; ++du) {
      const int u2 = cu + du, v2 = cv + dv;
      if ((du == 0 && dv == 0) || u2 < 0 || v2 < 0 || u2 >= CW_ || v2 >= CH_) continue;
      const int r = cell_label_[v2 * CW_ + u2];
      if (r < 0) continue;
      bool dup = false;
      for (int i = 0; i < nk; ++i) dup |= k.cand[i] == r;
      if (!dup) k.cand[nk++] = r;
    }
  if (nk == 0) return;
  k.nk = nk;
  // The candidates' plane coefficients in registers.
  for (int i = 0; i < nk; ++i) {
    const PlaneFit& f = grows[k.cand[i]].plane;
    k.pa[i] = f.a, k.pb[i] = f.b, k.pc[i] = f.c;
    k.lab_of[i] = k.cand[i];
  }
  k.lab_of[nk] = -1;
  // Two steps, both without data-dependent branches (which pixels fit which plane is noise on
  // real frames: a branch per pixel mispredicted about every other pixel, and the per-pixel
  // update of a region's moments in memory chained each pixel to the last). First each pixel's
  // best candidate (slot nk: none, also for pixels without a reading: bres < 0 admits none);
  // then each candidate's moments, held in registers, take its pixels in raster order: every
  // region's sums see the same additions in the same order as one pass adding pixel by pixel,
  // so they are bit-identical to it.
  const int u0 = cu * cs, v0 = cv * cs;
  for (int v = v0; v < v0 + cs; ++v) select_cell_row(k, v, u0, v0, cs);
  add_cell_pixels(grows, k, u0, v0, cs);
}

void Segmentation::select_cell_row(const CellCands& k, int v, int u0, int v0, int cs) {
  const int nk = k.nk;
  const float* pa = k.pa;
  const float* pb = k.pb;
  const float* pc = k.pc;
  const int* lab_of = k.lab_of;
  const float tw = tolerance_w();
  std::uint8_t* sel = cell_sel_.data();
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
    const __m128 vvv = _mm_set1_ps(vv), zero = _mm_setzero_ps(), tw4 = _mm_set1_ps(tw),
                 neg = _mm_set1_ps(-1.f);
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
      for (int j = 0; j < 4; ++j) {
        lr[u + j] = lab_of[b4[j]];
        sel[(v - v0) * cs + u + j - u0] = static_cast<std::uint8_t>(b4[j]);
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

void Segmentation::add_cell_pixels(std::vector<Grow>& grows, const CellCands& k, int u0, int v0, int cs) {
  const int cell_px = cs * cs;
  int* lists = cell_pix_.data();
  const int* row_in_cell = cell_pix_.data() + cell_px;
  const std::uint8_t* sel = cell_sel_.data();
  for (int i = 0; i < k.nk; ++i) {
    // This candidate's pixels, in raster order (a branch-free compaction).
    int n = 0;
    for (int j = 0; j < cell_px; ++j) {
      lists[n] = j;
      n += sel[j] == i;
    }
    if (n == 0) continue;
    Grow& g = grows[k.cand[i]];
    InvDepthMoments m = g.m;
    for (int j = 0; j < n; ++j) {
      const int dv = row_in_cell[lists[j]], u = u0 + lists[j] - dv * cs, v = v0 + dv;
      m.add(un_[u], vn_[v], w_[static_cast<std::size_t>(v) * W_ + u]);
    }
    g.m = m;
    g.count += n;
  }
}

}  // namespace stairguide
