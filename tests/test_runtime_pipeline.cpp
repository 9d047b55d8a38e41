// The runtime in process: threaded and synchronous modes on small generated frames, frame lines,
// counters, pacing, camera loss and reconnection, config reload, stop, watchdog.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>

#include <functional>
#include <limits>
#include <new>
#include <system_error>

#include "file_test_util.hpp"
#include "stairguide/runtime/frame_clock.hpp"
#include "stairguide/runtime/latency.hpp"
#include "stairguide/runtime/logging.hpp"
#include "stairguide/runtime/pipeline.hpp"
#include "stairguide/runtime/runtime.hpp"

using namespace stairguide;
using namespace stairguide::runtime;
using Clock = std::chrono::steady_clock;

namespace {

/// A camera 1.3 m above a flat textured floor, tilted 45 deg down, walking forward 1 m/s at 30 Hz.
/// Small frames (160x120) keep the real stages fast.
class FloorSource : public FrameSource {
 public:
  struct Behaviour {
    long frames = 60;
    double fps = 30.0;
    bool live = false;
    long error_at = -1;                 ///< replay: kError at this frame
    long timeout_at = -1;               ///< live: kTimeout from this frame on
    std::function<double(long)> ts;     ///< the frame's timestamp (empty: i / fps)
    std::function<void(long)> on_read;  ///< called before frame i is read
    long bad_alloc_at = -1;             ///< std::bad_alloc from read() at this frame
  };
  explicit FloorSource(Behaviour b, long start_index = 0) : b_(b), i_(start_index) {
    k_.width = 160;
    k_.height = 120;
    k_.fx = k_.fy = 131.25f;
    k_.cx = 79.5f;
    k_.cy = 59.5f;
  }
  ReadResult read(RgbdFrame& out) override {
    if (b_.live && b_.timeout_at >= 0 && i_ >= b_.timeout_at) {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
      return {ReadStatus::kTimeout, "fake camera: no frame"};
    }
    if (!b_.live && i_ >= b_.frames) return {ReadStatus::kEnd, ""};
    if (b_.on_read) b_.on_read(i_);
    if (i_ == b_.bad_alloc_at) throw std::bad_alloc();
    if (i_ == b_.error_at)
      return {ReadStatus::kError, "fake.oni: frame " + std::to_string(i_) + " is corrupt"};
    render(out, i_);
    ++i_;
    if (b_.live) std::this_thread::sleep_for(std::chrono::milliseconds(2));
    return {};
  }
  CameraIntrinsics intrinsics() const override { return k_; }
  long frame_count() const override { return b_.live ? -1 : b_.frames; }
  std::string describe() const override { return b_.live ? "fake camera" : "fake recording"; }
  bool is_live() const override { return b_.live; }

 private:
  void render(RgbdFrame& f, long i) const {
    const float tilt = deg2rad(45.f), h = 1.3f;
    const float ux = 0.f, uy = -std::cos(tilt), uz = -std::sin(tilt);  // up, camera frame
    const float fy_ = -std::sin(tilt), fz = std::cos(tilt);            // forward, camera frame
    const float walked = static_cast<float>(i) / static_cast<float>(b_.fps);
    f.index = static_cast<std::uint64_t>(i);
    f.timestamp = b_.ts ? b_.ts(i) : static_cast<double>(i) / b_.fps;
    f.intrinsics = k_;
    f.depth.create(k_.height, k_.width, CV_32FC1);
    f.gray.create(k_.height, k_.width, CV_8UC1);
    f.color.create(k_.height, k_.width, CV_8UC3);
    for (int v = 0; v < k_.height; ++v) {
      for (int u = 0; u < k_.width; ++u) {
        const float dx = (u - k_.cx) / k_.fx, dy = (v - k_.cy) / k_.fy;
        const float denom = ux * dx + uy * dy + uz;
        float z = 0.f;
        unsigned char g = 0;
        if (denom < -1e-3f) {
          const float s = -h / denom;
          if (s < 6.f) {
            z = s;
            const float X = s * dx, F = s * (fy_ * dy + fz) + walked;
            g = static_cast<unsigned char>(128 + 50 * std::sin(6.2831853f * X / 0.3f) +
                                           50 * std::sin(6.2831853f * F / 0.25f));
          }
        }
        f.depth.at<float>(v, u) = z;
        f.gray.at<unsigned char>(v, u) = g;
        f.color.at<cv::Vec3b>(v, u) = cv::Vec3b(g, g, g);
      }
    }
  }
  Behaviour b_;
  long i_;
  CameraIntrinsics k_;
};

class RecordingNotifier : public Notifier {
 public:
  explicit RecordingNotifier(std::uint64_t wd = 0) : wd_(wd) {}
  void notify(const std::string& s) override {
    std::lock_guard<std::mutex> lk(m_);
    msgs_.push_back(s);
  }
  std::uint64_t watchdog_usec() const override { return wd_; }
  int count(const std::string& prefix) const {
    std::lock_guard<std::mutex> lk(m_);
    int n = 0;
    for (const auto& s : msgs_)
      if (s.find(prefix) != std::string::npos) ++n;
    return n;
  }

