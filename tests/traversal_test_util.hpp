#pragma once
// Synthetic walks through perception, the stairs stage and the traversal tracker, with the
// ground-truth poses as the odometry (optionally with drift injected: a scale error on every
// increment and a yaw that grows with time), scored against each frame's truth (the step under
// the body). Several tracker variants (configs, drifts) share one rendering and perception pass.

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "stairguide/capture/synth_source.hpp"
#include "stairguide/core/config.hpp"
#include "stairguide/perception/perception.hpp"
#include "stairguide/stairs/stairs.hpp"
#include "stairguide/stairs/traversal.hpp"

namespace sgtest {

/// Odometry drift: every increment scaled by (1 + scale), the world turned about the vertical by
/// yaw_rate * t (rad/s) as the increments are added up.
struct Drift {
  float scale = 0.f;
  float yaw_rate = 0.f;
};

/// The drifted odometry, fed the true poses one by one.
class DriftedOdometry {
 public:
  explicit DriftedOdometry(Drift d) : d_(d) {}
  stairguide::Pose operator()(const stairguide::Pose& truth, double t) {
    const Eigen::Matrix3f Rz =
        Eigen::AngleAxisf(d_.yaw_rate * static_cast<float>(t), Eigen::Vector3f::UnitZ()).toRotationMatrix();
    if (!have_) {
      p_ = truth.translation();
      have_ = true;
    } else {
      p_ += Rz * ((1.f + d_.scale) * (truth.translation() - last_.translation()));
    }
    last_ = truth;
    stairguide::Pose out = stairguide::Pose::Identity();
    out.linear() = Rz * truth.linear();
    out.translation() = p_;
    return out;
  }

