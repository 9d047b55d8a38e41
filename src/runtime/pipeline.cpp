// The stage wrappers of the daemon. Each wraps the library's stage of its room; a room that the
// library does not provide yet is a named seam (available() == false, ran == false in its
// outputs): the runtime reports it and never invents a result.
#include "stairguide/runtime/pipeline.hpp"

#include "stairguide/stairs/stair_checks.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <deque>
#include <utility>

#include "stairguide/odometry/dense_odometry.hpp"
#include "stairguide/perception/perception.hpp"
#include "stairguide/stairs/drop_detection.hpp"
#include "stairguide/stairs/stairs.hpp"
#include "stairguide/stairs/traversal.hpp"

namespace stairguide::runtime {

namespace {

double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// The detection as the user is told it. The distance and bearing are measured in the plane
// perpendicular to the stair's own vertical (y_S), from the point under the camera, the bearing
// from the camera's forward direction in that plane: the same with a floor in view and with a
// remembered one; unknown without either.
StairSummary summarize(const StairResult& r) {
  StairSummary s;
  s.detected = r.detected;
  if (!r.detected) return s;
  s.kind = r.kind;
  s.direction = r.direction();
  s.without_floor = r.without_floor;
  s.levels = r.levels;
  s.riser_m = r.riser_m;
  s.tread_m = r.tread_m;
  s.width_m = r.width_m;
  s.T_camera_stair = r.T_camera_stair;
  if (r.without_floor) return s;
  const Eigen::Vector3f up = r.T_camera_stair.rotation().col(1);
  const Eigen::Vector3f o = r.origin();
  const Eigen::Vector3f oh = o - o.dot(up) * up;
  Eigen::Vector3f fwd = Eigen::Vector3f::UnitZ() - up.z() * up;
  if (fwd.norm() < 1e-3f) return s;  // looking straight down: no forward direction
  fwd.normalize();
  const Eigen::Vector3f right = fwd.cross(up);
  s.distance_m = oh.norm();
  s.bearing_rad = std::atan2(oh.dot(right), oh.dot(fwd));
  return s;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Odometry: the odometry room's DenseOdometry, configured from the first frame's intrinsics (and
// again whenever they change: a reconnected camera may come back in another mode).
struct OdometryStage::Impl {
  PipelineConfig config;
  DenseOdometry odometry;
  CameraIntrinsics intrinsics;
  bool configured = false;
};

OdometryStage::OdometryStage(const PipelineConfig& config) : impl_(std::make_unique<Impl>()) {
  impl_->config = config;
}
OdometryStage::~OdometryStage() = default;

OdometryOutput OdometryStage::step(const RgbdFrame& frame) {
  const auto t0 = std::chrono::steady_clock::now();
  Impl& m = *impl_;
  const CameraIntrinsics& k = frame.intrinsics;
  if (!m.configured || k.width != m.intrinsics.width || k.height != m.intrinsics.height ||
      k.fx != m.intrinsics.fx || k.fy != m.intrinsics.fy || k.cx != m.intrinsics.cx ||
      k.cy != m.intrinsics.cy) {
    const Pose keep = m.odometry.pose();
    m.odometry.configure(m.config.odometry, k);
    if (m.configured) m.odometry.reset(keep);  // a new camera mode continues the same track
    m.intrinsics = k;
    m.configured = true;
  }
  const OdometryResult r = m.odometry.track(frame);
  OdometryOutput out;
  out.seq = frame.index;
  out.ran = true;
  out.ok = r.ok;
  out.status = r.ok ? "ok" : (r.why && *r.why ? r.why : to_string(r.status));
  out.T_world_camera = r.T_world_camera;
  out.ms = ms_since(t0);
  return out;
}
bool OdometryStage::reconfigure(const PipelineConfig& config) {
  Impl& m = *impl_;
  // Only its own section matters: a reload for the verbosity or the perception's tunables must
  // not restart the track the step count holds its staircase in.
  PipelineConfig probe = m.config;
  probe.odometry = config.odometry;
  const bool same = config_equal(probe, m.config);
  m.config = config;
  if (same) return false;
  if (m.configured) {
    const Pose keep = m.odometry.pose();
    m.odometry.configure(config.odometry, m.intrinsics);
    m.odometry.reset(keep);
  }
  return true;
}
void OdometryStage::restart() { impl_->odometry.reset(impl_->odometry.pose()); }
bool OdometryStage::available() const { return true; }
std::string OdometryStage::describe() const { return "DenseOdometry"; }

// ---------------------------------------------------------------------------------------------
// Perception (segmentation, floor, Manhattan, classification) -> stairs (detection, modelling).
// The odometry's pose of the same frame carries the Manhattan frame between views and holds the
// staircase in the world for the traversal tracker (paper 5.2).
struct PerceptionStage::Impl {
  explicit Impl(const PipelineConfig& c) : config(c), perception(c), stairs(c), traversal(c.traversal) {}
  PipelineConfig config;
  Perception perception;
  StairStage stairs;
  TraversalTracker traversal;
  SceneResult scene;
  StairResult stair;
  // The odometry's answer for the frame being perceived (hold_and_carry asks it).
  PoseAnswer pose_answer = PoseAnswer::kNever;
  OdometryLink pose_link;
  // The floor as last found, held in the odometry's world: a drop's edge near the feet leaves
  // only a strip of floor in view, which the floor detector may not take (drop_scene()).
  Pose T_world_floor = Pose::Identity();
  double floor_seen_t = -1.0;
  std::uint64_t floor_track = 0;  // the odometry's world it is held in
  // Views whose own Manhattan frame waits for the odometry's pose of their frame (oldest first).
  std::deque<std::pair<std::uint64_t, ManhattanSighting>> pending;
};

PerceptionStage::PerceptionStage(const PipelineConfig& config) : impl_(std::make_unique<Impl>(config)) {}
PerceptionStage::~PerceptionStage() = default;

PerceptionOutput PerceptionStage::step(const RgbdFrame& frame, std::uint64_t seq,
                                       const OdometryLookup& odometry) {
  const auto t0 = std::chrono::steady_clock::now();
  Impl& m = *impl_;
  m.perception.process(frame, m.scene);
  m.pose_answer = PoseAnswer::kNever;
  if (odometry) hold_and_carry(frame, seq, odometry);
  PerceptionOutput out;
  out.seq = frame.index;
  out.ran = true;
  out.floor_found = m.scene.floor_found;
  out.manhattan_found = m.scene.manhattan_found;
  out.manhattan_carried = m.scene.manhattan_carried;
  out.manhattan_yaw = m.scene.manhattan_yaw;
  out.rig_height_m = m.perception.floor_detector().rig_height();
  out.rig_tilt_rad = m.perception.floor_detector().rig_tilt();
  out.rig_learned = m.perception.floor_detector().rig_learned();
  // The stair stage runs without a floor too: its floorless route (when configured) finds a stack
  // of treads by their own vertical, with the distance from the user's feet unknown.
  m.stairs.run(m.scene, &frame.intrinsics, m.stair);
  out.stair_detected = m.stair.detected;
  out.stair = summarize(m.stair);
  // Drop-offs: the floor ending with nothing within a step below (a descent is the stair stage's).
  SceneResult carried;
  const DropResult drop =
      detect_drop(frame, drop_scene(frame, static_cast<bool>(odometry), carried), m.config.drops);
  out.drop = summarize_drop(drop, m.stair);
  // The tracker: the pose of this frame when the odometry has it; otherwise the tracker takes the
  // camera to be where it was and lets the live view correct the staircase.
  if (m.config.traversal.enabled) {
    const bool trusted = odometry && m.pose_answer == PoseAnswer::kReady;
    out.traversal = m.traversal.update(m.scene, m.stair, m.pose_link.T_world_camera, trusted, frame.timestamp,
                                       m.pose_link.track);
  }
  if (m.stair.detected) {
    out.state = to_string(m.stair.kind);
    out.levels = m.stair.levels;
    char buf[200];
    if (m.stair.without_floor)
      std::snprintf(
          buf, sizeof buf,
          "%s, %d levels seen, riser %.1f cm, tread %.1f cm, no floor in view: distance and first step "
          "unknown",
          to_string(m.stair.kind), m.stair.levels, 100.0 * m.stair.riser_m, 100.0 * m.stair.tread_m);
    else
      std::snprintf(buf, sizeof buf,
                    "%s, %d levels, riser %.1f cm, tread %.1f cm, width %.2f m, %.2f m ahead",
                    to_string(m.stair.kind), m.stair.levels, 100.0 * m.stair.riser_m, 100.0 * m.stair.tread_m,
                    m.stair.width_m, m.stair.origin().norm());
    // The building code describes what was found (steep, low risers); it never silenced it.
    out.detail = std::string(buf) + "; " + code_notes_text(m.stair.code_notes);
  } else if (!m.scene.floor_found) {
    out.state = "no_floor";
    out.detail = m.scene.why.empty() ? "no floor" : m.scene.why;
  } else {
    out.state = "floor";
    out.detail = std::string("floor, no stairs: ") + to_string(m.stair.verdict);
  }
  if (out.drop.detected) {
    char buf[120];
    std::snprintf(buf, sizeof buf, "; drop ahead %.2f m at %+.0f deg, %.2f m deep", out.drop.distance_m,
                  rad2deg(out.drop.bearing_rad), out.drop.depth_m);
    out.detail += buf;
  }
  out.ms = ms_since(t0);
  return out;
}

// The floor the drop stage measures from: this view's, or, when this view's floor was not found,
// the one last found carried by the odometry (for at most kFloorCarry s, in the same odometry
// world: a dense odometry drifts about a centimetre in that time). Standing 0.5-0.7 m from
// a platform's edge, the floor in view is a strip the floor detector does not take, and the
// approach beep would fall silent where it matters most.
const SceneResult& PerceptionStage::drop_scene(const RgbdFrame& frame, bool posed_run, SceneResult& carried) {
  constexpr double kFloorCarry = 8.0;  // s
  Impl& m = *impl_;
  const bool posed = posed_run && m.pose_answer == PoseAnswer::kReady;
  if (m.scene.floor_found) {
    m.floor_seen_t = posed ? frame.timestamp : -1.0;
    if (posed) m.T_world_floor = m.pose_link.T_world_camera * m.scene.T_floor_camera.inverse();
    m.floor_track = m.pose_link.track;
    return m.scene;
  }
  if (!posed || m.floor_seen_t < 0.0 || frame.timestamp - m.floor_seen_t > kFloorCarry ||
      m.pose_link.track != m.floor_track)
    return m.scene;
  carried.floor_found = true;
  carried.T_floor_camera = m.T_world_floor.inverse() * m.pose_link.T_world_camera;
  return carried;
}

// The odometry's pose is asked for only now: running beside perception on the same frame, it has
// usually finished the frame by the time segmentation has. Perception waits for it only on a view
// that needs a frame carried; a view seen before its pose came is held when the pose comes.
void PerceptionStage::hold_and_carry(const RgbdFrame& frame, std::uint64_t seq,
                                     const OdometryLookup& odometry) {
  constexpr std::size_t kMaxPending = 32;
  Impl& m = *impl_;
  auto flush = [&] {
    while (!m.pending.empty()) {
      OdometryLink l;
      const PoseAnswer a = odometry(m.pending.front().first, l, false);
      if (a == PoseAnswer::kNotYet) break;  // nor the later ones: the odometry goes in order
      if (a == PoseAnswer::kReady) m.perception.hold_manhattan(m.pending.front().second, l);
      m.pending.pop_front();
    }
  };
  flush();
  // process() just ran: a frame found is this view's own (apply_odometry has not carried one in).
  const bool seen = m.scene.manhattan_found;
  const bool carry = !seen && m.scene.floor_found &&
                     (m.perception.can_carry_manhattan(frame.timestamp) || !m.pending.empty());
  // A staircase held by the traversal tracker needs this frame's pose as much as a carried frame.
  const bool traversing = m.config.traversal.enabled && m.traversal.holding();
  OdometryLink link;
  const PoseAnswer a = odometry(seq, link, carry || traversing);
  m.pose_answer = a;
  if (a == PoseAnswer::kReady) m.pose_link = link;
  if (a == PoseAnswer::kReady) {
    flush();  // the odometry has passed the views before this one
    m.perception.apply_odometry(link, frame.timestamp, m.scene);
  } else if (a == PoseAnswer::kNotYet && seen) {
    if (m.pending.size() == kMaxPending) m.pending.pop_front();
    m.pending.emplace_back(seq, m.perception.manhattan_sighting(m.scene, frame.timestamp));
  }
}

const SceneResult& PerceptionStage::last_scene() const { return impl_->scene; }
const StairResult& PerceptionStage::last_stair() const { return impl_->stair; }

void PerceptionStage::reconfigure(const PipelineConfig& config) {
  // Sections perception does not read (the odometry's, the runtime's, the feedback's) change
  // nothing here: its memory (the floor, the Manhattan frame, what the stairs stage holds) stays.
  {
    PipelineConfig probe = config;
    probe.odometry = impl_->config.odometry;
    probe.runtime = impl_->config.runtime;
    probe.feedback = impl_->config.feedback;
    if (config_equal(probe, impl_->config)) {
      impl_->config = config;
      return;
    }
  }
  // The stages take their config at construction; tracking restarts with the new values. Not the
  // traversal: a reload on the stairs (a SIGHUP for the verbosity) would have started the count
  // again from nothing under the user's feet. The odometry keeps its world over a reload, so the
  // staircase held in it stays where it is.
  TraversalTracker traversal = std::move(impl_->traversal);
  // Nor the wearer's rig: it is the same person with the same camera (a waist rig would have
  // waited rig_learn_frames views for its floor again).
  const FloorDetector::Rig rig = impl_->perception.floor_detector().rig();
  impl_ = std::make_unique<Impl>(config);
  impl_->traversal = std::move(traversal);
  impl_->perception.restore_rig(rig);
  impl_->traversal.reconfigure(config.traversal);
  if (!config.traversal.enabled) impl_->traversal.reset();
}
bool PerceptionStage::available() const { return true; }
std::string PerceptionStage::describe() const {
  return impl_->config.traversal.enabled ? "Perception+StairStage+TraversalTracker"
                                         : "Perception+StairStage(traversal disabled in the config)";
}

// Feedback: src/runtime/feedback_stage.cpp.

std::string describe_stages(const PipelineConfig& config) {
  return "odometry=" + OdometryStage(config).describe() +
         " perception=" + PerceptionStage(config).describe() +
         " feedback=" + FeedbackStage(config).describe();
}

}  // namespace stairguide::runtime