 private:
  mutable std::mutex m_;
  std::vector<std::string> msgs_;
  std::uint64_t wd_;
};

/// The per-frame lines a run printed, parsed into key -> value maps.
struct Lines {
  std::FILE* f = std::tmpfile();
  ~Lines() {
    if (f) std::fclose(f);
  }
  std::vector<std::map<std::string, std::string>> parse() const {
    std::fflush(f);
    std::rewind(f);
    std::vector<std::map<std::string, std::string>> out;
    char buf[1024];
    while (std::fgets(buf, sizeof buf, f)) out.push_back(stairguide::test::parse_kv(buf));
    return out;
  }
};

PipelineConfig quiet_config() {
  PipelineConfig c;
  c.runtime.log_level = "warn";
  c.runtime.status_interval = 0.2f;
  c.capture.retry_min = 0.02f;
  c.capture.retry_max = 0.08f;
  return c;
}

RuntimeOptions replay_options(FloorSource::Behaviour b, bool realtime, bool sync, std::FILE* out) {
  RuntimeOptions o;
  o.input = "fake.oni";
  o.realtime = realtime;
  o.synchronous = sync;
  o.frame_lines = out != nullptr;
  o.frame_out = out;
  o.open_source = [b](const std::string&, const CaptureConfig&) { return std::make_unique<FloorSource>(b); };
  return o;
}

struct Quiet {
  Quiet() { setup_logging("warn"); }
} quiet_logs;

}  // namespace

TEST(LatencyHistogram, PercentilesToTheBin) {
  LatencyHistogram h;
  EXPECT_EQ(h.percentile(50), 0.0);
  for (int i = 1; i <= 100; ++i) h.add(i);  // 1..100 ms
  EXPECT_NEAR(h.percentile(50), 50.0, 0.11);
  EXPECT_NEAR(h.percentile(99), 99.0, 0.11);
  EXPECT_NEAR(h.percentile(100), 100.0, 0.11);
  EXPECT_NEAR(h.mean(), 50.5, 1e-9);
  h.add(5000);  // overflow bin reports the maximum
  EXPECT_EQ(h.percentile(100), 5000.0);
}

TEST(Logging, JournalOnlyWhenStderrIsTheJournalStream) {
  struct stat st {};
  ASSERT_EQ(fstat(2, &st), 0);
  const std::string mine = std::to_string(st.st_dev) + ":" + std::to_string(st.st_ino);
  const char* old = std::getenv("JOURNAL_STREAM");
  const std::string saved = old ? old : "";
  unsetenv("JOURNAL_STREAM");
  EXPECT_FALSE(stderr_is_journal());
  setenv("JOURNAL_STREAM", mine.c_str(), 1);
  EXPECT_TRUE(stderr_is_journal());
  setenv("JOURNAL_STREAM", (std::to_string(st.st_dev) + ":" + std::to_string(st.st_ino + 1)).c_str(), 1);
  EXPECT_FALSE(stderr_is_journal()) << "a redirected stderr is not the journal";
  if (old)
    setenv("JOURNAL_STREAM", saved.c_str(), 1);
  else
    unsetenv("JOURNAL_STREAM");
  EXPECT_TRUE(set_log_level("debug"));
  EXPECT_FALSE(set_log_level("chatty"));
  EXPECT_TRUE(set_log_level("warn"));
}

