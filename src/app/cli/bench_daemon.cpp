// `stairguide bench daemon [--json] [INPUT]`: the daemon's runtime on a recording held in memory
// (so that the figures are the pipeline's, not the renderer's or the disk's):
//   1. reference: synchronous mode (one thread, every stage on every frame), same frames;
//   2. fast replay, threaded: frames per second through the whole pipeline, every frame through
//      odometry (odometry_frames_lost must be 0);
//   3. real-time replay at the recording's 30 Hz, threaded: capture-to-decision latency p50/p99 and
//      the share of frames perception skipped.
// Top-level JSON keys: fps (2), latency_p50_ms / latency_p99_ms / perception_drop_rate (3),
// odometry_frames_lost (2 + 3); each run in full under "fast", "realtime", "reference".
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core/utility.hpp>

#include "cli/command.hpp"
#include "stairguide/capture/frame_source.hpp"
#include "stairguide/runtime/logging.hpp"
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

std::string run_json(const Run& r) {
  const auto& s = r.stats;
  char buf[1024];
  std::snprintf(
      buf, sizeof buf,
      "{\"frames\": %llu, \"fps\": %.2f, \"latency_p50_ms\": %.2f, \"latency_p99_ms\": %.2f, "
      "\"latency_max_ms\": %.2f, \"odometry_frames\": %llu, \"odometry_frames_lost\": %llu, "
      "\"odometry_failures\": %llu, \"perception_frames\": %llu, \"perception_skipped\": %llu, "
      "\"perception_drop_rate\": %.4f, \"perception_fps\": %.2f, \"odometry_ms_mean\": %.2f, "
      "\"perception_ms_mean\": %.2f, \"wall_s\": %.2f}",
      static_cast<unsigned long long>(s.frames_captured), s.fps, s.latency_p50_ms, s.latency_p99_ms,
      s.latency_max_ms, static_cast<unsigned long long>(s.odometry_frames),
      static_cast<unsigned long long>(s.odometry_frames_lost + (s.frames_captured - s.odometry_frames)),
      static_cast<unsigned long long>(s.odometry_failures),
      static_cast<unsigned long long>(s.perception_frames),
      static_cast<unsigned long long>(s.perception_skipped), s.perception_drop_rate, s.perception_fps,
      s.odometry_ms_mean, s.perception_ms_mean, r.wall_s);
  return buf;
}

void print_run(const char* name, const Run& r) {
  const auto& s = r.stats;
  std::printf(
      "%-22s %5llu frames  %7.1f fps  latency p50 %6.1f ms  p99 %6.1f ms  odometry %llu lost %llu  "
      "perception %llu skipped %llu (%.1f%%)  stage means: odometry %.1f ms perception %.1f ms\n",
      name, static_cast<unsigned long long>(s.frames_captured), s.fps, s.latency_p50_ms, s.latency_p99_ms,
      static_cast<unsigned long long>(s.odometry_frames),
      static_cast<unsigned long long>(s.odometry_frames_lost + (s.frames_captured - s.odometry_frames)),
      static_cast<unsigned long long>(s.perception_frames),
      static_cast<unsigned long long>(s.perception_skipped), 100.0 * s.perception_drop_rate,
      s.odometry_ms_mean, s.perception_ms_mean);
}

int bench_daemon(Context& ctx) {
  const bool json = ctx.flag("--json");
  const bool skip_realtime = ctx.flag("--no-realtime");
  const long frames_wanted = ctx.int_option("--frames", 1, 100000).value_or(600);
  const long reference_frames = ctx.int_option("--reference-frames", 0, 100000).value_or(150);
  const auto pos = ctx.positionals(0, 1);
  std::string input =
      pos.empty() ? "synth:ascending_approach_climb:" + std::to_string(frames_wanted) + ":1" : pos[0];

  runtime::setup_logging("warn");  // the runtime's counters would otherwise go to stdout
  cv::setNumThreads(1);             // as stairguided does at start (see stairguided_main.cpp)
  PipelineConfig config = ctx.config;
  config.runtime.log_level = "warn";

  auto src = open_frame_source(input, config.capture);
  const std::string desc = src->describe();
  const CameraIntrinsics k = src->intrinsics();
  auto frames = std::make_shared<std::vector<RgbdFrame>>();
  if (!json) std::fprintf(stderr, "bench daemon: reading %s into memory...\n", desc.c_str());
  for (long i = 0; i < frames_wanted; ++i) {
    RgbdFrame f;
    const ReadResult r = src->read(f);
    if (r.status == ReadStatus::kEnd) break;
    if (!r.ok()) throw std::runtime_error(r.message);
    frames->push_back(std::move(f));
  }
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
        "\"perception_drop_rate\": %.4f, \"fps_ratio_vs_reference\": %.3f,\n \"fast\": %s,\n \"realtime\": "
        "%s,\n"
        " \"reference\": %s}\n",
        desc.c_str(), n, k.width, k.height, fast.stats.fps, lat.stats.latency_p50_ms,
        lat.stats.latency_p99_ms, total_lost, lat.stats.perception_drop_rate, ratio, run_json(fast).c_str(),
        skip_realtime ? "null" : run_json(rt).c_str(),
        reference_frames > 0 ? run_json(reference).c_str() : "null");
  } else {
    std::printf("stairguide bench daemon: %s, %ld frames %dx%d\n", desc.c_str(), n, k.width, k.height);
    if (reference_frames > 0) print_run("reference (1 thread)", reference);
    print_run("fast replay", fast);
    if (!skip_realtime) print_run("real-time 30 Hz", rt);
    std::printf("threaded fast replay vs one thread: %.2fx frames per second\n", ratio);
    std::printf(
        "targets: fast >= 60 fps: %s (%.1f); every frame through odometry: %s (%llu lost); "
        "real-time p99 <= 50 ms: %s (%.1f); perception drops <= 1%%: %s (%.2f%%)\n",
        fast.stats.fps >= 60 ? "PASS" : "FAIL", fast.stats.fps, total_lost == 0 ? "PASS" : "FAIL", total_lost,
        lat.stats.latency_p99_ms <= 50 ? "PASS" : "FAIL", lat.stats.latency_p99_ms,
        lat.stats.perception_drop_rate <= 0.01 ? "PASS" : "FAIL", 100.0 * lat.stats.perception_drop_rate);
  }
  return 0;
}

}  // namespace

SG_BENCH("daemon", "daemon [--json] [--frames N] [--reference-frames N] [--no-realtime] [INPUT]",
         "the daemon's threads: fast and 30 Hz replay (fps, latency p50/p99, drops) vs one thread",
         bench_daemon);

}  // namespace stairguide::cli
