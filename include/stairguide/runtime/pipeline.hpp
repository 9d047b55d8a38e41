#pragma once
/// \file pipeline.hpp
/// The stages the daemon runs, behind one small interface each, so that the threaded runtime and
/// the synchronous (one thread, in order) mode drive exactly the same code.
///
/// - `OdometryStage::step(frame)`: dense RGB-D odometry on every frame (odometry room).
/// - `PerceptionStage::step(frame, odometry)`: segmentation, floor, Manhattan frame, classification
///   (perception room) -> stair detection and modelling, drop-offs (stairs room) -> traversal.
/// - `FeedbackStage::decide(perception, odometry)`: the cue decision (feedback room).
///
/// Each stage wraps whatever the library provides; a room the library does not have yet is
/// reported by `available()` = false and `describe()` (a seam, never a fake result). Stages are
/// not thread-safe: each is driven by one thread. `reconfigure()` is called by that same thread
/// between two frames.

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "stairguide/core/config.hpp"
#include "stairguide/core/types.hpp"
#include "stairguide/runtime/latency.hpp"
#include "stairguide/stairs/traversal_result.hpp"

namespace stairguide {
struct OdometryLink;  // perception/perception.hpp
struct SceneResult;   // perception/scene.hpp
struct StairResult;   // stairs/stair_result.hpp
}  // namespace stairguide

namespace stairguide::runtime {

/// What odometry made of one frame.
struct OdometryOutput {
  std::uint64_t seq = 0;  ///< runtime frame number (0-based, in capture order)
  bool ran = false;       ///< false: this build has no odometry stage
  bool ok = false;        ///< estimate trusted (see `status`)
  std::string status;     ///< "ok", "first frame", or why not (short, no spaces: for the frame lines)
  Pose T_world_camera = Pose::Identity();  ///< accumulated pose C0 -> Ck
  double ms = 0.0;                         ///< time spent in the stage
};

/// What perception (and the stair stages behind it) made of one frame.
struct PerceptionOutput {
  std::uint64_t seq = 0;  ///< runtime frame number
  bool ran = false;       ///< false: this build has no perception stage
  bool floor_found = false;
  bool stair_detected = false;
  /// One token for the frame lines: "no_floor", "floor", "ascending", "descending",
  /// "single_step", "curb" (a detection), or "none" without a perception stage.
  std::string state;
  std::string detail;  ///< human-readable: why no floor / no stair, levels, riser...
  int levels = 0;      ///< stair levels in view (0 without a detection)
  /// The Manhattan frame: seen in this view, carried by the odometry from an earlier one, or none.
  bool manhattan_found = false;
  bool manhattan_carried = false;
  float manhattan_yaw = 0.f;  ///< rad, k_M from the floor frame's forward axis
  /// The wearer's rig as the floor detector has learned it (camera height above what the user stands
  /// on, and its tilt); 0 while not yet established.
  float rig_height_m = 0.f;
  float rig_tilt_rad = 0.f;
  int rig_learned = 0;  ///< FloorDetector::rig_learned(): changes when the rig is learned anew
  /// The typed results: what the feedback room reads (as numbers, not from `detail`).
  StairSummary stair;
  DropSummary drop;  ///< a drop-off ahead (stairs/drop_detection.hpp); not told when `stair` goes down
  TraversalResult
      traversal;  ///< the traversal tracker (stairs/traversal.hpp); `ran` false when traversal.enabled is off
  double ms = 0.0;  ///< time spent in the stages
};

/// A made-up output of runtime frame `seq`: the user on an ascending flight, `climbed` steps up
/// (the feedback stage driven without perception: `bench daemon`'s cue timing, the tests).
inline PerceptionOutput climbing_output(std::uint64_t seq, int climbed) {
  PerceptionOutput p;
  p.seq = seq;
  p.ran = true;
  p.floor_found = true;
  p.state = "ascending";
  p.traversal.ran = true;
  p.traversal.state = TraversalState::kOnStairs;
  p.traversal.kind = StairKind::kAscending;
  p.traversal.direction = 1;
  p.traversal.steps_climbed = p.traversal.step_index = climbed;
  return p;
}

/// What the odometry says of a frame's pose.
enum class PoseAnswer {
  kReady,   ///< `link` holds its trusted pose
  kNotYet,  ///< the odometry has not reached the frame yet
  kNever,   ///< there will be none: the odometry failed on it, dropped it, or has stopped
};
/// The odometry's pose of runtime frame `seq`. With `wait` it may wait briefly for the odometry
/// thread to reach the frame (asked only where a Manhattan frame is to be carried: elsewhere
/// perception does not wait).
using OdometryLookup = std::function<PoseAnswer(std::uint64_t seq, OdometryLink& link, bool wait)>;

/// The feedback decision for one perceived frame.
struct Decision {
  std::string state;     ///< the state the user is in, as told ("none", "ascending", ...)
  bool changed = false;  ///< differs from the previous decision
  std::string cue;       ///< cue emitted for this frame, empty when none (or no feedback stage)
};

/// Dense odometry on every frame.
class OdometryStage {
 public:
  explicit OdometryStage(const PipelineConfig& config);
  ~OdometryStage();
  OdometryStage(const OdometryStage&) = delete;
  OdometryStage& operator=(const OdometryStage&) = delete;

