// Segmentation, plane fits: least squares in inverse depth (free or with a fixed normal), PCA,
// and the dominant directions the thin-strip seeds may take.
#include "internal.hpp"

namespace stairguide {

using namespace segmentation_detail;

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

PlaneFit fit_plane(const InvDepthMoments& m) {
  PlaneFit f;
  CentredPlane p;
  if (!solve_centred_plane(m, p)) return f;
  f.ok = true;
  f.d = static_cast<float>(1.0 / p.g);
  f.normal = Eigen::Vector3f(static_cast<float>(-p.a / p.g), static_cast<float>(-p.b / p.g),
                             static_cast<float>(-p.c / p.g));
  f.a = static_cast<float>(p.a);
  f.b = static_cast<float>(p.b);
  f.c = static_cast<float>(p.c);
  f.rms_w = static_cast<float>(p.rms_w);
  // The plane's point on the ray of the mean pixel stands in for the centroid.
  if (p.wm > 1e-9)
    f.mean = Eigen::Vector3f(static_cast<float>(p.mu / p.wm), static_cast<float>(p.mv / p.wm),
                             static_cast<float>(1.0 / p.wm));
  return f;
}

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
  if (wm > 1e-9)
    f.mean = Eigen::Vector3f(static_cast<float>(mu / wm), static_cast<float>(mv / wm),
                             static_cast<float>(1.0 / wm));
  return f;
}

void Segmentation::find_dominant_directions(const std::vector<Grow>& grows) {
  // Normals of the big regions of the cell pass, biggest first; one per direction (a tread and
  // the floor give one). Their fits span hundreds of rows, so their tilt is the precise one.
  dirs_.clear();
  const double min_px =
      std::max<double>(cfg_.region_min_pixels, cfg_.dominant_min_fraction * stats_.valid_pixels);
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

}  // namespace stairguide
