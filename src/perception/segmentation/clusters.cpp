// Segmentation, clusters: the remaining pixels as obstacle clusters (step 6).
#include "internal.hpp"

#include <opencv2/imgproc.hpp>

namespace stairguide {

using namespace segmentation_detail;

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
      const std::size_t need =
          static_cast<std::size_t>(tail) / static_cast<std::size_t>(stride * stride) + 64;
      auto it = std::lower_bound(
          cluster_pool_.begin(), cluster_pool_.end(), need,
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

}  // namespace stairguide
