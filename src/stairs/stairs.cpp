#include "stairguide/stairs/stairs.hpp"

#include <chrono>
#include <utility>

namespace stairguide {

const char* to_string(StairAxesMethod m) {
  switch (m) {
    case StairAxesMethod::kNone: return "none";
    case StairAxesMethod::kManhattan: return "manhattan";
    case StairAxesMethod::kPca: return "pca";
  }
  return "none";
}

const char* to_string(StairVerdict v) {
  switch (v) {
    case StairVerdict::kDetected: return "detected";
    case StairVerdict::kNoFloor: return "no floor";
    case StairVerdict::kFloorDoubtful: return "floor doubtful (a lower level is nearer the user)";
    case StairVerdict::kNoCandidates: return "no step candidates";
    case StairVerdict::kNoFirstStep: return "no first step connected to the floor";
    case StairVerdict::kObstacle: return "single level too small for a step (obstacle)";
    case StairVerdict::kRiserOutOfRange: return "rise not a step's (under 5 or over 25 cm)";
    case StairVerdict::kTreadTooShort: return "tread too shallow to hold a foot";
    case StairVerdict::kBlondelOutOfRange: return "2R+T outside the building code";
    case StairVerdict::kTooNarrow: return "too narrow to walk";
    case StairVerdict::kInconsistentEdges: return "step edges not evenly spaced";
    case StairVerdict::kStackedLevels: return "a level stands on the one below it (an object on a surface)";
    case StairVerdict::kTreadTooLong: return "levels farther apart than a stride (not one flight)";
  }
  return "unknown";
}

StairStage::StairStage(const ClassificationConfig& classification, const StairDetectionConfig& detection,
                       const StairModellingConfig& modelling, const FloorConfig& floor)
    : detection_(classification, detection),
      modelling_(classification, detection, modelling),
      floorless_(classification, detection, modelling, floor),
      floorless_on_(detection.floorless) {}

namespace {

void reset(StairResult& r, StairVerdict v, int candidates) { r.clear(v, candidates); }

using Clock = std::chrono::steady_clock;

/// Detection from t0 to t1, modelling from t1 to t2.
void set_timings(StairResult& r, Clock::time_point t0, Clock::time_point t1, Clock::time_point t2) {
  auto ms = [](Clock::duration x) { return std::chrono::duration<double, std::milli>(x).count(); };
  r.timings.detection_ms = ms(t1 - t0);
  r.timings.modelling_ms = ms(t2 - t1);
  r.timings.total_ms = ms(t2 - t0);
}

/// True when `a` is the better answer for the user than `b`.
bool better(const StairResult& a, const StairResult& b) {
  if (a.detected != b.detected) return a.detected;
  if (a.levels != b.levels) return a.levels > b.levels;
  return a.kind == StairKind::kDescending || a.kind == StairKind::kCurb;
}

}  // namespace

void StairStage::run(const SceneResult& scene, const CameraIntrinsics* K, StairResult& out) {
  using clock = std::chrono::steady_clock;
  const auto t0 = clock::now();
  detection_.run(scene, detection_out_);
  const auto t1 = clock::now();
  const auto& d = detection_out_;
  if (d.verdict == StairVerdict::kNoFloor && floorless_on_) {
    // No floor, so no heights: the horizontal planes themselves give the vertical (floorless.hpp).
    reset(other_, d.verdict, d.candidates);
    floorless_.run(scene, K, out);
    // Without a stack of levels the reason stays "no floor"; a rejected stack says why.
    if (!out.detected && out.levels < 2) out.verdict = StairVerdict::kNoFloor;
    set_timings(out, t0, t1, clock::now());
    return;
  }
  reset(up_, d.ascending.verdict, d.ascending.candidates);
  reset(down_, d.descending.verdict, d.descending.candidates);
  if (d.verdict == StairVerdict::kDetected) {
    if (d.ascending.step_levels() > 0) modelling_.run(scene, d.ascending, up_, K);
    if (d.descending.step_levels() > 0) modelling_.run(scene, d.descending, down_, K);
  }
  // A doubtful floor spoils both directions: every height is measured from it.
  if (up_.verdict == StairVerdict::kFloorDoubtful || down_.verdict == StairVerdict::kFloorDoubtful) {
    for (StairResult* r : {&up_, &down_}) {
      r->detected = false;
      r->verdict = StairVerdict::kFloorDoubtful;
    }
  }
  // Which level the user stands on is in doubt, which way is up is not: the treads' own vertical
  // (the floorless route) still tells a staircase that is there, with its first step placed from
  // the remembered camera height or left unknown (issue 39: doubt about the floor silenced
  // flights seen from a landing).
  if (up_.verdict == StairVerdict::kFloorDoubtful && floorless_on_) {
    floorless_.run(scene, K, out);
    if (out.detected) {
      reset(other_, StairVerdict::kFloorDoubtful, d.candidates);
      set_timings(out, t0, t1, clock::now());
      return;
    }
  }
  const auto t2 = clock::now();
  if (d.verdict != StairVerdict::kDetected) {
    reset(out, d.verdict, d.candidates);
    reset(other_, d.verdict, d.candidates);
  } else if (better(down_, up_)) {
    std::swap(out, down_);
    std::swap(other_, up_);
  } else {
    std::swap(out, up_);
    std::swap(other_, down_);
  }
  // With nothing modelled on either side, say why in the most informative way.
  if (!out.detected && out.levels == 0 && d.verdict == StairVerdict::kDetected)
    out.verdict = (d.ascending.candidates + d.descending.candidates) > 0 ? StairVerdict::kNoFirstStep
                                                                         : StairVerdict::kNoCandidates;
  out.candidates = d.candidates;
  out.rejected_candidates = d.ascending.rejected + d.descending.rejected;
  const auto t3 = clock::now();
  auto ms = [](clock::duration x) { return std::chrono::duration<double, std::milli>(x).count(); };
  out.timings.detection_ms = ms(t1 - t0);
  out.timings.modelling_ms = ms(t2 - t1);
  out.timings.total_ms = ms(t3 - t0);
}

}  // namespace stairguide
