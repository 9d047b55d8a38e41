#pragma once
/// \file perception.hpp
/// The perception facade (paper section 3): segmentation, floor, Manhattan frame and
/// classification in order on one RGB-D frame, with the floor and Manhattan tracking kept between
/// frames. Pure: no threads, no I/O, no exceptions on the per-frame path; buffers are kept.

#include "stairguide/core/config.hpp"
#include "stairguide/perception/floor_detection.hpp"
#include "stairguide/perception/manhattan_frame.hpp"
#include "stairguide/perception/region_classification.hpp"
#include "stairguide/perception/scene.hpp"
#include "stairguide/perception/segmentation.hpp"

namespace stairguide {

class Perception {
 public:
  Perception(const SegmentationConfig& seg = {}, const FloorConfig& floor = {}, const ManhattanConfig& manhattan = {},
             const ClassificationConfig& classification = {});
  explicit Perception(const PipelineConfig& config);

  /// Runs every stage on `frame` into `out` (its vectors are reused). A frame without a floor
  /// has out.floor_found == false and out.why saying so; its regions are kUnclassified.
  void process(const RgbdFrame& frame, SceneResult& out);
  SceneResult process(const RgbdFrame& frame) {
    SceneResult r;
    process(frame, r);
    return r;
  }

  /// Forgets the floor and Manhattan tracking (start of a new sequence, or independent views).
  void reset();

  /// Per-pixel labels of the last frame (see Segmentation::labels()).
  const std::vector<int>& labels() const { return segmentation_.labels(); }
  const Segmentation& segmentation() const { return segmentation_; }
  const FloorEstimate& last_floor() const { return floor_est_; }

 private:
  Segmentation segmentation_;
  FloorDetector floor_;
  ManhattanTracker manhattan_;
  ClassificationConfig classification_;
  FloorEstimate floor_est_;
};

/// Colours of the paper's Fig. 3 f (BGR): yellow vertical, blue horizontal step candidate, green
/// floor, red other / obstacle; grey for unclassified planes.
cv::Vec3b region_class_color(RegionClass c);

/// Draws the classification over `base` (BGR, or grey / empty: a depth shading is used) with
/// `alpha` opacity; clusters are drawn red. Returns a new CV_8UC3 image.
cv::Mat draw_classification(const cv::Mat& base, const cv::Mat& depth, const SceneResult& scene,
                            const std::vector<int>& labels, float alpha = 0.55f);

}  // namespace stairguide
