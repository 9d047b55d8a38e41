#pragma once
/// \file segmentation.hpp
/// Planar segmentation of an organized depth image (paper 3.1), using the image structure instead
/// of the paper's voxel grid + k-d tree route (which `stairguide bench perception` runs as the
/// reference). Planes are fitted in inverse depth (1/z linear in the image coordinates; Kinect
/// noise is constant there), so every test is a fixed number of noise sigmas at any range:
///  1. cells of `cell_size_px` pixels: a least-squares plane per cell from summed moments; a cell
///     is planar when its residual is within the noise;
///  2. region growing over the cell grid (CAPE-like), nearest planar cells first: a neighbour
///     joins when the region's plane explains its pixels (mean squared residual from moments);
///  3. pixels of the non-planar cells beside regions (edges, holes) join the neighbouring region
///     whose plane fits them best;
///  4. what is left is seeded again from `fine_cell_size_px` cells and grown pixel by pixel with a
///     plane test and a local-continuity test (thin, far treads; stops at occlusion edges); then
///     from 2-row windows of `strip_length_px` columns (treads seen as strips 2-3 rows tall).
///     A strip of a few rows fixes a plane's offset well but its tilt poorly (degrees at 3 m), so
///     these seeds first try the dominant directions (normals of the regions covering at least
///     `dominant_min_fraction` of the image: floor, walls, near treads and risers): a seed that
///     lies on a plane parallel to one, within the noise, grows with that normal fixed and only
///     its offset fitted; it keeps the fixed normal only while its pixels do not reject it (its
///     free fit is not clearly better); last, windows of runs of free pixels in one row with a
///     hole or a depth jump above and below (treads of a descent at 3-5 m seen as lines one row
///     tall per column, whose rows touch only at their ends or not at all) seed on a dominant
///     direction only and grow to the rows above and below across gaps of a few columns; a line
///     that continues without a depth jump into the rows above or below (the front face of a
///     shelf board under its top) is released;
///  4b. a strip one cell row tall whose plane is a blend of two dominant directions (a cell
///     across a tread/riser crease at range, planar within the noise) is split along the crease
///     line of the two; a band of up to a few rows at the top border of the view that lies on
///     another dominant direction than the rest of its region (a tread sliver taken by its riser)
///     is split off, and so is a band of up to a few rows below an occlusion edge (a tread's
///     visible part under the shadow of the next nosing, taken by its riser): found from the cells
///     short of readings, on regions parallel to one dominant direction and square to another,
///     only where the band lies behind the region's plane by many sigma^2 (a convex edge; a floor
///     meeting a wall is concave) and on a dominant direction within the noise. All three only
///     where the split lowers the summed squared residual by many sigma^2;
///  5. adjacent regions on one plane are merged (each part's mean residual under the union's
///     plane within the noise: a small part's own tilt is too rough to extrapolate over a big
///     neighbour); small regions that bend smoothly (no depth jump, normals between the merge
///     angle and `curved_bend_max_angle` apart) into other such regions are facets of a curved
///     surface (people, bags, cushions: region growing with a noise-sized inlier test tiles
///     them) and go to the obstacles, unless parallel to a big region; border pixels go to the
///     plane that fits them best; regions whose residual is not noise-like are dropped; area
///     (pixel footprints on the plane), principal rectangle, extent and curvature are computed; a
///     strip grown with its own normal (less than a cell tall, at least 8 times as wide as tall)
///     takes a dominant direction on the strip seeds' terms (its tilt is as rough as theirs: a far
///     tread 3-4 rows tall came out 18 deg off);
///  6. the remaining pixels (eroded) form obstacle clusters (image connectivity + depth jumps).
/// No threads; buffers are kept between frames of one size.

#include <cstdint>
#include <vector>

#include "stairguide/core/config.hpp"
#include "stairguide/core/types.hpp"
#include "stairguide/perception/scene.hpp"

