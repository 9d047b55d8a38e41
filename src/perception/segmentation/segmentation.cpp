// Segmentation: the driver over its phases (see segmentation.hpp for the steps).
#include "internal.hpp"

#include <chrono>

namespace stairguide {

using namespace segmentation_detail;

Segmentation::Segmentation(const SegmentationConfig& config) : cfg_(config) {}

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