  OdometryOutput step(const RgbdFrame& frame);
  /// Applies a new config; when its odometry section changed, the odometry keeps its pose but
  /// restarts from the next frame, and true is returned. Other sections change nothing here.
  bool reconfigure(const PipelineConfig& config);
  /// After a camera reconnect: the next frame starts a new track from the last pose.
  void restart();
  bool available() const;
  std::string describe() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Segmentation -> floor -> Manhattan -> classification -> stair detection/modelling -> traversal.
class PerceptionStage {
 public:
  explicit PerceptionStage(const PipelineConfig& config);
  ~PerceptionStage();
  PerceptionStage(const PerceptionStage&) = delete;
  PerceptionStage& operator=(const PerceptionStage&) = delete;

  /// `seq` is the runtime frame number of `frame`; `odometry` gives the odometry's poses by frame
  /// number (may be empty): the Manhattan frame is held in the odometry's world and carried to
  /// views whose own walls make none. A view whose pose is not there yet has its frame held when
  /// it comes, on a later step.
  PerceptionOutput step(const RgbdFrame& frame, std::uint64_t seq, const OdometryLookup& odometry);
  /// The full results of the last step(), as the stages left them (the scene after the Manhattan
  /// carry, the stairs stage's model): for an observer of the synchronous mode, valid until the
  /// next step() or reconfigure().
  const SceneResult& last_scene() const;
  const StairResult& last_stair() const;
  void reconfigure(const PipelineConfig& config);
  bool available() const;
  std::string describe() const;

 private:
  void hold_and_carry(const RgbdFrame& frame, std::uint64_t seq, const OdometryLookup& odometry);
  const SceneResult& drop_scene(const RgbdFrame& frame, bool posed_run, SceneResult& carried);
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Turns perceived states into cues for the user.
class FeedbackStage {
 public:
  explicit FeedbackStage(const PipelineConfig& config);
  ~FeedbackStage();
  FeedbackStage(const FeedbackStage&) = delete;
  FeedbackStage& operator=(const FeedbackStage&) = delete;

  /// `timestamp_s`: the frame's timestamp (the policy's clock: a replay at any speed gives the
  /// same cues); `captured`: when it was captured (the cue latency is measured from it).
  Decision decide(const PerceptionOutput& perception, const OdometryOutput* latest_odometry,
                  double timestamp_s = 0.0,
                  std::chrono::steady_clock::time_point captured = std::chrono::steady_clock::now());
  /// Between frames (the feedback thread's every turn, at least every 50 ms): the wearer's button
  /// presses answered at once and a mute ended on time, even when no frame comes. Opens the
  /// button (feedback.button_enabled) on its first call.
  void poll();
  /// The camera stopped sending (`why` names it) / is back: the user must be told.
  void camera_lost(const std::string& why);
  void camera_back();
  void reconfigure(const PipelineConfig& config);
  bool available() const;
  std::string describe() const;
  /// Plays out what is queued, at most `timeout` (end of a replay).
  void drain(std::chrono::milliseconds timeout);

  /// Capture of the frame that warranted a cue -> its first sample handed to the sound device.
  struct CueLatency {
    std::uint64_t cues = 0;     ///< cues given (all sinks)
    std::uint64_t sounded = 0;  ///< of them, started on the sound device
    std::uint64_t lost = 0;     ///< of them, dropped unplayed (the sound device could not take them)
    double p50_ms = 0.0, p99_ms = 0.0, max_ms = 0.0;
    std::string last;                     ///< token of the last cue given ("" none)
    std::vector<CueKindLatency> by_kind;  ///< per cue kind given at least once, in Cue order
  };
  CueLatency cue_latency() const;  ///< any thread
  void clear_cue_latency();        ///< forgets the latencies measured so far (benchmarks)

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// One line naming the stage implementations compiled into this build, e.g.
/// "odometry=DenseOdometry perception=none(seam) ...".
std::string describe_stages(const PipelineConfig& config);

}  // namespace stairguide::runtime
