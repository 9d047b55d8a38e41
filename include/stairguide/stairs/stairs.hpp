#pragma once
/// \file stairs.hpp
/// The stairs stage (paper section 4): detection (stair_detection.hpp) then modelling
/// (stair_modelling.hpp) of both an ascending and a descending staircase, keeping the better one.
///
///   StairStage stage(config);           // once
///   StairResult result;                 // reused frame after frame
///   stage.run(scene, frame.intrinsics, result);  // scene from perception
///   if (result.detected) ... result.kind, result.riser_m, result.T_camera_stair ...
///   else ... to_string(result.verdict)
///
/// Pure: no I/O, no threads, no exceptions; buffers are kept between frames.

#include "stairguide/core/config.hpp"
#include "stairguide/perception/scene.hpp"
#include "stairguide/stairs/floorless.hpp"
#include "stairguide/stairs/stair_detection.hpp"
#include "stairguide/stairs/stair_modelling.hpp"
#include "stairguide/stairs/stair_result.hpp"

namespace stairguide {

class StairStage {
 public:
  /// `floor` gives the floorless route (floorless.hpp) its roll limit.
  StairStage(const ClassificationConfig& classification, const StairDetectionConfig& detection,
             const StairModellingConfig& modelling, const FloorConfig& floor = {});
  explicit StairStage(const PipelineConfig& config)
      : StairStage(config.classification, config.stair_detection, config.stair_modelling, config.floor) {}

  /// Detects and models the staircase of one frame. When both an ascending and a descending one
  /// are found, the result is the validated one with more levels (a tie goes to the descending one,
  /// the more dangerous); `other()` holds the other. When perception found no floor and
  /// StairDetectionConfig::floorless is on, the floorless route (floorless.hpp) runs instead: a
  /// staircase it finds has `without_floor` set, anything else keeps the verdict kNoFloor.
  void run(const SceneResult& scene, StairResult& out) { run(scene, nullptr, out); }
  /// The same, knowing the frame's intrinsics: a staircase cut by the image border is not taken
  /// for a narrow one (see StairModelling::run).
  void run(const SceneResult& scene, const CameraIntrinsics& K, StairResult& out) { run(scene, &K, out); }
  void run(const SceneResult& scene, const CameraIntrinsics* K, StairResult& out);

  /// The hypothesis of the other direction from the last run (not detected when there was none).
  const StairResult& other() const { return other_; }
  /// Detection output of the last run (levels before modelling).
  const StairDetectionOutput& detection() const { return detection_out_; }
  /// What the floorless route saw in the last run (meaningful after a frame without floor).
  const FloorlessTrace& floorless_trace() const { return floorless_.trace(); }

 private:
  StairDetection detection_;
  StairModelling modelling_;
  FloorlessStairs floorless_;
  bool floorless_on_ = true;
  StairDetectionOutput detection_out_;
  StairResult up_, down_, other_;
};

}  // namespace stairguide
