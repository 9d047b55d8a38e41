// `stairguide bench daemon [--json] [INPUT]`: the daemon's runtime on a recording held in memory
// (so that the figures are the pipeline's, not the renderer's or the disk's):
//   1. reference: synchronous mode (one thread, every stage on every frame), same frames;
//   2. fast replay, threaded: frames per second through the whole pipeline, every frame through
//      odometry (odometry_frames_lost must be 0);
//   3. real-time replay at the recording's 30 Hz, threaded: capture-to-decision latency p50/p99 and
//      the share of frames perception skipped.
//   --cues: only the cue latency per cue kind over the synthetic walks (climbs and descents), each
//      replayed from memory at its 30 Hz: capture of the frame warranting a cue -> its first sample
//      handed to the sound device, p50/p99/max per kind, and the cues heard after their step passed.
//   4. the cue path: the feedback stage driven at 30 Hz with a cue (a step tick) every third frame,
//      from the decision to the cue's first sample handed to the sound device (`--audio DEV`,
//      default ALSA's "null"; the buzzer is off in every run).
// Top-level JSON keys: fps (2), latency_p50_ms / latency_p99_ms / perception_drop_rate (3),
// cue_latency_p50_ms / cue_latency_p99_ms (3: capture of the frame warranting a cue -> its first
// sample out), odometry_frames_lost (2 + 3); each run in full under "fast", "realtime",
// "reference", "cue_path".
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <filesystem>
#include <thread>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core/utility.hpp>

#include "cli/command.hpp"
#include "stairguide/capture/frame_source.hpp"
#include "stairguide/runtime/logging.hpp"
#include "stairguide/runtime/pipeline.hpp"
#include "stairguide/runtime/runtime.hpp"

namespace stairguide::cli {
namespace {

/// Frames read once, replayed from memory (pixels shared: the stages only read a frame).
class MemorySource : public FrameSource {
 public:
  MemorySource(std::shared_ptr<const std::vector<RgbdFrame>> frames, CameraIntrinsics k, std::string desc,
               long limit)
      : frames_(std::move(frames)),
        k_(k),
        desc_(std::move(desc)),
        n_(std::min<long>(limit, static_cast<long>(frames_->size()))) {}
  ReadResult read(RgbdFrame& out) override {
    if (i_ >= n_) return {ReadStatus::kEnd, ""};
    out = (*frames_)[static_cast<std::size_t>(i_++)];
    return {};
  }
  CameraIntrinsics intrinsics() const override { return k_; }
  long frame_count() const override { return n_; }
  std::string describe() const override { return desc_ + " (in memory)"; }