namespace stairguide {

/// Running first and second moments of 3D points (double: sums over 10^5 points).
struct PointMoments {
  double w = 0, sx = 0, sy = 0, sz = 0, sxx = 0, sxy = 0, sxz = 0, syy = 0, syz = 0, szz = 0;
  void add(float x, float y, float z, double weight = 1.0) {
    w += weight;
    sx += weight * x;
    sy += weight * y;
    sz += weight * z;
    sxx += weight * x * x;
    sxy += weight * x * y;
    sxz += weight * x * z;
    syy += weight * y * y;
    syz += weight * y * z;
    szz += weight * z * z;
  }
};

/// Moments for a plane fit in inverse depth. A plane n.p + d = 0 seen through a pinhole is linear
/// in normalised image coordinates: 1/z = a u' + b v' + c with u' = (u-cx)/fx, v' = (v-cy)/fy,
/// (a, b, c) = -n / d. Kinect noise is sigma_z = k z^2, i.e. a constant k in 1/z, and it lies
/// along the ray: ordinary least squares on 1/z is therefore unbiased, where a PCA of the 3D
/// points tilts thin, far planes towards the viewing rays (degrees at 3 m).
struct InvDepthMoments {
  double n = 0, su = 0, sv = 0, sw = 0, suu = 0, suv = 0, svv = 0, suw = 0, svw = 0, sww = 0;
  void add(float u, float v, float w) {
    n += 1.0;
    su += u;
    sv += v;
    sw += w;
    suu += double(u) * u;
    suv += double(u) * v;
    svv += double(v) * v;
    suw += double(u) * w;
    svw += double(v) * w;
    sww += double(w) * w;
  }
  void sub(float u, float v, float w) {
    n -= 1.0;
    su -= u;
    sv -= v;
    sw -= w;
    suu -= double(u) * u;
    suv -= double(u) * v;
    svv -= double(v) * v;
    suw -= double(u) * w;
    svw -= double(v) * w;
    sww -= double(w) * w;
  }
  void add(const InvDepthMoments& o) {
    n += o.n;
    su += o.su;
    sv += o.sv;
    sw += o.sw;
    suu += o.suu;
    suv += o.suv;
    svv += o.svv;
    suw += o.suw;
    svw += o.svw;
    sww += o.sww;
  }
  /// Mean residual in 1/z of these points under the plane 1/z = a u' + b v' + c.
  double mean_residual(double a, double b, double c) const {
    return n > 0 ? (sw - a * su - b * sv) / n - c : 0.0;
  }
};

/// A plane: unit normal facing the camera (origin), n.p + d = 0 (d > 0: distance of the camera).
struct PlaneFit {
  bool ok = false;
  Eigen::Vector3f normal = Eigen::Vector3f::Zero();
  float d = 0.f;
  Eigen::Vector3f mean =
      Eigen::Vector3f::Zero();      ///< centroid (PCA fits; inverse-depth fits: the point at the mean pixel)
  float a = 0.f, b = 0.f, c = 0.f;  ///< inverse-depth form 1/z = a u' + b v' + c (inverse-depth fits)
  float rms_w = 0.f;                ///< residual RMS in 1/z (1/m) (inverse-depth fits)
  Eigen::Vector3f eigenvalues = Eigen::Vector3f::Zero();       ///< ascending variances (PCA fits)
  Eigen::Matrix3f eigenvectors = Eigen::Matrix3f::Identity();  ///< columns (PCA fits)
};
/// Least-squares plane in inverse depth (see InvDepthMoments).
PlaneFit fit_plane(const InvDepthMoments& m);
/// Least-squares plane in inverse depth with its unit normal fixed to `n` (facing the camera):
/// only the offset is fitted. Fails when the points lie behind the camera for that normal.
PlaneFit fit_plane_fixed_normal(const InvDepthMoments& m, const Eigen::Vector3f& n);
/// PCA plane of 3D points (principal axes, curvature).
PlaneFit fit_plane_pca(const PointMoments& m);

/// Counters of one segmentation run.
struct SegmentationStats {
  int valid_pixels = 0;
  int planar_cells = 0;
  int seeds_used = 0;
  int regions_merged = 0;
  int border_pixels_moved = 0;  ///< pixels handed to the neighbouring region whose plane fits better
  /// Milliseconds per step (for `stairguide bench perception`).
  double backproject_ms = 0, grow_ms = 0, merge_ms = 0, refine_ms = 0, finalize_ms = 0, clusters_ms = 0;
  double cells_ms = 0, seeds_ms = 0, strips_ms = 0;  ///< parts of grow_ms: cell pass, fine seeds, strip seeds
  int regions_dropped = 0;       ///< grown regions below region_min_pixels or failing the planarity check
  int dominant_directions = 0;   ///< normals the thin-strip seeds may take
  int fixed_normal_regions = 0;  ///< regions grown with a dominant direction's normal
  int curved_tiles = 0;          ///< small regions dropped as facets of a curved surface
  int crease_splits = 0;         ///< regions split along a crease between two dominant directions
  int border_splits = 0;         ///< bands at the top border split off their region
  int edge_splits = 0;           ///< bands below an occlusion edge split off their region
  int line_regions = 0;          ///< regions grown from one-row line seeds (line_pass)
};

/// The segmentation stage. Keeps its buffers between calls (same image size: no reallocation).
class Segmentation {
 public:
  explicit Segmentation(const SegmentationConfig& config = {});