TEST(Runtime, ThreadedFastReplayPutsEveryFrameThroughOdometry) {
  Lines lines;
  RecordingNotifier n;
  FloorSource::Behaviour b;
  b.frames = 60;
  Runtime rt(quiet_config(), replay_options(b, false, false, lines.f), &n);
  rt.start();
  ASSERT_TRUE(rt.wait_finished(std::chrono::seconds(60)));
  ASSERT_TRUE(rt.join(std::chrono::seconds(1)));
  EXPECT_EQ(rt.exit_code(), 0);
  const RuntimeStats s = rt.stats();
  EXPECT_EQ(s.state, "ended");
  EXPECT_EQ(s.frames_captured, 60u);
  EXPECT_EQ(s.odometry_frames, 60u);
  EXPECT_EQ(s.odometry_frames_lost, 0u);
  EXPECT_EQ(s.perception_frames + s.perception_skipped, 60u);
  EXPECT_EQ(s.decisions, s.perception_frames);
  EXPECT_GT(s.fps, 0.0);
  EXPECT_GT(s.latency_p99_ms, 0.0);
  EXPECT_GE(s.latency_p99_ms, s.latency_p50_ms);

  const auto l = lines.parse();
  ASSERT_EQ(l.size(), 60u);
  std::uint64_t skipped_lines = 0, odometry_ok = 0;
  for (std::size_t i = 0; i < l.size(); ++i) {
    EXPECT_EQ(l[i].at("frame"), std::to_string(i)) << "frame lines out of order";
    EXPECT_NE(l[i].at("odom"), "lost");
    EXPECT_NE(l[i].at("odom"), "none") << "no odometry stage ran";
    odometry_ok += l[i].at("odom") == "ok";
    if (l[i].at("perception") == "skipped") {
      ++skipped_lines;
      EXPECT_EQ(l[i].at("latency_ms"), "-");
    } else {
      EXPECT_GT(std::stod(l[i].at("latency_ms")), 0.0);
    }
  }
  EXPECT_EQ(skipped_lines, s.perception_skipped) << "every skipped frame is reported";
  EXPECT_GE(odometry_ok, 55u) << "odometry should track a textured floor";
  EXPECT_EQ(n.count("READY=1"), 1);
}

TEST(Runtime, SynchronousModeRunsEveryStageOnEveryFrame) {
  Lines lines;
  FloorSource::Behaviour b;
  b.frames = 20;
  Runtime rt(quiet_config(), replay_options(b, false, true, lines.f), nullptr);
  rt.start();
  EXPECT_EQ(rt.run(), 0);
  const RuntimeStats s = rt.stats();
  EXPECT_EQ(s.odometry_frames, 20u);
  EXPECT_EQ(s.perception_frames, 20u);
  EXPECT_EQ(s.perception_skipped, 0u);
  const auto l = lines.parse();
  ASSERT_EQ(l.size(), 20u);
  for (const auto& kv : l) {
    EXPECT_NE(kv.at("perception"), "skipped");
    EXPECT_NE(kv.at("perception"), "none");
  }
  // A flat floor seen from 1.3 m at 45 deg: perception finds it, and no stairs.
  EXPECT_EQ(l.back().at("perception"), "floor");
}

TEST(Runtime, RealTimeReplayIsPacedByTimestamps) {
  FloorSource::Behaviour b;
  b.frames = 16;  // 15 frame periods = 0.5 s
  Runtime rt(quiet_config(), replay_options(b, true, false, nullptr), nullptr);
  const auto t0 = Clock::now();
  rt.start();
  ASSERT_TRUE(rt.wait_finished(std::chrono::seconds(30)));
  const double s = std::chrono::duration<double>(Clock::now() - t0).count();
  rt.join(std::chrono::seconds(1));
  EXPECT_GE(s, 0.48);
  // Not stuck and not free-running either way: under ThreadSanitizer on a 2-core machine loaded by
  // parallel builds the 16 frames took 3.4 s (perception there is many times slower than 30 Hz).
  EXPECT_LT(s, 8.0);
  // Pacing is what this checks. Perception skipping to the newest frame is by design when it
  // falls behind; under ThreadSanitizer (tools/tsan-runtime) on a loaded 2-core machine it did
  // once skip 1 of the 16 frames. Most frames must still be perceived.
  EXPECT_LE(rt.stats().perception_skipped, 3u) << "perception keeps up with 30 Hz on 160x120";
}