 private:
  std::shared_ptr<const std::vector<RgbdFrame>> frames_;
  CameraIntrinsics k_;
  std::string desc_;
  long n_ = 0, i_ = 0;
};

struct Run {
  runtime::RuntimeStats stats;
  double wall_s = 0.0;
  int exit_code = 0;
};

Run run_once(const PipelineConfig& config, std::shared_ptr<const std::vector<RgbdFrame>> frames,
             CameraIntrinsics k, const std::string& desc, long limit, bool realtime, bool synchronous) {
  runtime::RuntimeOptions o;
  o.input = "bench";
  o.realtime = realtime;
  o.synchronous = synchronous;
  o.frame_lines = false;
  o.open_source = [=](const std::string&, const CaptureConfig&) {
    return std::make_unique<MemorySource>(frames, k, desc, limit);
  };
  runtime::Runtime rt(config, o, nullptr);
  const auto t0 = std::chrono::steady_clock::now();
  rt.start();
  Run r;
  r.exit_code = rt.run();
  r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  r.stats = rt.stats();
  return r;
}

// The frames of `src` read into memory (at most `limit`; all when it is negative); a read error
// throws.
std::shared_ptr<std::vector<RgbdFrame>> read_frames(FrameSource& src, long limit) {
  auto frames = std::make_shared<std::vector<RgbdFrame>>();
  for (long i = 0; limit < 0 || i < limit; ++i) {
    RgbdFrame f;
    const ReadResult r = src.read(f);
    if (r.status == ReadStatus::kEnd) break;
    if (!r.ok()) throw std::runtime_error(r.message);
    frames->push_back(std::move(f));
  }
  return frames;
}

std::string run_json(const Run& r) {
  const auto& s = r.stats;
  char buf[1024];
  std::snprintf(
      buf, sizeof buf,
      "{\"frames\": %llu, \"fps\": %.2f, \"latency_p50_ms\": %.2f, \"latency_p99_ms\": %.2f, "
      "\"latency_max_ms\": %.2f, \"odometry_frames\": %llu, \"odometry_frames_lost\": %llu, "
      "\"odometry_failures\": %llu, \"perception_frames\": %llu, \"perception_skipped\": %llu, "
      "\"perception_drop_rate\": %.4f, \"perception_fps\": %.2f, \"odometry_ms_mean\": %.2f, "
      "\"perception_ms_mean\": %.2f, \"cues\": %llu, \"cues_sounded\": %llu, \"cue_latency_p50_ms\": %.2f, "
      "\"cue_latency_p99_ms\": %.2f, \"wall_s\": %.2f}",
      static_cast<unsigned long long>(s.frames_captured), s.fps, s.latency_p50_ms, s.latency_p99_ms,
      s.latency_max_ms, static_cast<unsigned long long>(s.odometry_frames),
      static_cast<unsigned long long>(s.odometry_frames_lost + (s.frames_captured - s.odometry_frames)),
      static_cast<unsigned long long>(s.odometry_failures),
      static_cast<unsigned long long>(s.perception_frames),
      static_cast<unsigned long long>(s.perception_skipped), s.perception_drop_rate, s.perception_fps,
      s.odometry_ms_mean, s.perception_ms_mean, static_cast<unsigned long long>(s.cues),
      static_cast<unsigned long long>(s.cues_sounded), s.cue_latency_p50_ms, s.cue_latency_p99_ms, r.wall_s);
  return buf;
}

void print_run(const char* name, const Run& r) {
  const auto& s = r.stats;
  std::printf(
      "%-22s %5llu frames  %7.1f fps  latency p50 %6.1f ms  p99 %6.1f ms  odometry %llu lost %llu  "
      "perception %llu skipped %llu (%.1f%%)  stage means: odometry %.1f ms perception %.1f ms  "
      "cues %llu (sounded %llu) capture->sound p50 %.1f ms p99 %.1f ms\n",
      name, static_cast<unsigned long long>(s.frames_captured), s.fps, s.latency_p50_ms, s.latency_p99_ms,
      static_cast<unsigned long long>(s.odometry_frames),
      static_cast<unsigned long long>(s.odometry_frames_lost + (s.frames_captured - s.odometry_frames)),
      static_cast<unsigned long long>(s.perception_frames),
      static_cast<unsigned long long>(s.perception_skipped), 100.0 * s.perception_drop_rate,
      s.odometry_ms_mean, s.perception_ms_mean, static_cast<unsigned long long>(s.cues),
      static_cast<unsigned long long>(s.cues_sounded), s.cue_latency_p50_ms, s.cue_latency_p99_ms);
}

/// The feedback stage alone at 30 Hz, a step tick every third frame: decision -> first sample.
runtime::FeedbackStage::CueLatency cue_path(const PipelineConfig& config, int frames) {
  PipelineConfig c = config;
  c.feedback.count_interval = 100;  // ticks only (no spoken counts)
  c.feedback.min_tick_interval = 0.f;
  runtime::FeedbackStage stage(c);
  // "ready" and "first step" come on the first frame (the second waits for the first to end):
  // the steps that follow are measured on an idle sink.
  const int warmup = 30;
  const auto t0 = std::chrono::steady_clock::now();
  for (int i = 0; i < warmup + frames; ++i) {
    if (i == warmup) {
      stage.drain(std::chrono::milliseconds(3000));
      stage.clear_cue_latency();
    }
    std::this_thread::sleep_until(t0 + std::chrono::microseconds(33333) * i +
                                  std::chrono::seconds(i >= warmup ? 1 : 0));
    const runtime::PerceptionOutput p =
        runtime::climbing_output(static_cast<std::uint64_t>(i), i < warmup ? 1 : 1 + (i - warmup) / 3);
    stage.decide(p, nullptr, i / 30.0, std::chrono::steady_clock::now());
  }
  stage.drain(std::chrono::milliseconds(3000));
  return stage.cue_latency();
}

/// The cue latency per cue kind as a wearer meets it: each synthetic walk (climbs and descents)
/// held in memory and replayed threaded at its 30 Hz (the runtime paces the frames by their
/// timestamps, so the cues' clock is the sensor's), cues to `config.feedback.audio_device`.
int bench_cues(const PipelineConfig& config, const std::vector<std::string>& walks, bool json) {
  struct Acc {
    std::uint64_t given = 0, sounded = 0, late = 0;
    std::vector<double> ms, dms;
  };
  std::vector<std::pair<std::string, Acc>> kinds;  // in the order first met
  auto acc_of = [&](const std::string& k) -> Acc& {
    for (auto& [n, a] : kinds)
      if (n == k) return a;
    kinds.push_back({k, Acc{}});
    return kinds.back().second;
  };
  std::vector<double> decision_ms;  // capture -> decision over all walks' frames (the stages' share)
  std::string per_walk;
  for (const auto& walk : walks) {
    auto src = open_frame_source("synth:" + walk, config.capture);
    const CameraIntrinsics k = src->intrinsics();
    const std::string desc = src->describe();
    if (!json) std::fprintf(stderr, "bench daemon --cues: %s: rendering...\n", walk.c_str());
    auto frames = read_frames(*src, -1);
    src.reset();
    const long n = static_cast<long>(frames->size());
    if (!json)
      std::fprintf(stderr, "bench daemon --cues: %s: %ld frames at 30 Hz (%.0f s)...\n", walk.c_str(), n,
                   n / 30.0);
    const Run r = run_once(config, frames, k, desc, n, true, false);
    frames.reset();
    std::uint64_t walk_cues = 0, walk_late = 0;
    double walk_max = 0.0;
    for (const auto& c : r.stats.cue_kinds) {
      Acc& a = acc_of(c.kind);
      a.given += c.given;
      a.sounded += c.sounded;
      a.late += c.late;
      a.ms.insert(a.ms.end(), c.samples_ms.begin(), c.samples_ms.end());
      a.dms.insert(a.dms.end(), c.from_decision_ms.begin(), c.from_decision_ms.end());
      walk_cues += c.given;
      walk_late += c.late;
      for (double v : c.samples_ms) walk_max = std::max(walk_max, v);
    }
    char line[512];
    std::snprintf(
        line, sizeof line,
        "%s{\"walk\": \"%s\", \"frames\": %ld, \"cues\": %llu, \"late\": %llu, \"cue_latency_max_ms\": %.1f, "
        "\"decision_latency_p99_ms\": %.1f, \"perception_drop_rate\": %.4f}",
        per_walk.empty() ? "" : ", ", walk.c_str(), n, static_cast<unsigned long long>(walk_cues),
        static_cast<unsigned long long>(walk_late), walk_max, r.stats.latency_p99_ms,
        r.stats.perception_drop_rate);
    per_walk += line;
    if (!json)
      std::printf(
          "%-22s %5ld frames  cues %3llu  late %llu  cue latency max %7.1f ms  capture->decision p99 %6.1f "
          "ms  "
          "perception skipped %.1f%%\n",
          walk.c_str(), n, static_cast<unsigned long long>(walk_cues),
          static_cast<unsigned long long>(walk_late), walk_max, r.stats.latency_p99_ms,
          100.0 * r.stats.perception_drop_rate);
  }
  auto pct = [](std::vector<double> v, double p) {
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    const auto rank = std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil(p / 100.0 * v.size())));
    return v[rank - 1];
  };
  bool pass = true;
  std::string kinds_json;
  std::vector<double> all;
  std::uint64_t late = 0;
  for (const auto& [name, a] : kinds) {
    const double p50 = pct(a.ms, 50), p99 = pct(a.ms, 99);
    const double mx = a.ms.empty() ? 0.0 : *std::max_element(a.ms.begin(), a.ms.end());
    all.insert(all.end(), a.ms.begin(), a.ms.end());
    late += a.late;
    if (!a.ms.empty() && p99 > 100.0) pass = false;
    char b[512];
    const double d50 = pct(a.dms, 50), d99 = pct(a.dms, 99);
    std::snprintf(b, sizeof b,
                  "%s\"%s\": {\"given\": %llu, \"sounded\": %llu, \"late\": %llu, \"p50_ms\": %.1f, "
                  "\"p99_ms\": %.1f, \"max_ms\": %.1f, "
                  "\"from_decision_p50_ms\": %.1f, \"from_decision_p99_ms\": %.1f}",
                  kinds_json.empty() ? "" : ", ", name.c_str(), static_cast<unsigned long long>(a.given),
                  static_cast<unsigned long long>(a.sounded), static_cast<unsigned long long>(a.late), p50,
                  p99, mx, d50, d99);
    kinds_json += b;
    if (!json)
      std::printf(
          "  %-14s given %4llu  sounded %4llu  late %3llu  p50 %7.1f ms  p99 %7.1f ms  max %7.1f ms   "
          "(decision -> sound p50 %6.1f p99 %6.1f ms)\n",
          name.c_str(), static_cast<unsigned long long>(a.given), static_cast<unsigned long long>(a.sounded),
          static_cast<unsigned long long>(a.late), p50, p99, mx, d50, d99);
  }
  if (late > 0) pass = false;
  if (json)
    std::printf(
        "{\"cue_latency_p50_ms\": %.1f, \"cue_latency_p99_ms\": %.1f, \"late\": %llu, \"kinds\": {%s},\n "
        "\"walks\": [%s]}\n",
        pct(all, 50), pct(all, 99), static_cast<unsigned long long>(late), kinds_json.c_str(),
        per_walk.c_str());
  else
    std::printf(
        "all cues: p50 %.1f ms p99 %.1f ms, %llu late; target p99 <= 100 ms for every kind and none late: "
        "%s\n",
        pct(all, 50), pct(all, 99), static_cast<unsigned long long>(late), pass ? "PASS" : "FAIL");
  return 0;
}

