// The floorless route, phase "up" (floorless.hpp, step 1): the vertical from the largest family of
// parallel planes plausible as horizontal for a body-worn camera.
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "floorless_internal.hpp"
#include "stairguide/stairs/floorless.hpp"

namespace stairguide {

using namespace floorless;

bool FloorlessStairs::find_up(const SceneResult& scene) {
  cand_.clear();
  for (std::size_t i = 0; i < scene.regions.size(); ++i) {
    const PlaneRegion& r = scene.regions[i];
    if (r.points.size() < 10 || r.pixel_count < kMinRegionPixels) continue;
    float tilt = 0.f, roll = 0.f;
    tilt_roll(r.normal, tilt, roll);
    if (std::fabs(roll) > floor_.roll_max || tilt < det_.floorless_tilt_min || tilt > det_.floorless_tilt_max)
      continue;
    cand_.push_back(static_cast<int>(i));
  }
  if (cand_.empty()) return false;
  // The family with the most pixels: each plausible normal votes with the pixels of the regions
  // parallel to it.
  const float cos_par = std::cos(cls_.parallel_threshold);
  long best_pix = -1;
  int best = -1;
  for (int c : cand_) {
    const Eigen::Vector3f& nc = scene.regions[static_cast<std::size_t>(c)].normal;
    long pix = 0;
    for (int j : cand_)
      if (nc.dot(scene.regions[static_cast<std::size_t>(j)].normal) >= cos_par)
        pix += scene.regions[static_cast<std::size_t>(j)].pixel_count;
    if (pix > best_pix) {
      best_pix = pix;
      best = c;
    }
  }
  const Eigen::Vector3f n0 = scene.regions[static_cast<std::size_t>(best)].normal;
  // The common normal of all the family's planes (paper 5.2): each region centred on its own mean,
  // the direction of least spread of them all. One region's normal is noisy; the family's is not.
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  Eigen::Vector3f mean_normal = Eigen::Vector3f::Zero();
  std::size_t total = 0;
  for (int j : cand_) {
    const PlaneRegion& r = scene.regions[static_cast<std::size_t>(j)];
    if (n0.dot(r.normal) < cos_par) continue;
    mean_normal += r.normal * static_cast<float>(r.pixel_count);
    const std::size_t stride = std::max<std::size_t>(1, r.points.size() / kFitPoints);
    Eigen::Vector3d m = Eigen::Vector3d::Zero();
    std::size_t n = 0;
    for (std::size_t i = 0; i < r.points.size(); i += stride, ++n) m += r.points[i].cast<double>();
    m /= static_cast<double>(n);
    for (std::size_t i = 0; i < r.points.size(); i += stride) {
      const Eigen::Vector3d d = r.points[i].cast<double>() - m;
      scatter += d * d.transpose();
    }
    total += n;
  }
  Eigen::Vector3f up = mean_normal.normalized();
  if (total >= 50) {
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(scatter);
    Eigen::Vector3f fit = es.eigenvectors().col(0).cast<float>().normalized();
    if (fit.dot(up) < 0.f) fit = -fit;
    // A fit far from the normals means the family is not one set of parallel planes.
    if (fit.dot(up) >= std::cos(deg2rad(3.f))) up = fit;
  }
  family_.clear();
  for (int j : cand_)
    if (up.dot(scene.regions[static_cast<std::size_t>(j)].normal) >= cos_par) family_.push_back(j);
  trace_.up = up;
  tilt_roll(up, trace_.tilt, trace_.roll);
  trace_.family_regions = static_cast<int>(family_.size());
  if (std::fabs(trace_.roll) > floor_.roll_max || trace_.tilt < det_.floorless_tilt_min ||
      trace_.tilt > det_.floorless_tilt_max || family_.empty())
    return false;
  trace_.up_found = true;
  return true;
}

}  // namespace stairguide