TEST(Runtime, ReadErrorMidReplayEndsWithExitCode1) {
  FloorSource::Behaviour b;
  b.frames = 30;
  b.error_at = 10;
  Runtime rt(quiet_config(), replay_options(b, false, false, nullptr), nullptr);
  rt.start();
  ASSERT_TRUE(rt.wait_finished(std::chrono::seconds(30)));
  rt.join(std::chrono::seconds(1));
  EXPECT_EQ(rt.exit_code(), 1);
  EXPECT_EQ(rt.stats().state, "failed");
  EXPECT_EQ(rt.stats().odometry_frames, 10u) << "the frames before the bad one are all processed";
}

TEST(Runtime, OpenFailureOfAReplayThrowsAtStart) {
  RuntimeOptions o;
  o.input = "/nonexistent/rec.oni";
  o.open_source = [](const std::string& in, const CaptureConfig&) -> std::unique_ptr<FrameSource> {
    throw SourceError(in + ": no such file");
  };
  Runtime rt(quiet_config(), o, nullptr);
  EXPECT_THROW(rt.start(), SourceError);
}

TEST(Runtime, StopsWithinASecondWhileRunning) {
  FloorSource::Behaviour b;
  b.frames = 100000;
  Runtime rt(quiet_config(), replay_options(b, true, false, nullptr), nullptr);
  rt.start();
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  const auto t0 = Clock::now();
  rt.request_stop();
  ASSERT_TRUE(rt.join(std::chrono::milliseconds(1000)));
  const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
  EXPECT_LT(ms, 1000.0);
  EXPECT_EQ(rt.exit_code(), 0);
  EXPECT_EQ(rt.stats().state, "stopped");
  EXPECT_GT(rt.stats().frames_captured, 3u);
}

TEST(Runtime, ReconfigureIsAppliedBetweenFrames) {
  Lines lines;
  FloorSource::Behaviour b;
  b.frames = 24;  // 0.8 s in real time
  Runtime rt(quiet_config(), replay_options(b, true, false, lines.f), nullptr);
  rt.start();
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  PipelineConfig c = quiet_config();
  c.segmentation.voxel_size = 0.05f;
  rt.reconfigure(c);
  ASSERT_TRUE(rt.wait_finished(std::chrono::seconds(30)));
  rt.join(std::chrono::seconds(1));
  EXPECT_EQ(rt.stats().config_generation, 2u);
  const auto l = lines.parse();
  ASSERT_EQ(l.size(), 24u);
  EXPECT_EQ(l.front().at("cfg"), "1");
  EXPECT_EQ(l.back().at("cfg"), "2");
}