int bench_daemon(Context& ctx) {
  const bool json = ctx.flag("--json");
  const bool cues_only = ctx.flag("--cues");
  const std::string walks_arg = ctx.option("--walks").value_or(
      "climb_3_steps,climb_8_steps,climb_14_steps,climb_8_pause_turn,climb_8_person,"
      "descend_3_steps,descend_8_steps,descend_14_steps,descend_8_pause_turn,descend_8_person");
  const bool skip_realtime = ctx.flag("--no-realtime");
  const long frames_wanted = ctx.int_option("--frames", 1, 100000).value_or(600);
  const long reference_frames = ctx.int_option("--reference-frames", 0, 100000).value_or(150);
  const std::string audio_device = ctx.option("--audio").value_or("null");
  const auto pos = ctx.positionals(0, 1);
  std::string input =
      pos.empty() ? "synth:ascending_approach_climb:" + std::to_string(frames_wanted) + ":1" : pos[0];

  runtime::setup_logging("warn");  // the runtime's counters would otherwise go to stdout
  cv::setNumThreads(1);            // as stairguided does at start (see stairguided_main.cpp)
  PipelineConfig config = ctx.config;
  config.runtime.log_level = "warn";
  // Cues to a sound device that takes samples at the pace of a card (the sink holds itself to
  // it), no buzzer; the sounds from the source tree when they are not installed.
  config.feedback.audio_device = audio_device;
  config.feedback.haptic_enabled = false;
  if (!std::filesystem::exists(config.feedback.sounds_dir))
    config.feedback.sounds_dir = std::string(STAIRGUIDE_SOURCE_DIR) + "/sounds";

  if (cues_only) {
    std::vector<std::string> walks;
    std::stringstream ws(walks_arg);
    for (std::string w; std::getline(ws, w, ',');)
      if (!w.empty()) walks.push_back(w);
    return bench_cues(config, walks, json);
  }

  auto src = open_frame_source(input, config.capture);
  const std::string desc = src->describe();
  const CameraIntrinsics k = src->intrinsics();
  if (!json) std::fprintf(stderr, "bench daemon: reading %s into memory...\n", desc.c_str());
  auto frames = read_frames(*src, frames_wanted);
  src.reset();
  if (frames->empty()) throw UsageError(input + ": no frames");
  const long n = static_cast<long>(frames->size());
  std::shared_ptr<const std::vector<RgbdFrame>> shared = frames;

  if (!json)
    std::fprintf(stderr, "bench daemon: %ld frames %dx%d; reference (one thread, %ld frames)...\n", n,
                 k.width, k.height, std::min(n, reference_frames));
  Run reference;
  if (reference_frames > 0)
    reference = run_once(config, shared, k, desc, std::min(n, reference_frames), false, true);
  if (!json) std::fprintf(stderr, "bench daemon: fast replay (threaded)...\n");
  const Run fast = run_once(config, shared, k, desc, n, false, false);
  Run rt;
  if (!skip_realtime) {
    if (!json) std::fprintf(stderr, "bench daemon: real-time replay (threaded, %.0f s)...\n", n / 30.0);
    rt = run_once(config, shared, k, desc, n, true, false);
  }
  if (!json) std::fprintf(stderr, "bench daemon: the cue path (feedback stage at 30 Hz, 10 s)...\n");
  const auto cues = cue_path(config, 300);
  const Run& lat = skip_realtime ? fast : rt;
  const auto lost = [](const Run& r) {
    return r.stats.odometry_frames_lost + (r.stats.frames_captured - r.stats.odometry_frames);
  };
  const unsigned long long total_lost = lost(fast) + (skip_realtime ? 0 : lost(rt));
  const double ratio = reference.stats.fps > 0 ? fast.stats.fps / reference.stats.fps : 0.0;

  if (json) {
    std::printf(
        "{\"input\": \"%s\", \"frames\": %ld, \"width\": %d, \"height\": %d, \"fps\": %.2f, "
        "\"latency_p50_ms\": %.2f, \"latency_p99_ms\": %.2f, \"odometry_frames_lost\": %llu, "
        "\"perception_drop_rate\": %.4f, \"fps_ratio_vs_reference\": %.3f, \"cue_latency_p50_ms\": %.2f, "
        "\"cue_latency_p99_ms\": %.2f,\n \"fast\": %s,\n \"realtime\": %s,\n"
        " \"reference\": %s,\n \"cue_path\": {\"cues\": %llu, \"sounded\": %llu, \"p50_ms\": %.2f, "
        "\"p99_ms\": %.2f, \"max_ms\": %.2f}}\n",
        desc.c_str(), n, k.width, k.height, fast.stats.fps, lat.stats.latency_p50_ms,
        lat.stats.latency_p99_ms, total_lost, lat.stats.perception_drop_rate, ratio,
        lat.stats.cue_latency_p50_ms, lat.stats.cue_latency_p99_ms, run_json(fast).c_str(),
        skip_realtime ? "null" : run_json(rt).c_str(),
        reference_frames > 0 ? run_json(reference).c_str() : "null",
        static_cast<unsigned long long>(cues.cues), static_cast<unsigned long long>(cues.sounded),
        cues.p50_ms, cues.p99_ms, cues.max_ms);
  } else {
    std::printf("stairguide bench daemon: %s, %ld frames %dx%d\n", desc.c_str(), n, k.width, k.height);
    if (reference_frames > 0) print_run("reference (1 thread)", reference);
    print_run("fast replay", fast);
    if (!skip_realtime) print_run("real-time 30 Hz", rt);
    std::printf("threaded fast replay vs one thread: %.2fx frames per second\n", ratio);
    std::printf(
        "cue path at 30 Hz: %llu cues, %llu sounded, decision -> first sample p50 %.2f ms p99 %.2f ms max "
        "%.2f ms\n",
        static_cast<unsigned long long>(cues.cues), static_cast<unsigned long long>(cues.sounded),
        cues.p50_ms, cues.p99_ms, cues.max_ms);
    std::printf(
        "targets: fast >= 60 fps: %s (%.1f); every frame through odometry: %s (%llu lost); "
        "real-time p99 <= 50 ms: %s (%.1f); perception drops <= 1%%: %s (%.2f%%); "
        "cue capture->sound p99 <= 100 ms: %s (%.1f over %llu cues; the cue path's decision->sound p99 "
        "%.1f)\n",
        fast.stats.fps >= 60 ? "PASS" : "FAIL", fast.stats.fps, total_lost == 0 ? "PASS" : "FAIL", total_lost,
        lat.stats.latency_p99_ms <= 50 ? "PASS" : "FAIL", lat.stats.latency_p99_ms,
        lat.stats.perception_drop_rate <= 0.01 ? "PASS" : "FAIL", 100.0 * lat.stats.perception_drop_rate,
        lat.stats.cues_sounded > 0 && lat.stats.cue_latency_p99_ms <= 100 ? "PASS" : "FAIL",
        lat.stats.cue_latency_p99_ms, static_cast<unsigned long long>(lat.stats.cues_sounded), cues.p99_ms);
  }
  return 0;
}

}  // namespace

SG_BENCH("daemon",
         "daemon [--json] [--frames N] [--reference-frames N] [--no-realtime] [--audio DEV] [INPUT] | "
         "daemon --cues [--walks W,W..] [--audio DEV] [--json]",
         "the daemon's threads: fast and 30 Hz replay (fps, latency p50/p99, drops) vs one thread; --cues: "
         "cue latency per cue kind over the synthetic climbs and descents at 30 Hz",
         bench_daemon);

}  // namespace stairguide::cli