  /// Segments `frame.depth` (CV_32FC1 metres, 0 = no reading) with `frame.intrinsics`.
  /// Fills `regions` (ids 0..n-1) and `clusters`, reusing their storage. Returns false (with
  /// `why`) when the frame has no usable depth.
  bool run(const RgbdFrame& frame, std::vector<PlaneRegion>& regions, std::vector<ObstacleCluster>& clusters,
           std::string* why = nullptr);

  /// Per pixel (v*width+u): index of the region, -2 - k for obstacle cluster k, -1 for none.
  const std::vector<int>& labels() const { return label_; }
  const SegmentationStats& stats() const { return stats_; }
  const SegmentationConfig& config() const { return cfg_; }

 private:
  struct Grow {
    InvDepthMoments m;
    PlaneFit plane;
    double fit_w = 0;
    int count = 0;
    int dir = -1;  ///< index into dirs_ when the normal is fixed to a dominant direction
  };
  void backproject(const RgbdFrame& frame);
  void cell_pass(std::vector<Grow>& grows);
  /// Cell pass, its phases: the cell grid (cell of each column and row, the coordinate sums of a
  /// full cell); each cell's moments and planarity test (planar cells into cells_); region growing
  /// over the cell grid; the pixels of the region cells; and the pixels of each other cell beside
  /// regions, handed to the neighbouring region whose plane fits them best.
  void cell_grid(int cs);
  void cell_moments(int cs);
  /// cell_moments four cells of row `cv` at a time (SSE2); returns the first cell column left to do.
  int cell_row_simd(int cv, int cs);
  float cell_first_w(int cu, int cv, int cs) const;
  void cell_finish(int cu, int cv, int cs, float w0, float n, float Sw, float Suw, float Svw, float Sww);
  void grow_cells(std::vector<Grow>& grows);
  void label_cell_pixels(int cs);
  /// The regions around one cell that its pixels may join, with their planes' coefficients.
  struct CellCands {
    int cand[8];
    float pa[8], pb[8], pc[8];
    int lab_of[9];
    int nk = 0;
  };
  void refine_cell(std::vector<Grow>& grows, int c, int cs);
  /// Each pixel of row `v` of the cell at (u0, v0): its best candidate (cell_sel_) and label.
  void select_cell_row(const CellCands& k, int v, int u0, int v0, int cs);
  /// Each candidate's moments take its pixels of the cell, in raster order.
  void add_cell_pixels(std::vector<Grow>& grows, const CellCands& k, int u0, int v0, int cs);
  void seed_pass(int cell, std::vector<Grow>& grows);
  /// Grows a region from `seed_pixels` (g.plane, g.dir set). Returns true when the region was
  /// grown with a fixed normal its pixels reject (it is then released, g.count == 0).
  bool grow_region(int region, const std::vector<int>& seed_pixels, Grow& g);
  /// The growth of grow_region and grow_line: labels the seed pixels, then takes neighbours
  /// breadth-first (left, right, above, below; with kReach > 0 the rows above and below up to
  /// kReach columns either way) that lie on the plane within the noise and continue their
  /// neighbour's depth, refitting as the region doubles (g.dir >= 0: normal fixed), and refits
  /// g's plane at the end. Returns how many pixels it labelled (queue_[0, n)).
  template <int kReach>
  int grow_pixels(int region, const std::vector<int>& seed_pixels, Grow& g);
  /// Gives a dropped growth's `tail` pixels back (released_), empties g; returns whether it was
  /// grown on a dominant direction (`dir`) its pixels reject.
  bool release_growth(int tail, Grow& g, int dir);
  void find_dominant_directions(const std::vector<Grow>& grows);
  /// Best fixed-normal fit of `m` over the dominant directions within the planar-cell limit (-1: none).
  int best_direction(const InvDepthMoments& m, PlaneFit& fit) const;
  /// Plane of a region's moments: fixed to its dominant direction while the pixels accept it.
  PlaneFit region_plane(const InvDepthMoments& m, int& dir) const;
  void strip_pass(std::vector<Grow>& grows);
  /// Seeds from runs of free pixels in one row on a dominant direction, grown across small gaps
  /// between rows (far treads of a descent seen as lines one pixel row tall).
  void line_pass(std::vector<Grow>& grows);
  /// line_pass' seeds (line_seeds_): windows of runs of free pixels in one row, mostly with a hole
  /// or a depth jump above and below, that lie on a dominant direction; nearest and best first.
  void find_line_seeds();
  /// grow_region for line_pass: the neighbours of a pixel are its left and right ones and those
  /// up to kLineReach columns away in the rows above and below (g.dir fixed). The same return;
  /// also released when it continues without a depth jump into the rows above or below it.
  bool grow_line(int region, const std::vector<int>& seed_pixels, Grow& g);
  /// Splits regions that straddle a crease between two dominant directions (a tread and its
  /// riser within one cell row, at range) along the crease line.
  void split_creases(std::vector<Grow>& grows);
  /// split_creases' candidates (split_cands_): strips one cell row tall whose plane is a blend of
  /// two dominant directions, with the (at most two) direction pairs and an image box holding them.
  void find_crease_candidates(const std::vector<Grow>& grows);
  /// Splits candidate `cd` along the crease line where that lowers the residual enough.
  struct SplitCand;
  void split_crease(std::vector<Grow>& grows, const SplitCand& cd);
  /// Splits off a band of rows at the top border of the view that lies on another dominant
  /// direction than the rest of its region (a tread sliver above its riser).
  void split_border_bands(std::vector<Grow>& grows);
  /// The same below an occlusion edge (no readings above): a tread's visible sliver between its
  /// riser and the shadow of the next nosing, taken by the riser's region.
  void split_edge_bands(std::vector<Grow>& grows);
  /// split_edge_bands' candidate regions (live_, their slots in cid_): planar, parallel to one
  /// dominant direction and square to another. False: none.
  bool edge_band_candidates(const std::vector<Grow>& grows);
  /// split_edge_bands' tops of columns under a hole (order_) and the residual sums per candidate
  /// and row below them (edge_acc_).
  void find_edge_tops(const std::vector<Grow>& grows);
  /// The band of a region's first rows (from the top border or below an occlusion edge) to split
  /// off onto a dominant direction: rows 0 and dir -1 when none explains the region better.
  /// `bins` holds the moments of the region's pixels per row (or per sweep step) from the border,
  /// `nb` of them; `only_dir` >= 0 tries that direction alone. `gain` is the drop in the summed
  /// squared residual (1/m^2) the split brings.
  struct BandSplit {
    int rows = 0, dir = -1;
    double gain = 0.0;
  };
  BandSplit best_band_split(const Grow& g, const InvDepthMoments* bins, int nb, bool below_edge,
                            int only_dir = -1) const;
  /// For a region touching the top border that no band of rows splits: the band bounded by a line
  /// parallel to the crease between its plane and another dominant direction (a tread sliver
  /// leaving the view at a slant). Moves the band to a new region; returns whether it did.
  bool split_slanted_border_band(std::vector<Grow>& grows, int r);
  /// Refits a region's plane after pixels left it (fixed to its dominant direction while they accept it).
  void refit_region(Grow& g) const;
  /// Moves the pixels of region `r` listed in `pixels` to a new region on direction `dir`.
  /// Returns false (nothing changed) when the new region's fit fails.
  bool move_to_new_region(std::vector<Grow>& grows, int r, const std::vector<int>& pixels, int dir);
  void merge_regions(std::vector<Grow>& grows);
  /// merge_regions' phases: the live regions (live_, cid_), which of them touch (mask_) and the
  /// seam samples (seams_), false when there is nothing to merge; the merges of touching pairs
  /// (union-find in `parent`); the labels relabelled to their roots.
  bool find_seams(const std::vector<Grow>& grows);
  void merge_pairs(std::vector<Grow>& grows, std::vector<int>& parent);
  void relabel_merged(const std::vector<int>& parent);
  void drop_curved_tiles(std::vector<Grow>& grows);
  /// drop_curved_tiles' phases: the live regions, their areas and which are candidate facets
  /// (returns how many); the seam contacts of each pair, and how many of them are smooth.
  int curved_candidates(const std::vector<Grow>& grows);
  void seam_contacts(const std::vector<Grow>& grows);
  void refine_borders(std::vector<Grow>& grows);
  /// refine_borders' first layer: the pixels with a neighbour of another region (seed_pixels_).
  void find_border_pixels();
  void finalize(std::vector<Grow>& grows, std::vector<PlaneRegion>& regions);
  /// finalize's phases: which grown regions survive (their compact ids in order_, planes in
  /// fits_; returns how many); the pooled pixel and point buffers handed out, biggest to the
  /// biggest; one raster pass over the labels (pixels, points, sums); each region's description.
  std::size_t keep_regions(std::vector<Grow>& grows);
  void hand_out_buffers(const std::vector<Grow>& grows, std::vector<PlaneRegion>& regions, std::size_t out);
  void raster_regions(std::vector<PlaneRegion>& regions, std::size_t out);
  /// Centroid, area, principal rectangle, extent and curvature of region `id`.
  void describe_region(PlaneRegion& R, std::size_t id, float area_k);
  void extract_clusters(std::vector<ObstacleCluster>& clusters);
  /// Inlier tolerance on the perpendicular distance (m) at depth z from a plane at distance d.
  /// v = p / width without a hardware division (exact for images up to 4096 wide).
  int row_of(int p) const { return static_cast<int>((static_cast<std::uint64_t>(p) * div_magic_) >> 44); }
  float tolerance(float z, float d) const {
    return cfg_.inlier_sigmas * cfg_.depth_noise_coeff * z * (d < 0 ? -d : d) + cfg_.inlier_min_distance;
  }
  /// The same tolerance on the inverse-depth residual (1/m).
  /// Constant: Kinect noise (and disparity quantisation) is constant in 1/z. (A metric floor
  /// here would turn into a huge slack for planes seen edge-on, d -> 0.)
  float tolerance_w() const { return cfg_.inlier_sigmas * cfg_.depth_noise_coeff; }