TEST(Runtime, LostCameraIsReopenedWithBackOffAndResumes) {
  // The first camera delivers 15 frames then stops sending; the next two opens fail (unplugged),
  // the third gives a working camera again.
  auto opens = std::make_shared<int>(0);
  RuntimeOptions o;
  o.input = "device";
  o.open_source = [opens](const std::string&, const CaptureConfig&) -> std::unique_ptr<FrameSource> {
    const int k = (*opens)++;
    FloorSource::Behaviour b;
    b.live = true;
    if (k == 0) {
      b.timeout_at = 15;
      return std::make_unique<FloorSource>(b);
    }
    if (k <= 2) throw SourceError("fake camera: not connected");
    return std::make_unique<FloorSource>(b, 100);
  };
  RecordingNotifier n;
  Runtime rt(quiet_config(), o, &n);
  rt.start();
  const auto deadline = Clock::now() + std::chrono::seconds(20);
  while (rt.stats().frames_captured < 40 && Clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  rt.request_stop();
  ASSERT_TRUE(rt.join(std::chrono::seconds(1)));
  const RuntimeStats s = rt.stats();
  EXPECT_GE(s.frames_captured, 40u) << "capture resumed after the camera came back";
  EXPECT_EQ(s.camera_losses, 1u);
  EXPECT_EQ(s.reconnects, 1u);
  EXPECT_EQ(*opens, 4);
  EXPECT_GE(n.count("STATUS=camera lost"), 1);
  EXPECT_EQ(rt.exit_code(), 0);
}

TEST(Runtime, WatchdogIsPingedFromThePerceptionLoop) {
  RecordingNotifier n(/*watchdog_usec=*/200000);  // ping every 50 ms
  FloorSource::Behaviour b;
  b.frames = 15;  // 0.5 s real time
  Runtime rt(quiet_config(), replay_options(b, true, false, nullptr), &n);
  rt.start();
  ASSERT_TRUE(rt.wait_finished(std::chrono::seconds(30)));
  rt.join(std::chrono::seconds(1));
  EXPECT_GE(n.count("WATCHDOG=1"), 5);
  EXPECT_GE(n.count("STATUS="), 1);
}

namespace {

/// Starts `rt` and runs it to the end of its input: on this thread (`sync`), or waiting up to
/// `bound` for its threads to finish and join. Returns its exit code (-1: did not finish in time).
int run_to_the_end(Runtime& rt, bool sync, std::chrono::seconds bound) {
  rt.start();
  if (sync) return rt.run();
  if (!rt.wait_finished(bound) || !rt.join(std::chrono::seconds(2))) return -1;
  return rt.exit_code();
}

}  // namespace

// The daemon hands perception the odometry's pose of the very frame it works on, and perception
// carries the Manhattan frame seen earlier to the views of a fast turn whose own wall is a strip
// too narrow to make one (test_walk_manhattan checks those frames' yaw against the truth).
TEST(Runtime, ManhattanFrameIsCarriedByTheOdometryThroughAFastTurn) {
  // Under ThreadSanitizer only the threaded run: the one-thread run has no race to find and took
  // about 2 minutes of CI's TSan stage (110 frames of every stage); the Release suite runs both.
#if defined(__SANITIZE_THREAD__)
  const std::vector<bool> modes = {false};
#else
  const std::vector<bool> modes = {false, true};
#endif
  for (const bool sync : modes) {
    Lines lines;
    RuntimeOptions o;
    o.input = "synth:ascending_turn_fast:300:20261123";
    o.synchronous = sync;
    o.max_frames = 110;  // past the turn (frames 97-104 see only a strip of wall)
    o.frame_lines = true;
    o.frame_out = lines.f;
    Runtime rt(quiet_config(), o, nullptr);
    // 110 frames of the full pipeline took past 120 s under ThreadSanitizer with parallel builds
    // loading the 2 cores: the bound says "finishes", not how fast.
    ASSERT_EQ(run_to_the_end(rt, sync, std::chrono::seconds(400)), 0);
    int seen = 0, carried = 0;
    for (const auto& kv : lines.parse()) {
      seen += kv.at("manhattan") == "seen";
      carried += kv.at("manhattan") == "carried";
    }
    std::printf("%s: Manhattan frame seen on %d frames, carried on %d\n", sync ? "one thread" : "threaded",
                seen, carried);
    // Measured on one thread: seen on 5 frames, carried on 71 (the turn, and the glance away
    // before it; 7 and 69 when this test was written). Threaded, perception skips to the newest
    // frame, so how many of the few frames with a whole wall it works on depends on the machine's
    // load: 4 in a CI run, 5 at rest.
    EXPECT_GE(seen, sync ? 5 : 1) << (sync ? "one thread" : "threaded");
    EXPECT_GE(carried, sync ? 50 : 1) << (sync ? "one thread" : "threaded");
  }
}

// ---- issue 41 ----

namespace {

/// What the daemon logs while alive, for the assertions on its warnings.
struct LogCapture {
  std::ostringstream os;
  std::shared_ptr<spdlog::sinks::ostream_sink_mt> sink = std::make_shared<spdlog::sinks::ostream_sink_mt>(os);
  LogCapture() { spdlog::default_logger()->sinks().push_back(sink); }
  ~LogCapture() {
    auto& v = spdlog::default_logger()->sinks();
    v.erase(std::remove(v.begin(), v.end(), sink), v.end());
  }
  std::string text() {
    spdlog::default_logger()->flush();
    return os.str();
  }
};

/// The decisions of a run's frame lines: every field but the times measured on the machine (and
/// `ts`, compared apart).
std::vector<std::string> decisions(const std::vector<std::map<std::string, std::string>>& lines) {
  std::vector<std::string> out;
  for (auto kv : lines) {
    for (const char* k : {"ts", "latency_ms", "odom_ms", "perception_ms"}) kv.erase(k);
    std::string l;
    for (const auto& [k, v] : kv) l += k + "=" + v + " ";
    out.push_back(l);
  }
  return out;
}

std::vector<std::map<std::string, std::string>> run_sync(FloorSource::Behaviour b, const PipelineConfig& c,
                                                         Runtime** rt_out = nullptr) {
  Lines lines;
  Runtime rt(c, replay_options(b, false, true, lines.f), nullptr);
  if (rt_out) *rt_out = &rt;
  rt.start();
  EXPECT_EQ(rt.run(), 0);
  if (rt_out) *rt_out = nullptr;
  return lines.parse();
}

}  // namespace

// 50 reloads of an unchanged config in a second, just before a flight, delayed "first step" by 25
// frames: each restarted the odometry's track and perception's memory. A reload of the same config
// now changes nothing: the run's decisions are those of a run without reloads, frame for frame.
TEST(Runtime, ABurstOfReloadsOfTheSameConfigChangesNothing) {
  FloorSource::Behaviour b;
  b.frames = 80;
  const PipelineConfig c = quiet_config();
  const auto clean = run_sync(b, c);
  Runtime* rt = nullptr;
  int reloads = 0, applied = 0;
  b.on_read = [&](long i) {
    if (i < 20 || i >= 45 || !rt) return;
    for (int k = 0; k < 2; ++k, ++reloads) applied += rt->reconfigure(c);  // 2 per frame: 50 in all
  };
  const auto stormed = run_sync(b, c, &rt);
  EXPECT_EQ(reloads, 50);
  EXPECT_EQ(applied, 0) << "an unchanged config was applied";
  ASSERT_EQ(stormed.size(), clean.size());
  const auto a = decisions(clean), d = decisions(stormed);
  for (std::size_t i = 0; i < a.size(); ++i) EXPECT_EQ(d[i], a[i]) << "frame " << i;
  // A changed config is still applied (generation 2 from the frame after it).
  PipelineConfig changed = c;
  changed.segmentation.voxel_size = 0.05f;
  b.on_read = [&](long i) {
    if (i == 30 && rt) applied += rt->reconfigure(changed);
  };
  const auto reloaded = run_sync(b, c, &rt);
  EXPECT_EQ(applied, 1);
  ASSERT_EQ(reloaded.size(), 80u);
  EXPECT_EQ(reloaded[29].at("cfg"), "1");
  EXPECT_EQ(reloaded[31].at("cfg"), "2");
}

// A reload that changes only what the odometry does not read keeps its track: the step count
// holds its staircase in the odometry's world.
TEST(Runtime, AReloadOfAnotherSectionDoesNotRestartTheOdometry) {
  PipelineConfig c = quiet_config();
  OdometryStage odometry(c);
  PipelineConfig louder = c;
  louder.runtime.log_level = "info";
  louder.feedback.verbosity = "verbose";
  louder.segmentation.voxel_size = 0.05f;
  EXPECT_FALSE(odometry.reconfigure(louder));
  louder.odometry.iterations += 1;
  EXPECT_TRUE(odometry.reconfigure(louder));
}

TEST(FrameClock, UntrustworthyTimestampsAreReplacedByAMonotoneClock) {
  FrameClock k(0.1);
  EXPECT_EQ(k.next(5.0).t, 5.0);
  EXPECT_EQ(k.next(5.1).t, 5.1);
  FrameTime t = k.next(0.2);  // the clock jumps back 4.9 s
  EXPECT_TRUE(t.replaced);
  EXPECT_NEAR(t.t, 5.2, 1e-12);
  EXPECT_NE(t.why.find("goes back 4.900 s"), std::string::npos) << t.why;
  t = k.next(0.3);  // the frames after it keep their spacing from there
  EXPECT_FALSE(t.replaced);
  EXPECT_NEAR(t.t, 5.3, 1e-12);
  t = k.next(0.3);
  EXPECT_TRUE(t.replaced);
  EXPECT_NE(t.why.find("equals the previous frame's"), std::string::npos) << t.why;
  EXPECT_NEAR(t.t, 5.4, 1e-12);
  for (double bad : {1e300, std::nan(""), -std::numeric_limits<double>::infinity()}) {
    const double before = t.t;
    t = k.next(bad);
    EXPECT_TRUE(t.replaced) << bad;
    EXPECT_NEAR(t.t, before + 0.1, 1e-12) << bad;
  }
  t = k.next(0.7);  // 0.4 s after the last usable time (three frames had none)
  EXPECT_FALSE(t.replaced);
  EXPECT_NEAR(t.t, 5.7 + 0.1, 1e-9);
  t = k.next(100.0);  // a leap forward beyond the bound
  EXPECT_TRUE(t.replaced);
  EXPECT_NE(t.why.find("jumps 99.300 s forward"), std::string::npos) << t.why;
  // A live camera that really stalled 5 s is believed: the wall clock says so too.
  t = k.next(105.0, 5.02);
  EXPECT_FALSE(t.replaced) << t.why;
  t = k.next(104.0, 0.033);  // a live clock that jumps back: the wall-clock step is used
  EXPECT_TRUE(t.replaced);
  EXPECT_EQ(k.replaced(), 7u);
}

// Frame timestamps that cannot be trusted (issue 41: a clock that jumps back 5 s counted 6 of 8
// steps, equal ones failed the odometry on 288 of 450 frames, 1e300 silenced the cues; all with exit
// 0 and no warning). Each is replaced by the frame clock with a warning naming the frame, and the
// run's decisions are those of the same frames with a good clock.
TEST(Runtime, UntrustworthyTimestampsAreWarnedAndTheRunIsThatOfAGoodClock) {
  FloorSource::Behaviour b;
  b.frames = 60;
  const PipelineConfig c = quiet_config();
  const auto clean = decisions(run_sync(b, c));
  struct Case {
    const char* name;
    std::function<double(long)> ts;
    std::uint64_t replaced;
    const char* warning;
  };
  const Case cases[] = {
      {"jumps back 5 s", [](long i) { return i / 30.0 - (i >= 30 ? 5.0 : 0.0); }, 1,
       "frame 30 (#30 of the run): timestamp -4 goes back 4.967 s"},
      {"equal", [](long) { return 12.5; }, 59,
       "frame 1 (#1 of the run): timestamp 12.5 equals the previous frame's"},
      {"reversed", [](long i) { return 100.0 - i / 30.0; }, 59, "frame 1 (#1 of the run): timestamp"},
      {"1e300", [](long i) { return i == 30 ? 1e300 : i / 30.0; }, 1,
       "frame 30 (#30 of the run): timestamp 1e+300 is not a time"},
      {"NaN from frame 30", [](long i) { return i >= 30 ? std::nan("") : i / 30.0; }, 30,
       "frame 30 (#30 of the run): timestamp nan is not a finite number"},
  };
  for (const Case& k : cases) {
    LogCapture log;
    b.ts = k.ts;
    Lines lines;
    Runtime rt(c, replay_options(b, false, true, lines.f), nullptr);
    rt.start();
    EXPECT_EQ(rt.run(), 0) << k.name;
    const auto l = lines.parse();
    ASSERT_EQ(l.size(), 60u) << k.name;
    for (std::size_t i = 1; i < l.size(); ++i) {
      const double dt = std::stod(l[i].at("ts")) - std::stod(l[i - 1].at("ts"));
      EXPECT_GT(dt, 0.0) << k.name << " frame " << i;
      EXPECT_LE(dt, 1.0 / 30.0 + 2e-6) << k.name << " frame " << i;
    }
    EXPECT_EQ(rt.stats().timestamps_replaced, k.replaced) << k.name;
    EXPECT_EQ(decisions(l), clean) << k.name;
    const std::string text = log.text();
    EXPECT_NE(text.find(k.warning), std::string::npos) << k.name << ":\n" << text;
    EXPECT_NE(text.find("frames had a timestamp that could not be trusted"), std::string::npos) << text;
  }
}

// A live camera's clock that jumps back (a USB reset) is replaced by the wall-clock step.
TEST(Runtime, ALiveCameraWhoseClockJumpsBackKeepsAMonotoneTime) {
  Lines lines;
  RuntimeOptions o;
  o.input = "device";
  o.synchronous = true;
  o.max_frames = 30;
  o.frame_lines = true;
  o.frame_out = lines.f;
  o.open_source = [](const std::string&, const CaptureConfig&) -> std::unique_ptr<FrameSource> {
    FloorSource::Behaviour b;
    b.live = true;
    b.ts = [](long i) { return 1000.0 + i / 30.0 - (i >= 15 ? 600.0 : 0.0); };
    return std::make_unique<FloorSource>(b);
  };
  LogCapture log;
  Runtime rt(quiet_config(), o, nullptr);
  rt.start();
  EXPECT_EQ(rt.run(), 0);
  const auto l = lines.parse();
  ASSERT_EQ(l.size(), 30u);
  for (std::size_t i = 1; i < l.size(); ++i)
    EXPECT_GT(std::stod(l[i].at("ts")), std::stod(l[i - 1].at("ts")));
  EXPECT_EQ(rt.stats().timestamps_replaced, 1u);
  EXPECT_NE(log.text().find("frame 15 (#15 of the run): timestamp 400.5 goes back"), std::string::npos)
      << log.text();
}

// A thread that cannot be started is named as such; it read "cannot open input".
TEST(Runtime, AThreadThatCannotStartIsNamedAndIsNotTheInput) {
  FloorSource::Behaviour b;
  b.frames = 100000;
  RuntimeOptions o = replay_options(b, true, false, nullptr);
  o.start_thread = [](const char* name, std::function<void()> body) {
    if (std::string(name) == "perception")
      throw std::system_error(EAGAIN, std::generic_category(), "pthread_create");
    return std::thread(std::move(body));
  };
  Runtime rt(quiet_config(), o, nullptr);
  try {
    rt.start();
    FAIL() << "started without its perception thread";
  } catch (const SourceError& e) {
    FAIL() << "a thread that cannot start reads as the input's fault: " << e.what();
  } catch (const StartError& e) {
    EXPECT_NE(
        std::string(e.what()).find("cannot start the perception thread: pthread_create: Resource temporarily "
                                   "unavailable"),
        std::string::npos)
        << e.what();
  }
  EXPECT_TRUE(rt.join(std::chrono::milliseconds(2000))) << "the threads already started stop";
}

// Out of memory in a thread (`ulimit -v 256000`) ended the daemon through std::terminate with no
// log line. It is logged, the run fails (exit code 1) and the other threads stop.
TEST(Runtime, OutOfMemoryInAThreadIsLoggedAndFailsTheRun) {
  for (const bool sync : {false, true}) {
    LogCapture log;
    FloorSource::Behaviour b;
    b.frames = 100;
    b.bad_alloc_at = 10;
    Runtime rt(quiet_config(), replay_options(b, false, sync, nullptr), nullptr);
    EXPECT_EQ(run_to_the_end(rt, sync, std::chrono::seconds(30)), 1);
    EXPECT_EQ(rt.stats().state, "failed");
    const std::string text = log.text();
    EXPECT_NE(text.find(std::string(sync ? "pipeline (one thread)" : "capture") +
                        " thread failed: out of memory (std::bad_alloc)"),
              std::string::npos)
        << text;
  }
}

// A configuration the ranges allowed hid a 20 s lag (ring_capacity 1024, a slow odometry) while the
// status said latency 4.8 ms. Perception takes the newest frame, so its latency stays small; the age
// of the odometry's poses is measured and reported apart. In a replay as fast as the odometry goes,
// the frame ring stays full: each pose comes about a ringful of odometry steps after its capture.
TEST(Runtime, AnOdometryBehindTheCameraShowsInTheStatus) {
  FloorSource::Behaviour b;
  b.frames = 150;
  PipelineConfig c = quiet_config();
  c.runtime.ring_capacity = 1024;  // not loadable any more; held to 30 in code too
  c.runtime.status_interval = 0.1f;
  RecordingNotifier n;
  Runtime rt(c, replay_options(b, false, false, nullptr), &n);
  rt.start();
  ASSERT_TRUE(rt.wait_finished(std::chrono::seconds(120)));
  ASSERT_TRUE(rt.join(std::chrono::seconds(2)));
  const RuntimeStats s = rt.stats();
  std::printf(
      "odometry %.2f ms a frame, its poses p50 %.1f ms p99 %.1f ms max %.1f ms after capture; "
      "perception latency p50 %.1f ms\n",
      s.odometry_ms_mean, s.odometry_lag_p50_ms, s.odometry_lag_p99_ms, s.odometry_lag_max_ms,
      s.latency_p50_ms);
  EXPECT_GT(s.odometry_lag_p50_ms, 5.0 * s.odometry_ms_mean) << "the ring's wait shows";
  // At most a ringful (32 frames) waits before the odometry: 1024 held 20 s of them.
  EXPECT_LT(s.odometry_lag_max_ms, 60.0 * std::max(1.0, s.odometry_ms_mean) + 1000.0);
  EXPECT_GE(n.count("odometry lag p50"), 1);
  EXPECT_NE(s.summary().find("odometry lag p50"), std::string::npos) << s.summary();
}