 private:
  Drift d_;
  bool have_ = false;
  stairguide::Pose last_ = stairguide::Pose::Identity();
  Eigen::Vector3f p_ = Eigen::Vector3f::Zero();
};

struct Variant {
  std::string name;
  stairguide::TraversalConfig cfg;
  Drift drift;
};

/// One frame of one variant.
struct FrameRecord {
  long index = 0;
  int truth_step = 0;
  float truth_along = 0.f;       // the body centre along z_S (truth)
  Eigen::Vector3f truth_camera;  // the camera in the true stair frame
  Eigen::Vector3f model_camera;  // the camera in the tracker's stair frame (NaN without one)
  stairguide::TraversalResult r;
  bool detected = false;  // the stairs stage found the staircase of the truth's direction
  float det_riser = 0.f, det_tread = 0.f;
};

struct WalkRun {
  std::string preset;
  int steps = 0;
  float riser = 0.f, tread = 0.f, width = 0.f;
  int direction = 0;
  std::vector<std::vector<FrameRecord>> frames;  // per variant
  std::vector<double> tracker_ms, stairs_ms;
};

/// Blanks the depth of the upper half of the image (the far steps): something standing in front.
inline void hide_upper_half(stairguide::RgbdFrame& f) { f.depth.rowRange(0, f.depth.rows / 2).setTo(0.f); }

/// Every frame of `preset` at `fps` through perception, the stairs stage and each variant's
/// tracker; frames [hide_from, hide_from + hide_count) have the upper half of their depth hidden.
inline WalkRun run_walk(const std::string& preset, std::uint32_t seed, const std::vector<Variant>& variants,
                        double fps = 15.0, long hide_from = -1, long hide_count = 0,
                        bool real_noise = false) {
  using namespace stairguide;
  synth::SynthOptions opt = real_noise ? synth::with_real_kinect_noise() : synth::SynthOptions{};
  opt.fps = fps;
  const synth::PresetInfo* info = synth::find_preset_info(preset);
  const long frames =
      info ? static_cast<long>(std::ceil(static_cast<double>(info->default_frames) * fps / 30.0)) : 1;
  auto src = synth::make_source(preset, frames, seed, opt);
  PipelineConfig cfg;
  Perception perception(cfg);
  StairStage stage(cfg);
  std::vector<TraversalTracker> trackers;
  std::vector<DriftedOdometry> odo;
  for (const Variant& v : variants) {
    trackers.emplace_back(v.cfg);
    odo.emplace_back(v.drift);
  }
  WalkRun run;
  run.preset = preset;
  run.frames.resize(variants.size());
  RgbdFrame f;
  SceneResult scene;
  StairResult stair;
  for (long i = 0; i < frames; ++i) {
    if (!src->read(f).ok()) break;
    const FrameTruth truth = *src->truth();
    if (truth.stairs.empty()) continue;
    const StairTruth& st = truth.stairs[0];
    run.steps = st.steps;
    run.riser = st.riser_m;
    run.tread = st.tread_m;
    run.width = st.width_m;
    run.direction = st.goes_down() ? -1 : 1;
    if (i >= hide_from && i < hide_from + hide_count) hide_upper_half(f);
    perception.process(f, scene);
    stage.run(scene, f.intrinsics, stair);
    run.stairs_ms.push_back(stair.timings.total_ms);
    const Pose T_sc_truth = st.T_camera_stair.inverse();
    const Eigen::Vector3f cam = T_sc_truth.translation();
    Eigen::Vector3f fwd = T_sc_truth.linear().col(2);
    fwd.y() = 0.f;
    fwd.normalize();
    for (std::size_t k = 0; k < variants.size(); ++k) {
      const Pose T_wc = odo[k](truth.T_world_camera, f.timestamp);
      FrameRecord rec;
      rec.index = i;
      rec.truth_step = st.user_step;
      rec.truth_camera = cam;
      rec.truth_along = (cam - 0.12f * fwd).z();
      rec.r = trackers[k].update(scene, stair, T_wc, true, f.timestamp);
      run.tracker_ms.push_back(rec.r.ms);
      rec.model_camera = rec.r.direction != 0
                             ? Eigen::Vector3f(rec.r.T_world_stair.inverse() * T_wc.translation())
                             : Eigen::Vector3f::Constant(std::nanf(""));
      rec.detected = stair.detected && stair.direction() == run.direction &&
                     (stair.kind == StairKind::kAscending || stair.kind == StairKind::kDescending);
      rec.det_riser = stair.riser_m;
      rec.det_tread = stair.tread_m;
      if (std::getenv("SG_TRACE") && k == 0)
        std::printf(
            "#%ld truth %d along %.3f | %s step %d known %d last %d in_view %d q %.2f corr h %.2f a %.2f yaw "
            "%.2f "
            "cm/deg | det %d %s lv %d r %.3f t %.3f floor %d wf %d | gap a %.1f h %.1f cm\n",
            i, rec.truth_step, rec.truth_along, to_string(rec.r.state), rec.r.step_index, rec.r.steps_known,
            rec.r.last_known, rec.r.in_view, rec.r.quality, 100 * rec.r.corr_height_m,
            100 * rec.r.corr_along_m, rec.r.corr_yaw_rad * 57.3f, stair.detected, to_string(stair.kind),
            stair.levels, stair.riser_m, stair.tread_m, scene.floor_found, stair.without_floor,
            100 * (rec.model_camera.z() - cam.z()), 100 * (rec.model_camera.y() - cam.y()));
      run.frames[k].push_back(rec);
    }
  }
  return run;
}

/// The figures of the issue on one variant of one walk.
struct TraversalFigures {
  int on_stairs = 0, right = 0;  // frames on the flight (truth step >= 1, before arrival), step right
  int final_climbed = 0;         // the highest step index reported on the flight
  int phantom = 0;               // frames with a step index or steps known beyond the flight's steps
  bool last_announced = false;   // last_step (or arrived) reported while the truth step < steps
  long last_announced_at = -1, foot_on_last_at = -1;
  bool arrived = false;
  int left_searching = 0;                    // frames not searching
  std::vector<float> gap_along, gap_height;  // per step 1..N, at the first frame on it (m, signed)
  double single_riser = 0, single_tread = 0, fused_riser = 0, fused_tread = 0;
  int fused_frames = 0;
  std::vector<long> wrong_frames;
};

inline TraversalFigures score(const WalkRun& run, std::size_t variant) {
  using namespace stairguide;
  TraversalFigures F;
  F.gap_along.assign(static_cast<std::size_t>(run.steps), std::nanf(""));
  F.gap_height.assign(static_cast<std::size_t>(run.steps), std::nanf(""));
  const float arrive_at = static_cast<float>(run.steps - 1) * run.tread + 0.2f;
  for (const FrameRecord& rec : run.frames[variant]) {
    const TraversalResult& r = rec.r;
    if (r.state != TraversalState::kSearching) ++F.left_searching;
    if (r.step_index > run.steps || r.steps_known > run.steps) ++F.phantom;
    if (rec.truth_step >= 1 && rec.truth_along < arrive_at) {
      ++F.on_stairs;
      if (r.step_index == rec.truth_step) {
        ++F.right;
      } else {
        F.wrong_frames.push_back(rec.index);
      }
    }
    if (r.state == TraversalState::kOnStairs || r.state == TraversalState::kLastStep)
      F.final_climbed = std::max(F.final_climbed, r.steps_climbed);
    if (r.state == TraversalState::kArrived) {
      F.arrived = true;
      F.final_climbed = std::max(F.final_climbed, r.steps_climbed);
    }
    if (rec.truth_step == run.steps && F.foot_on_last_at < 0) F.foot_on_last_at = rec.index;
    if (F.last_announced_at < 0 && r.last_known &&
        (r.state == TraversalState::kLastStep || r.state == TraversalState::kArrived)) {
      F.last_announced_at = rec.index;
      F.last_announced = rec.truth_step < run.steps;
    }
    if (rec.truth_step >= 1 && rec.truth_step <= run.steps) {
      const std::size_t k = static_cast<std::size_t>(rec.truth_step - 1);
      if (std::isnan(F.gap_along[k]) && std::isfinite(rec.model_camera.z())) {
        F.gap_along[k] = rec.model_camera.z() - rec.truth_camera.z();
        F.gap_height[k] = rec.model_camera.y() - rec.truth_camera.y();
      }
    }
    if (rec.detected && r.in_view && rec.det_riser > 0.f && rec.det_tread > 0.f) {
      F.single_riser += std::fabs(rec.det_riser - run.riser);
      F.single_tread += std::fabs(rec.det_tread - run.tread);
      F.fused_riser += std::fabs(r.riser_m - run.riser);
      F.fused_tread += std::fabs(r.tread_m - run.tread);
      ++F.fused_frames;
    }
  }
  if (F.fused_frames > 0) {
    F.single_riser /= F.fused_frames;
    F.single_tread /= F.fused_frames;
    F.fused_riser /= F.fused_frames;
    F.fused_tread /= F.fused_frames;
  }
  return F;
}

inline void print(const WalkRun& run, const std::string& variant, const TraversalFigures& F) {
  std::printf(
      "%-22s %-12s N=%2d on-stairs %3d right %3d (%.1f%%) climbed %d phantom %d last-announced %s (frame "
      "%ld, "
      "foot on it %ld) arrived %d | riser err single %.2f fused %.2f cm, tread single %.2f fused %.2f cm (%d "
      "frames)\n",
      run.preset.c_str(), variant.c_str(), run.steps, F.on_stairs, F.right,
      100.0 * F.right / std::max(1, F.on_stairs), F.final_climbed, F.phantom, F.last_announced ? "yes" : "NO",
      F.last_announced_at, F.foot_on_last_at, F.arrived, 100 * F.single_riser, 100 * F.fused_riser,
      100 * F.single_tread, 100 * F.fused_tread, F.fused_frames);
  std::printf("   gap along (cm):");
  for (float g : F.gap_along) std::printf(" %5.1f", 100.f * g);
  std::printf("\n   gap height (cm):");
  for (float g : F.gap_height) std::printf(" %5.1f", 100.f * g);
  std::printf("\n");
  if (!F.wrong_frames.empty()) {
    std::printf("   wrong step at frames:");
    for (std::size_t i = 0; i < F.wrong_frames.size() && i < 30; ++i) std::printf(" %ld", F.wrong_frames[i]);
    std::printf("\n");
  }
}

}  // namespace sgtest
