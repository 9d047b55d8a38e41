// Segmentation, merge: regions on one plane, facets of curved surfaces, border pixels (step 5).
#include "internal.hpp"

namespace stairguide {

using namespace segmentation_detail;

namespace {
int find_root(std::vector<int>& parent, int a) {
  while (parent[a] != a) {
    parent[a] = parent[parent[a]];
    a = parent[a];
  }
  return a;
}
}  // namespace

void Segmentation::merge_regions(std::vector<Grow>& grows) {
  if (!find_seams(grows)) return;
  const int n = static_cast<int>(grows.size());
  std::vector<int> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  merge_pairs(grows, parent);
  if (stats_.regions_merged == 0) return;
  for (int r = 0; r < n; ++r) parent[r] = find_root(parent, r);
  relabel_merged(parent);
}

bool Segmentation::find_seams(const std::vector<Grow>& grows) {
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
  if (m < 2 || m > 4096) return false;
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
  return true;
}

void Segmentation::merge_pairs(std::vector<Grow>& grows, std::vector<int>& parent) {
  const std::vector<int>& live = live_;
  const int m = static_cast<int>(live.size());
  const std::vector<std::uint8_t>& adj = mask_;
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
}

void Segmentation::relabel_merged(const std::vector<int>& parent) {
  const int n = static_cast<int>(parent.size());
  const int cs = std::max(2, cfg_.cell_size_px);
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
  if (curved_candidates(grows) == 0) return;
  const int n = static_cast<int>(live_.size());
  const std::vector<int>& live = live_;
  const std::vector<std::uint8_t>& cand = cell_planar_;
  const std::vector<float>& area = area_;
  seam_contacts(grows);
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

int Segmentation::curved_candidates(const std::vector<Grow>& grows) {
  const int ng = static_cast<int>(grows.size());
  std::vector<int>& cid = cid_;  // grown region -> index among the live ones (-1: empty slot)
  std::vector<int>& live = live_;
  cid.assign(static_cast<std::size_t>(ng), -1);
  live.clear();
  for (int r = 0; r < ng; ++r)
    if (grows[r].count > 0 && grows[r].plane.ok) cid[r] = static_cast<int>(live.size()), live.push_back(r);
  const int n = static_cast<int>(live.size());
  if (n < 2 || n > 4096) return 0;
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
  return ncand;
}

void Segmentation::seam_contacts(const std::vector<Grow>& grows) {
  const std::vector<int>& cid = cid_;
  const int n = static_cast<int>(live_.size());
  const std::vector<std::uint8_t>& cand = cell_planar_;
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
    const std::size_t k =
        static_cast<std::size_t>(std::min(a, b)) * n + static_cast<std::size_t>(std::max(a, b));
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
}

void Segmentation::refine_borders(std::vector<Grow>& grows) {
  // Pixels near the edge between two planes (a tread and its riser) are within the noise of both;
  // whichever region grew first took them, which biases its plane. Each border pixel goes to the
  // neighbouring region whose plane it fits best (CAPE-style refinement), layer by layer.
  find_border_pixels();
  std::vector<int>& cur = seed_pixels_;
  std::vector<int>& nxt = next_;
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

void Segmentation::find_border_pixels() {
  std::vector<int>& cur = seed_pixels_;
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
          auto other = [&](__m128i x) {
            return _mm_andnot_si128(_mm_cmpeq_epi32(x, a), _mm_cmpgt_epi32(x, neg));
          };
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
}

}  // namespace stairguide
