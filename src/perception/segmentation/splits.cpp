// Segmentation, splits: creases between two dominant directions, bands at the top border and
// below occlusion edges (step 4b).
#include "internal.hpp"

namespace stairguide {

using namespace segmentation_detail;

namespace {
/// Moments of the points in `a` that are not in `b` (b a subset of a).
InvDepthMoments moments_minus(const InvDepthMoments& a, const InvDepthMoments& b) {
  InvDepthMoments m = a;
  m.n -= b.n;
  m.su -= b.su;
  m.sv -= b.sv;
  m.sw -= b.sw;
  m.suu -= b.suu;
  m.suv -= b.suv;
  m.svv -= b.svv;
  m.suw -= b.suw;
  m.svw -= b.svw;
  m.sww -= b.sww;
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

bool Segmentation::move_to_new_region(std::vector<Grow>& grows, int r, const std::vector<int>& pixels,
                                      int dir) {
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
  find_crease_candidates(grows);
  for (const SplitCand& cd : split_cands_) split_crease(grows, cd);
}

void Segmentation::find_crease_candidates(const std::vector<Grow>& grows) {
  const int cs = std::max(2, cfg_.cell_size_px);
  const float cos_own = std::cos(cfg_.region_angle);
  const float cos_pair = std::cos(60.f * 3.14159265f / 180.f);
  const float sin_line = std::sin(10.f * 3.14159265f / 180.f);
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
        const float du = (t.x() * P.z() - P.x() * t.z()) * K_.fx,
                    dv = (t.y() * P.z() - P.y() * t.z()) * K_.fy;
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
    const double hv = 1.5 * std::sqrt(3.0 * std::max(0.0, sv2)),
                 hu = 1.5 * std::sqrt(3.0 * std::max(0.0, su2));
    const double vc = mv * K_.fy + K_.cy, uc = mu * K_.fx + K_.cx;
    c.v0 = std::max(0, static_cast<int>(vc - hv) - cs),
    c.v1 = std::min(H_ - 1, static_cast<int>(vc + hv) + cs);
    c.u0 = std::max(0, static_cast<int>(uc - hu) - cs),
    c.u1 = std::min(W_ - 1, static_cast<int>(uc + hu) + cs);
    cands.push_back(c);
  }
}

void Segmentation::split_crease(std::vector<Grow>& grows, const SplitCand& cd) {
  const float limit = 0.5f * tolerance_w();
  const double sig2 = double(cfg_.depth_noise_coeff) * cfg_.depth_noise_coeff;
  std::vector<int>& pix = split_pixels_;
  std::vector<int>& side_a = split_side_;
  const int r = cd.r;
  pix.clear();
  for (int v = cd.v0; v <= cd.v1; ++v) {
    const int* lab = &label_[static_cast<std::size_t>(v) * W_];
    for (int u = cd.u0; u <= cd.u1; ++u)
      if (lab[u] == r) pix.push_back(v * W_ + u);
  }
  if (static_cast<int>(pix.size()) != grows[r].count) return;  // not all inside the box: leave it
  const int p0 = 0, p1 = static_cast<int>(pix.size());
  const InvDepthMoments m = grows[r].m;
  const PlaneFit joint = fit_plane(m);
  if (!joint.ok) return;
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
        if (ssr < best)
          best = ssr, best_pair = pi, best_k = k, best_o = o, best_eu = eu, best_ev = ev, best_smin = smin;
      }
    }
  }
  if (best_pair < 0 || (ssr_joint - best) < kSplitGain * sig2) return;
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
  if (!move_to_new_region(grows, r, side_a, move_dir)) return;
  const PlaneFit fk = fit_plane_fixed_normal(grows[r].m, dirs_[keep_dir]);
  if (fk.ok) grows[r].plane = fk, grows[r].dir = keep_dir;
  ++stats_.crease_splits;
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
  const float max_cos =
      below_edge ? std::sin(15.f * 3.14159265f / 180.f) : std::cos(60.f * 3.14159265f / 180.f);
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
  if (!edge_band_candidates(grows)) return;
  find_edge_tops(grows);
  const std::vector<int>& tops = order_;
  if (tops.empty()) return;
  const int K = kBorderBandRows;
  const double sig2 = double(cfg_.depth_noise_coeff) * cfg_.depth_noise_coeff;
  std::vector<int>& slot = cid_;
  const std::vector<int>& regs = live_;
  const std::vector<float>& acc = edge_acc_;
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
    for (int k = 0; k < K && v + k < H_ && label_[p + k * W_] == l; ++k)
      b[k].add(un_[u], vn_[v + k], w_[p + k * W_]);
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

bool Segmentation::edge_band_candidates(const std::vector<Grow>& grows) {
  const int n = static_cast<int>(grows.size());
  const float cos_own = std::cos(cfg_.region_angle);
  // A tread and its riser meet at 90 degrees (give or take the build and the fits' noise).
  const float sin_cross = std::sin(15.f * 3.14159265f / 180.f);
  const float limit = 0.5f * tolerance_w();
  // Candidate regions: planar, parallel to a dominant direction (a riser, the front of a nosing)
  // and square to another one (the treads).
  std::vector<int>& slot = cid_;
  slot.assign(static_cast<std::size_t>(n), -1);
  std::vector<int>& regs = live_;
  regs.clear();
  for (int r = 0; r < n; ++r) {
    const Grow& g = grows[r];
    if (g.count < cfg_.region_min_pixels + static_cast<int>(kSplitMinSide) || !g.plane.ok ||
        g.plane.rms_w > limit)
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
  return !regs.empty();
}

void Segmentation::find_edge_tops(const std::vector<Grow>& grows) {
  const int K = kBorderBandRows;
  const int cs = std::max(2, cfg_.cell_size_px);
  const std::vector<int>& slot = cid_;
  const std::vector<int>& regs = live_;
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
  auto is_top = [&](int q, int l) {
    return label_[q] == l && !(z_[q - W_] > 0.f) && !(z_[q - 2 * W_] > 0.f);
  };
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
      if (nv < cs || (nv > holey && (cv == 0 || cell_valid_[static_cast<std::size_t>(c - CW_)] > holey)))
        continue;
      const int u0 = cu * cs;
      // A top two rows or more down the cell has two of the cell's own pixels without a reading
      // above it; one in the first two rows has holes in the bottom rows of the cell above.
      const int v_first =
          cv > 0 && cell_valid_[static_cast<std::size_t>(c - CW_)] == cs * cs ? cv * cs + 2 : cv * cs;
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
          const __m128 above = _mm_or_ps(_mm_cmpgt_ps(_mm_loadu_ps(z0 - W_), zero),
                                         _mm_cmpgt_ps(_mm_loadu_ps(z0 - 2 * W_), zero));
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
}

}  // namespace stairguide