  SegmentationConfig cfg_;
  CameraIntrinsics K_;
  int W_ = 0, H_ = 0;
  std::uint64_t div_magic_ = 0;
  std::vector<float> z_;            // depth, 0 where no reading (x = u' z, y = v' z)
  std::vector<float> w_;            // 1/z, 0 where no reading
  std::vector<float> un_, vn_;      // normalised image coordinates per column / row
  std::vector<float> gu_, gv_;      // offsets of the normalised coordinates inside a cell
  std::vector<int> ucell_, vcell_;  // cell column / row of each image column / row
  std::vector<int> label_;
  std::vector<int> queue_;
  std::vector<int> seed_pixels_, next_;
  struct Cell {
    int u0, v0;
    float score;
  };
  std::vector<Cell> cells_, cells_tmp_;
  struct LineSeed {
    int u0, v, n;
    float score;
  };
  std::vector<LineSeed> line_seeds_;      // line_pass: runs of free pixels in one row
  std::vector<std::uint64_t> sort_keys_;  // sort_cells: (score bits, index) keys
  /// Sorts cells_ by ascending score, in the very order std::sort on the cells gives (ties too).
  void sort_cells();
  std::vector<Grow> grows_;
  struct RegionAcc {
    double z3 = 0;
    PointMoments m;  // its first moments give the centroid
  };
  std::vector<RegionAcc> acc_;
  std::vector<PlaneFit> fits_;
  std::vector<std::vector<int>> pixel_pool_;  // finalize: buffers of regions not in use
  std::vector<std::vector<Eigen::Vector3f>> point_pool_;
  std::vector<std::vector<Eigen::Vector3f>> cluster_pool_;  // extract_clusters: point buffers not in use
  int CW_ = 0, CH_ = 0;                                     // cell grid
  std::vector<InvDepthMoments> cell_m_;
  std::vector<int> cell_label_;
  std::vector<std::uint8_t> cell_planar_;
  std::vector<std::uint16_t> cell_valid_;  // cell pass: pixels with a reading per cell
  int cell_need_ = 0;                      // cell pass: pixels with a reading a planar cell needs
  float cell_limit_ = 0.f;                 // cell pass: residual limit of a planar cell (1/m)
  float cell_full_[5] = {0, 0, 0, 0, 0};   // cell pass: Su, Sv, Suu, Suv, Svv over a full cell
  std::vector<int> first_kept_;            // finalize: first point column at or after each column
  std::vector<std::uint8_t> stride_keep_;  // extract_clusters: columns, then rows, that keep points
  std::vector<int> cell_pix_;              // cell pass: one candidate's pixels in a cell, then k / cs
  std::vector<std::uint8_t> cell_sel_;     // cell pass: best candidate of each pixel of a cell
  std::vector<int> order_, offsets_, sorted_, cid_, live_;
  std::vector<int> seams_;  // pixel pairs (p, q) on the borders between regions, from merge_regions
  std::vector<std::uint8_t> mask_;
  std::vector<std::uint8_t> tried_;  // fine seed pass: pixel was in a grown region that was too small
  int released_ = 0;                 // pixels (queue_[0..n)) released by the last dropped grow_region
  std::vector<std::uint16_t> contact_, smooth_;
  std::vector<float> area_;
  std::vector<float> edge_acc_;  // split_edge_bands: residual sums per candidate region and band row
  std::vector<Eigen::Vector3f> big_dirs_;    // region pairs: seam samples, depth-continuous ones
  std::vector<InvDepthMoments> bins_;        // split passes: moments per sweep bin / row
  std::vector<InvDepthMoments> slant_bins_;  // split_slanted_border_band: moments per sweep step
  std::vector<int> split_pixels_, split_side_;
  struct SplitCand {
    int r, np, pairs[4][2];
    int u0, u1, v0, v1;
  };
  std::vector<SplitCand> split_cands_;
  std::vector<Eigen::Vector3f> dirs_;  // dominant directions (unit normals facing the camera)
  SegmentationStats stats_;
};

}  // namespace stairguide
