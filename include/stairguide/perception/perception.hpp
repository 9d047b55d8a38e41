#pragma once
/// \file perception.hpp
/// The perception facade (paper section 3): segmentation, floor, Manhattan frame and
/// classification in order on one RGB-D frame, with the floor and Manhattan tracking kept between
/// frames. Pure: no threads, no I/O, no exceptions on the per-frame path; buffers are kept.

#include <cstdint>
#include <optional>
#include <vector>

#include "stairguide/core/config.hpp"
#include "stairguide/perception/floor_detection.hpp"
#include "stairguide/perception/manhattan_frame.hpp"
#include "stairguide/perception/region_classification.hpp"
#include "stairguide/perception/scene.hpp"
#include "stairguide/perception/segmentation.hpp"

namespace stairguide {

/// The odometry's pose of the frame being processed, for what perception keeps in the world from
/// one frame to the next (the Manhattan frame: walls do not turn when the user does).
struct OdometryLink {
  Pose T_world_camera = Pose::Identity();  ///< this frame's camera in the odometry's world
  /// Changes whenever the odometry's world is not the one of the previous poses (tracking lost, a
  /// restart, a new recording): nothing is carried across a change.
  std::uint64_t track = 0;
};

/// One view's own Manhattan frame, to be held in the odometry's world once the odometry's pose of
/// that view's frame is known (it may come a few frames later: the odometry runs beside).
struct ManhattanSighting {
  bool valid = false;
  Eigen::Vector3f k_camera = Eigen::Vector3f::UnitZ();  ///< k_M in the view's camera frame
  float weight = 0.f;      ///< its agreeing vertical planes: area times squared horizontal width
  double timestamp = 0.0;  ///< s, the view's
};

class Perception {
 public:
  Perception(const SegmentationConfig& seg = {}, const FloorConfig& floor = {},
             const ManhattanConfig& manhattan = {}, const ClassificationConfig& classification = {});
  explicit Perception(const PipelineConfig& config);

  /// Runs every stage on `frame` into `out` (its vectors are reused). A frame without a floor
  /// has out.floor_found == false and out.why saying so; its regions are kUnclassified.
  void process(const RgbdFrame& frame, SceneResult& out);
  SceneResult process(const RgbdFrame& frame) {
    SceneResult r;
    process(frame, r);
    return r;
  }

  /// With the odometry's pose of the frame `out` was just computed from (process()): the Manhattan
  /// frame is held in the odometry's world, where walls do not turn when the user does. Every frame
  /// a view sees is kept there for ManhattanConfig::carry_seconds with the weight of the planes
  /// that made it (area times squared width, fading with age); the frame held is the direction
  /// most of that weight agrees on, this view's own included.
  /// - A view whose own frame agrees with the held one (within cluster_tolerance) reports their
  ///   weighted mean: one view's yaw is off by degrees on real walls, the odometry's drift over
  ///   seconds much less.
  /// - A view whose own planes make no frame (a strip of wall while turning) gets the held one.
  /// - A view whose own frame turns against the held one by more than cluster_tolerance (a box
  ///   at the edge of the view taken for a wall) gets the held one, unless its own planes outweigh
  ///   what is held.
  /// Either way out.manhattan_carried is set, manhattan_why says why, and the vertical regions are
  /// classified again against the frame reported; this view's own frame is then held (as
  /// hold_manhattan). Nothing is held across a change of the odometry's track. Call it for the
  /// frames in order; a frame it is not called for neither gets the held frame nor adds to it
  /// (unless its sighting is held later with hold_manhattan).
  void apply_odometry(const OdometryLink& odometry, double timestamp, SceneResult& out);
  /// The frame `out` (just computed by process(), at `timestamp`) made of its own; invalid when
  /// none. Taken before apply_odometry changes `out`.
  ManhattanSighting manhattan_sighting(const SceneResult& out, double timestamp) const;
  /// Holds a view's own frame, given the odometry's pose of that view's frame: for a view whose
  /// pose came only after later views (apply_odometry holds the frame of the view it is given).
  /// A sighting from another track than the frames held, older than them, is dropped.
  void hold_manhattan(const ManhattanSighting& sighting, const OdometryLink& odometry);
  /// A frame is held that a view at `timestamp` could be given (if the odometry's track has not
  /// changed since).
  bool can_carry_manhattan(double timestamp) const {
    return !sightings_.empty() && timestamp >= sightings_.back().time &&
           timestamp - sightings_.back().time <= manhattan_cfg_.carry_seconds;
  }

  /// Forgets the floor and Manhattan tracking (start of a new sequence, or independent views).
  void reset();

  /// Per-pixel labels of the last frame (see Segmentation::labels()).
  const std::vector<int>& labels() const { return segmentation_.labels(); }
  const Segmentation& segmentation() const { return segmentation_; }
  const FloorEstimate& last_floor() const { return floor_est_; }
  /// The floor detector, with the user's camera height it holds (rig_height()).
  const FloorDetector& floor_detector() const { return floor_; }
  /// Takes over a rig learned by another detector (FloorDetector::restore_rig).
  void restore_rig(const FloorDetector::Rig& rig) { floor_.restore_rig(rig); }

 private:
  Segmentation segmentation_;
  FloorDetector floor_;
  ManhattanTracker manhattan_;
  EdgeCompass compass_;
  float max_range_ = CaptureConfig{}.max_range;  // m, the depth cut-off (the compass's floor lines)
  ClassificationConfig classification_;
  FloorEstimate floor_est_;
  ManhattanConfig manhattan_cfg_;
  // Manhattan frames seen in recent views: k_M in the odometry's world, time, weight.
  struct Sighting {
    Eigen::Vector3f k_world;
    double time;
    float weight;
  };
  std::vector<Sighting> sightings_;  // oldest first (by the views' time)
  struct HeldVote {
    float a, w;  // rad modulo 90 degrees in this view's floor frame; weight
    double time;
  };
  std::vector<HeldVote> held_votes_;  // scratch
  std::uint64_t sightings_track_ = 0;
  std::optional<float> last_yaw_;  // the last yaw reported (seen or carried): keeps k_M's branch
};

/// Colours of the paper's Fig. 3 f (BGR): yellow vertical, blue horizontal step candidate, green
/// floor, red other / obstacle; grey for unclassified planes.
cv::Vec3b region_class_color(RegionClass c);

/// Draws the classification over `base` (BGR, or grey / empty: a depth shading is used) with
/// `alpha` opacity; clusters are drawn red. Returns a new CV_8UC3 image.
cv::Mat draw_classification(const cv::Mat& base, const cv::Mat& depth, const SceneResult& scene,
                            const std::vector<int>& labels, float alpha = 0.55f);

}  // namespace stairguide
