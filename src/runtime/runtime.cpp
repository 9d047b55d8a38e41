// The daemon's threads: capture -> (odometry || perception) -> feedback, joined by SPSC rings.
//
// Data moves only through the lock-free rings (spsc_ring.hpp). The mutex + condition variable
// pairs ("doorbells") carry no data: a thread that found its ring empty (or full) sleeps on one
// until the other side rings it or a short timeout passes, so no thread spins on the two shared
// cores. The only other locks guard the config hand-over on SIGHUP, the latest pose, and the
// counters snapshot.
#include "stairguide/runtime/runtime.hpp"

#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <condition_variable>
#include <deque>
#include <mutex>
#include <new>
#include <system_error>
#include <thread>

#include "stairguide/perception/perception.hpp"
#include "stairguide/runtime/frame_clock.hpp"
#include "stairguide/runtime/latency.hpp"
#include "stairguide/runtime/logging.hpp"
#include "stairguide/runtime/pipeline.hpp"
#include "stairguide/runtime/spsc_ring.hpp"

namespace stairguide::runtime {

namespace {

using Clock = std::chrono::steady_clock;
using Ms = std::chrono::milliseconds;

double seconds_between(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}
double ms_between(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

/// A frame on its way through the pipeline. The frame itself is shared, read-only, by the
/// odometry and perception threads.
struct FramePacket {
  std::shared_ptr<const RgbdFrame> frame;
  std::uint64_t seq = 0;
  Clock::time_point captured{};
  bool new_track = false;  ///< first frame after the source was (re)opened
};

struct OdoMsg {
  OdometryOutput out;
  double timestamp = 0.0;
  Clock::time_point captured{};
};

struct PercMsg {
  PerceptionOutput out;
  double timestamp = 0.0;
  Clock::time_point captured{};
  std::uint64_t config_generation = 1;
  double latency_ms = -1.0;  ///< capture -> decision, set when the decision is made
  std::string cue;           ///< cues given on this frame (feedback tokens), empty for none
};

/// Wake-up signal between two threads; carries no data.
class Doorbell {
 public:
  void ring() {
    { std::lock_guard<std::mutex> lk(m_); }  // orders the ring after a waiter's predicate check
    cv_.notify_all();
  }
  template <class Pred>
  void wait(Pred pred, Clock::duration timeout) {
    std::unique_lock<std::mutex> lk(m_);
    cv_.wait_for(lk, timeout, pred);
  }

 private:
  std::mutex m_;
  std::condition_variable cv_;
};

enum class State { kStarting, kRunning, kCameraLost, kEnded, kStopped, kFailed };
const char* state_name(State s) {
  switch (s) {
    case State::kStarting:
      return "starting";
    case State::kRunning:
      return "running";
    case State::kCameraLost:
      return "camera lost";
    case State::kEnded:
      return "ended";
    case State::kStopped:
      return "stopped";
    case State::kFailed:
      return "failed";
  }
  return "?";
}

enum Worker { kCapture = 0, kOdometry, kPerception, kSink, kWorkers };
const char* worker_name(int w) {
  static const char* names[] = {"capture", "odometry", "perception", "feedback"};
  return names[w];
}

std::string token(std::string s) {
  for (char& c : s)
    if (c == ' ' || c == '\t' || c == '=') c = '_';
  return s.empty() ? "-" : s;
}

enum class NextFrame { kFrame, kEnd, kError, kStopped };

}  // namespace

std::string RuntimeStats::summary() const {
  char buf[768];
  const double drop_pct = 100.0 * perception_drop_rate;
  std::snprintf(
      buf, sizeof buf,
      "%s: %llu frames, %.1f fps, odometry %llu (failed %llu, lost %llu), perception %llu "
      "(%.1f fps, skipped %llu = %.1f%%), latency p50 %.1f ms p99 %.1f ms, odometry lag p50 %.1f ms p99 %.1f ms, "
      "camera lost %llu, cfg %llu, timestamps replaced %llu, traversal %s step %d left %d known %d, cues %llu "
      "(lost %llu, last %s)",
      state.c_str(), static_cast<unsigned long long>(frames_captured), fps,
      static_cast<unsigned long long>(odometry_frames), static_cast<unsigned long long>(odometry_failures),
      static_cast<unsigned long long>(odometry_frames_lost),
      static_cast<unsigned long long>(perception_frames), perception_fps,
      static_cast<unsigned long long>(perception_skipped), drop_pct, latency_p50_ms, latency_p99_ms,
      odometry_lag_p50_ms, odometry_lag_p99_ms, static_cast<unsigned long long>(camera_losses),
      static_cast<unsigned long long>(config_generation), static_cast<unsigned long long>(timestamps_replaced),
      traversal_state.c_str(), traversal_step, traversal_left, traversal_known,
      static_cast<unsigned long long>(cues), static_cast<unsigned long long>(cues_lost),
      last_cue.empty() ? "-" : last_cue.c_str());
  return buf;
}

struct Runtime::Impl {
  RuntimeOptions opt;
  Notifier* notifier = nullptr;

  // ---- config hand-over (SIGHUP) ----
  mutable std::mutex cfg_mutex;
  std::shared_ptr<const PipelineConfig> cfg;
  std::atomic<std::uint64_t> cfg_gen{1};

  std::shared_ptr<const PipelineConfig> config() const {
    std::lock_guard<std::mutex> lk(cfg_mutex);
    return cfg;
  }

  // ---- source (owned by the capture thread once started) ----
  std::unique_ptr<FrameSource> source;
  bool live = false;
  mutable std::mutex desc_mutex;
  std::string input_desc;
  std::string failure;  ///< why a replay failed mid-way (desc_mutex)

  // ---- stages ----
  std::unique_ptr<OdometryStage> odometry;
  std::unique_ptr<PerceptionStage> perception;
  std::unique_ptr<FeedbackStage> feedback;

  // ---- queues and their doorbells ----
  std::unique_ptr<SpscRing<FramePacket>> odo_in;
  NewestSlot<FramePacket> perc_in;
  std::unique_ptr<SpscRing<OdoMsg>> odo_out;
  std::unique_ptr<SpscRing<PercMsg>> perc_out;
  Doorbell odo_in_bell, odo_in_space, perc_in_bell, sink_bell, sink_space, pace_bell;

  // ---- thread control ----
  std::thread threads[kWorkers];
  std::atomic<bool> done[kWorkers] = {};
  std::atomic<std::int64_t> heartbeat_ns[kWorkers] = {};
  std::atomic<bool> stop{false};
  std::mutex exit_mutex;
  std::condition_variable exit_cv;
  bool started = false;

  // ---- counters ----
  std::atomic<std::uint64_t> captured{0}, odo_frames{0}, odo_failures{0}, perc_frames{0}, decisions{0};
  std::atomic<std::uint64_t> camera_losses{0}, reconnects{0}, odo_lost_sync{0};
  std::atomic<std::uint64_t> perc_taken_seq{0};  ///< seq + 1 of the last frame perception took
  std::atomic<int> state{static_cast<int>(State::kStarting)};
  std::atomic<int> exit_code{0};
  std::atomic<int> camera_event{0};  ///< +1 per lost/back transition (odd = lost)
  std::mutex camera_why_mutex;
  std::string camera_why;
  std::atomic<double> odo_ms_sum{0.0}, perc_ms_sum{0.0};

  // ---- latency and times (sink thread writes, stats() reads) ----
  mutable std::mutex stats_mutex;
  LatencyHistogram latency, interval_latency;
  // Capture -> the odometry's result reaching the feedback thread: the age of the poses the
  // traversal works with. Perception takes the newest frame, so its latency stays small however
  // far the odometry has fallen behind (issue 41: 20 s behind with the status saying 4.8 ms).
  LatencyHistogram odo_lag, interval_odo_lag;
  Clock::time_point first_capture{}, last_decision{};
  bool have_first = false, have_last = false;
  TraversalResult last_traversal;  // of the last decision (stats_mutex)

  // ---- odometry poses by frame, odometry -> perception ----
  // Perception carries the Manhattan frame between views with the pose of the very frame it works
  // on (a pose a few frames old is degrees off in a turn); the odometry runs beside it on the same
  // frame, so the last kPoseLog poses are kept by frame number.
  struct PoseEntry {
    std::uint64_t seq = ~std::uint64_t{0};
    Pose T_world_camera = Pose::Identity();
    std::uint64_t track = 0;  // changes when the odometry's world does (a failure, a restart)
    bool ok = false;
  };
  static constexpr std::size_t kPoseLog = 64;
  std::mutex pose_mutex;
  std::condition_variable pose_cv;
  std::array<PoseEntry, kPoseLog> pose_log{};
  std::uint64_t odo_track = 0;
  std::uint64_t odo_next_seq = 0;  // every frame before this one has passed the odometry
  bool odo_restarted = false;      // odometry thread only: reconfigured, its next frame starts afresh

  // ---- capture state (capture thread, or the caller in synchronous mode) ----
  std::uint64_t next_seq = 0;
  bool new_track = true;
  bool pacing_started = false;
  double pace_ts0 = 0.0, last_ts = 0.0;
  Clock::time_point pace_t0{}, last_due{};
  double backoff = 0.0;
  bool camera_reported_lost = false;
  std::unique_ptr<FrameClock> frame_clock;  // created at the first frame (the source's nominal rate)
  Clock::time_point last_read{};
  std::atomic<std::uint64_t> ts_replaced{0};

  // ---- sink (feedback thread, or the caller in synchronous mode) ----
  std::deque<OdoMsg> odo_pending;
  std::deque<PercMsg> perc_pending;
  std::uint64_t odo_high = 0;  ///< seq + 1 of the newest odometry output seen
  bool ready_sent = false;
  int camera_event_seen = 0;
  Clock::time_point last_status{};
  std::uint64_t status_base[5] = {};  // captured, odo, perc, skipped, lost at the last report
  OdometryOutput last_odometry;
  bool have_last_odometry = false;

  Impl(const PipelineConfig& c, RuntimeOptions o, Notifier* n) : opt(std::move(o)), notifier(n) {
    cfg = std::make_shared<const PipelineConfig>(c);
    if (!opt.open_source)
      opt.open_source = [](const std::string& in, const CaptureConfig& cc) {
        return open_frame_source(in, cc);
      };
    live = opt.input.empty() || opt.input == "device" || opt.input.rfind("device:", 0) == 0;
    if (opt.input.empty()) opt.input = "device";
    // The loader holds ring_capacity to [2, 30]; a config made in code is held there too.
    const auto cap = static_cast<std::size_t>(std::clamp(c.runtime.ring_capacity, 2, 30));
    odo_in = std::make_unique<SpscRing<FramePacket>>(cap);
    // Result rings are only ever short (the feedback thread is light); a few times the frame
    // ring so a slow log write never stalls the stages.
    odo_out = std::make_unique<SpscRing<OdoMsg>>(4 * cap);
    perc_out = std::make_unique<SpscRing<PercMsg>>(4 * cap);
    odometry = std::make_unique<OdometryStage>(c);
    perception = std::make_unique<PerceptionStage>(c);
    feedback = std::make_unique<FeedbackStage>(c);
    backoff = c.capture.retry_min;
    for (auto& h : heartbeat_ns) h.store(now_ns());
  }

  static std::int64_t now_ns() {
    return std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now().time_since_epoch()).count();
  }
  void beat(int w) { heartbeat_ns[w].store(now_ns(), std::memory_order_relaxed); }
  void notify(const std::string& s) {
    if (notifier) notifier->notify(s);
  }
  void set_state(State s) { state.store(static_cast<int>(s)); }
  State get_state() const { return static_cast<State>(state.load()); }

  void ring_all() {
    odo_in_bell.ring();
    odo_in_space.ring();
    perc_in_bell.ring();
    sink_bell.ring();
    sink_space.ring();
    pace_bell.ring();
  }

  /// Sleeps up to `d`, waking early on stop; keeps the capture heartbeat fresh.
  void sleep_interruptible(Clock::duration d) {
    const auto until = Clock::now() + d;
    while (!stop.load() && Clock::now() < until) {
      beat(kCapture);
      const auto left = until - Clock::now();
      pace_bell.wait([&] { return stop.load(); }, std::min<Clock::duration>(left, Ms(200)));
    }
  }

  void set_input_desc(const std::string& d) {
    std::lock_guard<std::mutex> lk(desc_mutex);
    input_desc = d;
  }

  // ================================ capture ================================

  void camera_lost(const std::string& why) {
    if (!camera_reported_lost) {
      camera_reported_lost = true;
      camera_losses.fetch_add(1);
      {
        std::lock_guard<std::mutex> lk(camera_why_mutex);
        camera_why = why;
      }
      camera_event.fetch_add(1);
      set_state(State::kCameraLost);
      sink_bell.ring();
    }
  }

  /// Opens (live: reopens with back-off) the source when needed and reads the next frame into
  /// `p`, paced for a real-time replay. Used by the capture thread and by synchronous mode.
  NextFrame next_frame(FramePacket& p) {
    auto cfg_now = config();
    while (!stop.load()) {
      beat(kCapture);
      if (!source) {
        // Only a live camera gets here: a replay was opened by start().
        try {
          source = opt.open_source(opt.input, cfg_now->capture);
          set_input_desc(source->describe());
          new_track = true;
          backoff = cfg_now->capture.retry_min;
          if (camera_reported_lost) {
            camera_reported_lost = false;
            reconnects.fetch_add(1);
            camera_event.fetch_add(1);
            spdlog::info("camera back: {}", source->describe());
          } else {
            spdlog::info("camera open: {}", source->describe());
          }
          if (get_state() == State::kCameraLost) set_state(State::kRunning);
        } catch (const std::exception& e) {
          camera_lost(e.what());
          spdlog::warn("camera not available: {}; retrying in {:.2f} s", e.what(), backoff);
          sleep_interruptible(
              std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(backoff)));
          backoff = std::min<double>(backoff * 2.0, cfg_now->capture.retry_max);
          cfg_now = config();  // a reload may have changed the device settings meanwhile
          continue;
        }
      }
      auto frame = std::make_shared<RgbdFrame>();
      const ReadResult r = source->read(*frame);
      beat(kCapture);
      if (r.ok()) {
        check_timestamp(*frame, cfg_now->capture.fps);
        if (!live && opt.realtime) pace(frame->timestamp, cfg_now->capture.fps);
        if (stop.load()) return NextFrame::kStopped;
        p.captured = Clock::now();
        p.seq = next_seq++;
        p.new_track = new_track;
        new_track = false;
        p.frame = std::move(frame);
        return NextFrame::kFrame;
      }
      if (r.status == ReadStatus::kEnd) {
        spdlog::info("{}: end of input{}{}", source->describe(), r.message.empty() ? "" : ": ", r.message);
        if (ts_replaced.load() > 0)
          spdlog::warn("{}: {} of {} frames had a timestamp that could not be trusted and were timed by the "
                       "frame clock instead",
                       source->describe(), ts_replaced.load(), next_seq);
        return NextFrame::kEnd;
      }
      if (!live) {
        const std::string why = r.message.empty() ? source->describe() + ": read failed" : r.message;
        spdlog::error("{}", why);
        std::lock_guard<std::mutex> lk(desc_mutex);
        failure = source->describe() + ": frame " + std::to_string(next_seq) + " cannot be read: " + why;
        return NextFrame::kError;
      }
      // Live camera stopped sending or vanished: tell the user, close it, reopen with back-off.
      const std::string why = r.message.empty() ? source->describe() + ": no frame" : r.message;
      spdlog::warn("camera lost: {}; reconnecting (back-off {:.2f} .. {:.2f} s)", why,
                   cfg_now->capture.retry_min, cfg_now->capture.retry_max);
      camera_lost(why);
      source.reset();
      sleep_interruptible(
          std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(backoff)));
      backoff = std::min<double>(backoff * 2.0, cfg_now->capture.retry_max);
    }
    return NextFrame::kStopped;
  }

  /// Frame times the stages can trust (frame_clock.hpp): a timestamp that is not finite, does not
  /// increase or leaps forward is replaced, with a warning naming the frame; the run goes on.
  /// A live camera's replacement step is the wall-clock time since the previous frame, a
  /// replay's one nominal frame period.
  void check_timestamp(RgbdFrame& f, int fps) {
    const auto now = Clock::now();
    if (!frame_clock) frame_clock = std::make_unique<FrameClock>(1.0 / std::max(1, fps));
    const double wall = live && last_read != Clock::time_point{} ? seconds_between(last_read, now) : -1.0;
    last_read = now;
    const double raw = f.timestamp;
    const FrameTime t = frame_clock->next(raw, wall);
    f.timestamp = t.t;
    if (!t.replaced) return;
    const std::uint64_t n = ts_replaced.fetch_add(1) + 1;
    // Every frame of a recording with equal timestamps would warn: the first few, then one in 100.
    if (n <= 5 || n % 100 == 0)
      spdlog::warn("{}: frame {} (#{} of the run): timestamp {} {}; timed {:.6f} s instead{}", source->describe(),
                   f.index, next_seq, raw, t.why, t.t,
                   n == 5 ? " (further ones are logged one in 100)" : n > 5 ? " (" + std::to_string(n) + " so far)" : "");
  }

  /// Real-time replay: hold the frame until its timestamp comes due on the wall clock.
  void pace(double ts, int fps) {
    const auto now = Clock::now();
    const auto period =
        std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / std::max(1, fps)));
    Clock::time_point due;
    // First frame, timestamps that do not increase (none in the recording), or a gap of more
    // than 2 s: restart the clock one frame period after the previous frame.
    if (!pacing_started || !(ts > last_ts) || ts - last_ts > 2.0) {
      due = pacing_started ? last_due + period : now;
      pace_t0 = due;
      pace_ts0 = ts;
      pacing_started = true;
    } else {
      due =
          pace_t0 + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(ts - pace_ts0));
    }
    last_ts = ts;
    last_due = due;
    if (due > now) sleep_interruptible(due - now);
  }

  void capture_loop() {
    spdlog::debug("capture thread up");
    const bool replay = !live;
    for (;;) {
      if (opt.max_frames >= 0 && static_cast<long>(next_seq) >= opt.max_frames) {
        set_state(State::kEnded);
        break;
      }
      FramePacket p;
      const NextFrame n = next_frame(p);
      if (n == NextFrame::kEnd) {
        set_state(State::kEnded);
        break;
      }
      if (n == NextFrame::kError) {
        exit_code.store(1);
        set_state(State::kFailed);
        break;
      }
      if (n == NextFrame::kStopped) break;
      captured.fetch_add(1);
      {
        std::lock_guard<std::mutex> lk(stats_mutex);
        if (!have_first) {
          have_first = true;
          first_capture = p.captured;
        }
      }
      if (get_state() == State::kStarting) set_state(State::kRunning);
      // Perception gets the newest frame (overwriting one it has not taken: counted there).
      FramePacket for_perception = p;
      perc_in.publish(std::move(for_perception));
      perc_in_bell.ring();
      // Odometry gets every frame. A replay waits for room; a live camera cannot wait (the
      // driver would drop frames unseen), so there the frame is dropped and counted.
      if (replay) {
        while (!odo_in->try_push(p) && !stop.load()) {
          beat(kCapture);
          odo_in_space.wait([&] { return !odo_in->full() || stop.load(); }, Ms(100));
        }
      } else {
        odo_in->push_or_drop(std::move(p));
      }
      odo_in_bell.ring();
      if (stop.load()) break;
    }
    source.reset();  // closes the device / recording on this thread
    finish(kCapture);
  }

  // ================================ odometry ================================

  void apply_config(std::uint64_t& gen, const std::function<void(const PipelineConfig&)>& apply) {
    const std::uint64_t g = cfg_gen.load();
    if (g == gen) return;
    auto c = config();
    apply(*c);
    gen = g;
  }

  OdoMsg run_odometry(const FramePacket& p) {
    if (p.new_track && p.seq != 0) odometry->restart();
    OdoMsg m;
    m.out = odometry->step(*p.frame);
    m.out.seq = p.seq;
    if (opt.pose_filter) opt.pose_filter(*p.frame, m.out);
    m.timestamp = p.frame->timestamp;
    m.captured = p.captured;
    odo_frames.fetch_add(1);
    if (m.out.ran && !m.out.ok) odo_failures.fetch_add(1);
    add_atomic(odo_ms_sum, m.out.ms);
    if (m.out.ran) {
      {
        std::lock_guard<std::mutex> lk(pose_mutex);
        // A restart (a new track, a new config) begins a new world: the motion up to its first
        // frame is not measured. A failed frame's pose is a guess, and what follows it is not
        // known to be in the same world as what came before.
        if (p.new_track || odo_restarted || !m.out.ok) ++odo_track;
        odo_restarted = false;
        pose_log[p.seq % kPoseLog] = {p.seq, m.out.T_world_camera, odo_track, m.out.ok};
        odo_next_seq = std::max(odo_next_seq, p.seq + 1);
      }
      pose_cv.notify_all();
    }
    return m;
  }

  static void add_atomic(std::atomic<double>& a, double v) {
    double cur = a.load(std::memory_order_relaxed);
    while (!a.compare_exchange_weak(cur, cur + v, std::memory_order_relaxed)) {
    }
  }

  template <class T>
  void push_result(SpscRing<T>& ring, T& msg, int worker) {
    while (!ring.try_push(msg)) {
      if (stop.load()) return;
      beat(worker);
      sink_space.wait([&] { return !ring.full() || stop.load(); }, Ms(100));
    }
    sink_bell.ring();
  }

  void odometry_loop() {
    std::uint64_t gen = 1;
    for (;;) {
      beat(kOdometry);
      if (stop.load()) break;
      const bool capture_finished = done[kCapture].load(std::memory_order_acquire);
      FramePacket p;
      if (!odo_in->try_pop(p)) {
        if (capture_finished) break;
        odo_in_bell.wait([&] { return !odo_in->empty() || done[kCapture].load() || stop.load(); }, Ms(100));
        continue;
      }
      odo_in_space.ring();
      apply_config(gen, [&](const PipelineConfig& c) {
        if (odometry->reconfigure(c)) odo_restarted = true;
      });
      OdoMsg m = run_odometry(p);
      p.frame.reset();
      push_result(*odo_out, m, kOdometry);
    }
    finish(kOdometry);
  }

  // ================================ perception ================================

  /// The odometry's trusted pose of frame `seq`, with `wait` waiting up to kPoseWait for the
  /// odometry thread to reach it.
  static constexpr Ms kPoseWait{100};
  PoseAnswer odometry_pose_of(std::uint64_t seq, OdometryLink& link, bool wait) {
    std::unique_lock<std::mutex> lk(pose_mutex);
    const auto deadline = Clock::now() + kPoseWait;
    for (;;) {
      const PoseEntry& e = pose_log[seq % kPoseLog];
      if (e.seq == seq) {
        if (!e.ok) return PoseAnswer::kNever;
        link.T_world_camera = e.T_world_camera;
        link.track = e.track;
        return PoseAnswer::kReady;
      }
      // Passed (dropped, or so long ago that the log has moved on), or no odometry any more.
      if (odo_next_seq > seq || done[kOdometry].load() || stop.load()) return PoseAnswer::kNever;
      if (!wait || pose_cv.wait_until(lk, deadline) == std::cv_status::timeout) return PoseAnswer::kNotYet;
    }
  }

  PercMsg run_perception(const FramePacket& p, std::uint64_t gen) {
    PercMsg m;
    // A machine too slow for the camera, played (RuntimeOptions::perception_delay_s): the stage is
    // held before it runs, as a busy CPU would hold it.
    if (opt.perception_delay_s > 0.0)
      std::this_thread::sleep_for(std::chrono::duration<double>(opt.perception_delay_s));
    m.out = perception->step(*p.frame, p.seq, [this](std::uint64_t seq, OdometryLink& link, bool wait) {
      return odometry_pose_of(seq, link, wait);
    });
    m.out.seq = p.seq;
    m.timestamp = p.frame->timestamp;
    m.captured = p.captured;
    m.config_generation = gen;
    perc_frames.fetch_add(1);
    add_atomic(perc_ms_sum, m.out.ms);
    return m;
  }

  /// WATCHDOG=1 when every other running thread has shown life recently: a thread stuck in a
  /// stage (or perception itself) stops the pings and systemd restarts the service.
  Clock::time_point last_watchdog{};
  void maybe_watchdog() {
    const auto now = Clock::now();
    const std::uint64_t wd = notifier ? notifier->watchdog_usec() : 0;
    const auto period = wd ? std::chrono::microseconds(wd / 4) : std::chrono::microseconds(1000000);
    if (now - last_watchdog < period) return;
    const auto c = config();
    const double limit_s = std::max(3.0, wd * 1e-6 / 2.0);
    const double capture_limit_s = limit_s + c->capture.read_timeout;
    const std::int64_t t = now_ns();
    for (int w = 0; w < kWorkers; ++w) {
      if (w == kPerception || done[w].load()) continue;
      const double age = (t - heartbeat_ns[w].load(std::memory_order_relaxed)) * 1e-9;
      if (age > (w == kCapture ? capture_limit_s : limit_s)) {
        spdlog::error("{} thread silent for {:.1f} s: withholding the watchdog", worker_name(w), age);
        last_watchdog = now;
        return;
      }
    }
    last_watchdog = now;
    notify("WATCHDOG=1");
  }

  void perception_loop() {
    std::uint64_t gen = 1;
    for (;;) {
      beat(kPerception);
      maybe_watchdog();
      if (stop.load()) break;
      const bool capture_finished = done[kCapture].load(std::memory_order_acquire);
      FramePacket p;
      if (!perc_in.take(p)) {
        if (capture_finished) break;
        perc_in_bell.wait([&] { return perc_in.has_new() || done[kCapture].load() || stop.load(); }, Ms(100));
        continue;
      }
      apply_config(gen, [&](const PipelineConfig& c) { perception->reconfigure(c); });
      perc_taken_seq.store(p.seq + 1, std::memory_order_release);
      PercMsg m = run_perception(p, gen);
      p.frame.reset();
      push_result(*perc_out, m, kPerception);
    }
    finish(kPerception);
  }

  // ================================ feedback / reporting ================================

  int logged_rig = 0;  // PerceptionOutput::rig_learned last logged (feedback thread)

  std::uint64_t skipped_count() const { return perc_in.overwritten(); }
  std::uint64_t lost_count() const { return odo_in->dropped() + odo_lost_sync.load(); }

  void on_perception(PercMsg& m) {
    const OdometryOutput* odo = have_last_odometry ? &last_odometry : nullptr;
    const Decision d = feedback->decide(m.out, odo, m.timestamp, m.captured);
    m.cue = d.cue;
    const auto now = Clock::now();
    const double lat = ms_between(m.captured, now);
    m.latency_ms = lat;
    {
      std::lock_guard<std::mutex> lk(stats_mutex);
      latency.add(lat);
      interval_latency.add(lat);
      last_decision = now;
      have_last = true;
      if (m.out.traversal.ran) last_traversal = m.out.traversal;
    }
    decisions.fetch_add(1);
    if (d.changed) spdlog::info("frame {}: state {} ({})", m.out.seq, d.state, m.out.detail);
    if (m.out.rig_learned != logged_rig && m.out.rig_height_m > 0.f) {
      // Learned from the first clear views, relearned when the wearer sits down or remounts the
      // rig: where the floor is looked for from now on.
      spdlog::info("frame {}: rig {}: the camera {:.2f} m above the floor, tilted {:.0f} deg down", m.out.seq,
                   logged_rig > 0 ? "relearned" : "learned", m.out.rig_height_m, m.out.rig_tilt_rad * 57.29578f);
      logged_rig = m.out.rig_learned;
    }
    if (!d.cue.empty()) spdlog::info("frame {}: cue {}", m.out.seq, d.cue);
    perc_pending.push_back(std::move(m));
  }

  void on_odometry(OdoMsg& m) {
    const double lag = ms_between(m.captured, Clock::now());
    {
      std::lock_guard<std::mutex> lk(stats_mutex);
      odo_lag.add(lag);
      interval_odo_lag.add(lag);
    }
    odo_high = std::max(odo_high, m.out.seq + 1);
    last_odometry = m.out;
    have_last_odometry = true;
    odo_pending.push_back(std::move(m));
  }

  void print_line(const OdoMsg* o, const PercMsg* p) {
    if (!ready_sent) {
      ready_sent = true;
      spdlog::info("first frame through the pipeline");
      notify("STATUS=running: first frame through");
    }
    if (!opt.frame_lines || !opt.frame_out) return;
    const std::uint64_t seq = o ? o->out.seq : p->out.seq;
    const double ts = o ? o->timestamp : p->timestamp;
    std::string odom;
    if (!o)
      odom = "lost";
    else if (!o->out.ran)
      odom = "none";
    else
      odom = o->out.ok ? "ok" : "fail:" + token(o->out.status);
    char lat[32] = "-", pms[32] = "-", oms[32] = "-";
    if (p) {
      std::snprintf(lat, sizeof lat, "%.2f", p->latency_ms);
      std::snprintf(pms, sizeof pms, "%.2f", p->out.ms);
    }
    if (o) std::snprintf(oms, sizeof oms, "%.2f", o->out.ms);
    std::fprintf(
        opt.frame_out,
        "frame=%llu ts=%.6f odom=%s perception=%s cfg=%llu latency_ms=%s odom_ms=%s perception_ms=%s manhattan=%s "
        "traversal=%s step=%d left=%d known=%d cue=%s\n",
        static_cast<unsigned long long>(seq), ts, odom.c_str(), p ? token(p->out.state).c_str() : "skipped",
        static_cast<unsigned long long>(p ? p->config_generation : cfg_gen.load()), lat, oms, pms,
        !p ? "-" : !p->out.manhattan_found ? "none" : p->out.manhattan_carried ? "carried" : "seen",
        p && p->out.traversal.ran ? to_string(p->out.traversal.state) : "-", p ? p->out.traversal.step_index : 0,
        p ? p->out.traversal.steps_left : -1, p ? p->out.traversal.steps_known : 0,
        p && !p->cue.empty() ? p->cue.c_str() : "-");
    std::fflush(opt.frame_out);
  }

  /// Emits the frame lines that are complete: a frame's odometry result is in and perception
  /// has either reported on it or moved past it (skipped).
  void emit_lines(std::uint64_t perc_taken, bool odo_finished, bool perc_finished) {
    for (;;) {
      if (!odo_pending.empty()) {
        const OdoMsg& o = odo_pending.front();
        if (!perc_pending.empty()) {
          const PercMsg& p = perc_pending.front();
          if (p.out.seq == o.out.seq) {
            print_line(&o, &p);
            odo_pending.pop_front();
            perc_pending.pop_front();
          } else if (p.out.seq > o.out.seq) {
            print_line(&o, nullptr);
            odo_pending.pop_front();
          } else {
            print_line(nullptr, &p);
            perc_pending.pop_front();
          }
          continue;
        }
        if (o.out.seq + 1 < perc_taken || perc_finished) {  // perception took a later frame
          print_line(&o, nullptr);
          odo_pending.pop_front();
          continue;
        }
        return;
      }
      if (!perc_pending.empty()) {
        const PercMsg& p = perc_pending.front();
        if (p.out.seq < odo_high || odo_finished) {  // odometry never saw it (live overrun)
          print_line(nullptr, &p);
          perc_pending.pop_front();
          continue;
        }
      }
      return;
    }
  }

  void handle_camera_events() {
    const int ev = camera_event.load();
    if (ev == camera_event_seen) return;
    camera_event_seen = ev;
    if (ev % 2 == 1) {
      std::string why;
      {
        std::lock_guard<std::mutex> lk(camera_why_mutex);
        why = camera_why;
      }
      feedback->camera_lost(why);
      bool ever = false;  // a camera that never gave a frame is not lost: it is not there yet
      {
        std::lock_guard<std::mutex> lk(stats_mutex);
        ever = have_first;
      }
      notify(std::string(ever ? "STATUS=camera lost: " : "STATUS=waiting for camera: ") + why +
             "; reconnecting");
    } else {
      feedback->camera_back();
    }
  }

  void maybe_report(bool force = false) {
    const auto now = Clock::now();
    const auto c = config();
    if (last_status == Clock::time_point{}) last_status = now;
    const double dt = seconds_between(last_status, now);
    if (!force && dt < c->runtime.status_interval) return;
    const std::uint64_t cur[5] = {captured.load(), odo_frames.load(), perc_frames.load(), skipped_count(),
                                  lost_count()};
    double p50 = 0, p99 = 0, lag50 = 0, lag99 = 0;
    {
      std::lock_guard<std::mutex> lk(stats_mutex);
      p50 = interval_latency.percentile(50);
      p99 = interval_latency.percentile(99);
      interval_latency.clear();
      lag50 = interval_odo_lag.percentile(50);
      lag99 = interval_odo_lag.percentile(99);
      interval_odo_lag.clear();
    }
    const double inv = dt > 0 ? 1.0 / dt : 0.0;
    const auto d = [&](int i) { return static_cast<double>(cur[i] - status_base[i]); };
    const double seen = d(2) + d(3);
    char buf[640];
    std::snprintf(
        buf, sizeof buf,
        "%s: capture %.1f fps, odometry %.1f fps, perception %.1f fps, skipped %.0f (%.1f%%), lost %.0f, "
        "latency p50 %.1f ms p99 %.1f ms, odometry lag p50 %.1f ms p99 %.1f ms, totals %llu frames %llu "
        "skipped %llu lost, cfg %llu",
        state_name(get_state()), d(0) * inv, d(1) * inv, d(2) * inv, d(3),
        seen > 0 ? 100.0 * d(3) / seen : 0.0, d(4), p50, p99, lag50, lag99, static_cast<unsigned long long>(cur[0]),
        static_cast<unsigned long long>(cur[3]), static_cast<unsigned long long>(cur[4]),
        static_cast<unsigned long long>(cfg_gen.load()));
    // The step count and its cues are only as fresh as the odometry's poses.
    if (lag99 > kLagWarnMs)
      spdlog::warn("odometry {:.1f} s behind the camera (p99 over the last {:.1f} s): step counts and their cues "
                   "come that late; the machine is too slow for this frame size and rate",
                   lag99 / 1000.0, dt);
    std::copy(cur, cur + 5, status_base);
    last_status = now;
    spdlog::info("{}", buf);
    notify(std::string("STATUS=") + buf);
  }

  static constexpr double kLagWarnMs = 1000.0;

  void sink_loop() {
    std::uint64_t gen = 1;
    for (;;) {
      beat(kSink);
      // Read the progress marks before draining the rings: whatever a finished (or moved on)
      // stage pushed before setting them is then visible in the rings.
      const bool odo_finished = done[kOdometry].load(std::memory_order_acquire);
      const bool perc_finished = done[kPerception].load(std::memory_order_acquire);
      const std::uint64_t perc_taken = perc_taken_seq.load(std::memory_order_acquire);
      apply_config(gen, [&](const PipelineConfig& c) { feedback->reconfigure(c); });
      bool got = false;
      OdoMsg om;
      while (odo_out->try_pop(om)) {
        got = true;
        on_odometry(om);
      }
      PercMsg pm;
      while (perc_out->try_pop(pm)) {
        got = true;
        on_perception(pm);
      }
      if (got) sink_space.ring();
      emit_lines(perc_taken, odo_finished, perc_finished);
      handle_camera_events();
      feedback->poll();  // the wearer's button, answered whether frames come or not
      maybe_report();
      if (stop.load()) break;
      if (odo_finished && perc_finished && odo_out->empty() && perc_out->empty()) {
        emit_lines(perc_taken, true, true);
        feedback->drain(Ms(3000));  // the input ended: let the last cues be heard
        break;
      }
      if (!got) {
        sink_bell.wait(
            [&] {
              return !odo_out->empty() || !perc_out->empty() || stop.load() ||
                     (done[kOdometry].load() && done[kPerception].load());
            },
            Ms(50));
      }
    }
    finish(kSink);
  }

  /// Runs a worker's loop. What escapes it (out of memory under a tight limit, a library's
  /// exception) is logged, fails the run and stops every thread: uncaught, it ended the process
  /// through std::terminate with no log line (issue 41, under `ulimit -v 256000`).
  template <class F>
  void guarded(int w, F&& loop, const char* name = nullptr) {
    try {
      loop();
      return;
    } catch (const std::bad_alloc&) {
      fail_worker(w, name, kOutOfMemory);
    } catch (const std::exception& e) {
      fail_worker(w, name, e.what());
    } catch (...) {
      fail_worker(w, name, "an unknown exception");
    }
  }
  static constexpr const char* kOutOfMemory =
      "out of memory (std::bad_alloc): the memory limit (ulimit -v, the unit's MemoryMax=) is too small "
      "for the pipeline at this frame size";

  void fail_worker(int w, const char* name, const char* why) noexcept {
    if (!name) name = worker_name(w);
    try {
      spdlog::critical("{} thread failed: {}; stopping", name, why);
      notify(std::string("STATUS=failed: ") + name + " thread: " + why);
    } catch (...) {
      // Logging itself ran out of memory: say it without allocating.
      static const char msg[] = "stairguided: a thread failed (out of memory?); stopping\n";
      [[maybe_unused]] const auto n = ::write(2, msg, sizeof msg - 1);
    }
    exit_code.store(1);
    set_state(State::kFailed);
    stop.store(true);
    if (!done[w].load()) finish(w);
    ring_all();
  }

  void finish(int w) {
    {
      std::lock_guard<std::mutex> lk(exit_mutex);
      done[w].store(true, std::memory_order_release);
    }
    exit_cv.notify_all();
    ring_all();
  }

  void run_synchronous(std::uint64_t& gen);

  bool all_done() const {
    for (const auto& d : done)
      if (!d.load()) return false;
    return true;
  }

  RuntimeStats stats() const {
    RuntimeStats s;
    s.state = state_name(get_state());
    s.frames_captured = captured.load();
    s.odometry_frames = odo_frames.load();
    s.odometry_failures = odo_failures.load();
    s.odometry_frames_lost = lost_count();
    s.perception_frames = perc_frames.load();
    s.perception_skipped = skipped_count();
    s.decisions = decisions.load();
    s.camera_losses = camera_losses.load();
    s.reconnects = reconnects.load();
    s.config_generation = cfg_gen.load();
    const double seen = static_cast<double>(s.perception_frames + s.perception_skipped);
    s.perception_drop_rate = seen > 0 ? static_cast<double>(s.perception_skipped) / seen : 0.0;
    s.odometry_ms_mean = s.odometry_frames ? odo_ms_sum.load() / static_cast<double>(s.odometry_frames) : 0.0;
    s.perception_ms_mean =
        s.perception_frames ? perc_ms_sum.load() / static_cast<double>(s.perception_frames) : 0.0;
    std::lock_guard<std::mutex> lk(stats_mutex);
    s.latency_p50_ms = latency.percentile(50);
    s.latency_p99_ms = latency.percentile(99);
    s.latency_max_ms = latency.max();
    s.odometry_lag_p50_ms = odo_lag.percentile(50);
    s.odometry_lag_p99_ms = odo_lag.percentile(99);
    s.odometry_lag_max_ms = odo_lag.max();
    s.timestamps_replaced = ts_replaced.load();
    const FeedbackStage::CueLatency cl = feedback->cue_latency();
    s.cues = cl.cues;
    s.cues_sounded = cl.sounded;
    s.cue_latency_p50_ms = cl.p50_ms;
    s.cue_latency_p99_ms = cl.p99_ms;
    s.last_cue = cl.last;
    s.cues_lost = cl.lost;
    s.cue_kinds = cl.by_kind;
    if (have_first && have_last) s.elapsed_s = std::max(0.0, seconds_between(first_capture, last_decision));
    if (last_traversal.ran) {
      s.traversal_state = to_string(last_traversal.state);
      s.traversal_step = last_traversal.step_index;
      s.traversal_left = last_traversal.steps_left;
      s.traversal_known = last_traversal.steps_known;
    }
    if (s.elapsed_s > 0) {
      s.fps = static_cast<double>(s.odometry_frames) / s.elapsed_s;
      s.perception_fps = static_cast<double>(s.perception_frames) / s.elapsed_s;
    }
    return s;
  }
};

// ================================ public interface ================================

Runtime::Runtime(const PipelineConfig& config, RuntimeOptions options, Notifier* notifier)
    : impl_(std::make_unique<Impl>(config, std::move(options), notifier)) {}

Runtime::~Runtime() {
  request_stop();
  for (auto& t : impl_->threads)
    if (t.joinable()) t.join();
}

void Runtime::start() {
  Impl& m = *impl_;
  if (m.started) return;
  m.started = true;
  const auto c = m.config();
  spdlog::info("stages: odometry={} perception={} feedback={}", m.odometry->describe(),
               m.perception->describe(), m.feedback->describe());
  if (!m.live) {
    // A replay must open now: a missing or corrupt recording is an error at start, not a retry.
    m.source = m.opt.open_source(m.opt.input, c->capture);
    m.set_input_desc(m.source->describe());
    const long n = m.source->frame_count();
    spdlog::info("replaying {} ({} frames, {}, {})", m.source->describe(),
                 n < 0 ? std::string("?") : std::to_string(n),
                 m.opt.realtime ? "real time" : "as fast as possible",
                 m.opt.synchronous ? "one thread" : "threaded");
  } else {
    m.set_input_desc(m.opt.input);
    spdlog::info("live input {} ({})", m.opt.input, m.opt.synchronous ? "one thread" : "threaded");
  }
  // READY=1 once the config is loaded, the replay opened and the threads are up, not after the
  // first frame: without a camera plugged in that would never come, and `systemctl start`
  // would wait for it. STATUS says what the daemon waits for.
  const std::string ready = "READY=1\nSTATUS=" + (m.live ? "waiting for camera " + m.opt.input
                                                         : "replaying " + m.source->describe());
  if (m.opt.synchronous) {
    m.notify(ready);
    return;
  }
  // A thread that cannot be had (out of threads or memory) is its own error, not the input's: it
  // read "cannot open input" (issue 41). The ones already started are stopped (and joined by the
  // destructor).
  const std::function<void()> loops[kWorkers] = {
      [&m] { m.guarded(kCapture, [&m] { m.capture_loop(); }); },
      [&m] { m.guarded(kOdometry, [&m] { m.odometry_loop(); }); },
      [&m] { m.guarded(kPerception, [&m] { m.perception_loop(); }); },
      [&m] { m.guarded(kSink, [&m] { m.sink_loop(); }); }};
  for (int w = 0; w < kWorkers; ++w) {
    try {
      m.threads[w] = m.opt.start_thread ? m.opt.start_thread(worker_name(w), loops[w]) : std::thread(loops[w]);
    } catch (const std::exception& e) {
      request_stop();
      throw StartError(std::string("cannot start the ") + worker_name(w) + " thread: " + e.what());
    }
  }
  m.notify(ready);
}

int Runtime::run() {
  Impl& m = *impl_;
  if (!m.started) start();
  if (!m.opt.synchronous) {
    while (!wait_finished(Ms(1000))) {
    }
    join(Ms(60000));
    return exit_code();
  }
  // Synchronous mode: the same stages in order on this thread, every frame through each.
  std::uint64_t gen = 1;
  m.guarded(kCapture, [&] { m.run_synchronous(gen); }, "pipeline (one thread)");
  if (m.done[kCapture].load()) {  // failed (guarded logged it): nothing more to play
    m.source.reset();
    for (auto& d : m.done) d.store(true);
    return exit_code();
  }
  m.emit_lines(m.next_seq, true, true);
  if (!m.stop.load()) m.feedback->drain(Ms(3000));  // the input ended: let the last cues be heard
  m.source.reset();
  for (auto& d : m.done) d.store(true);
  return exit_code();
}

void Runtime::Impl::run_synchronous(std::uint64_t& gen) {
  Impl& m = *this;
  for (;;) {
    if (m.opt.max_frames >= 0 && static_cast<long>(m.next_seq) >= m.opt.max_frames) {
      m.set_state(State::kEnded);
      break;
    }
    FramePacket p;
    const NextFrame n = m.next_frame(p);
    if (n == NextFrame::kEnd) {
      m.set_state(State::kEnded);
      break;
    }
    if (n == NextFrame::kError) {
      m.exit_code.store(1);
      m.set_state(State::kFailed);
      break;
    }
    if (n == NextFrame::kStopped) break;
    m.captured.fetch_add(1);
    {
      std::lock_guard<std::mutex> lk(m.stats_mutex);
      if (!m.have_first) {
        m.have_first = true;
        m.first_capture = p.captured;
      }
    }
    if (m.get_state() == State::kStarting) m.set_state(State::kRunning);
    m.apply_config(gen, [&](const PipelineConfig& c) {
      if (m.odometry->reconfigure(c)) m.odo_restarted = true;
      m.perception->reconfigure(c);
      m.feedback->reconfigure(c);
    });
    OdoMsg om = m.run_odometry(p);
    m.perc_taken_seq.store(p.seq + 1);
    PercMsg pm = m.run_perception(p, gen);
    m.on_odometry(om);
    m.on_perception(pm);
    if (m.opt.observer)
      m.opt.observer({*p.frame, *m.source, m.odo_pending.back().out, m.perc_pending.back().out,
                      m.perception->last_scene(), m.perception->last_stair(), m.perc_pending.back().cue});
    m.emit_lines(p.seq + 1, false, false);
    m.handle_camera_events();
    m.feedback->poll();
    m.beat(kOdometry);
    m.beat(kSink);
    m.maybe_watchdog();
    m.maybe_report();
  }
}

bool Runtime::finished() const { return impl_->all_done(); }

bool Runtime::wait_finished(std::chrono::milliseconds timeout) {
  Impl& m = *impl_;
  if (m.opt.synchronous) return m.all_done();
  std::unique_lock<std::mutex> lk(m.exit_mutex);
  return m.exit_cv.wait_for(lk, timeout, [&] { return m.all_done(); });
}

void Runtime::request_stop() {
  Impl& m = *impl_;
  if (!m.stop.exchange(true)) {
    const State s = m.get_state();
    if (s == State::kStarting || s == State::kRunning || s == State::kCameraLost)
      m.set_state(State::kStopped);
  }
  m.ring_all();
}

bool Runtime::join(std::chrono::milliseconds timeout) {
  Impl& m = *impl_;
  const auto deadline = Clock::now() + timeout;
  bool all = true;
  for (int w = 0; w < kWorkers; ++w) {
    auto& t = m.threads[w];
    if (!t.joinable()) continue;
    {
      std::unique_lock<std::mutex> lk(m.exit_mutex);
      m.exit_cv.wait_until(lk, deadline, [&] { return m.done[w].load(); });
    }
    if (m.done[w].load()) {
      t.join();
    } else {
      spdlog::error("{} thread did not stop within {} ms", worker_name(w), timeout.count());
      all = false;
    }
  }
  return all;
}

bool Runtime::reconfigure(const PipelineConfig& config) {
  Impl& m = *impl_;
  const auto old = m.config();
  // The same file reloaded (a SIGHUP storm, a `systemctl reload` to be sure): nothing to apply.
  // Taken, each reload restarted the odometry's track and perception's memory, and 50 of them
  // before a flight delayed "first step" by 25 frames (issue 41).
  if (config_equal(*old, config)) return false;
  {
    std::lock_guard<std::mutex> lk(m.cfg_mutex);
    m.cfg = std::make_shared<const PipelineConfig>(config);
    m.cfg_gen.fetch_add(1);
  }
  if (!set_log_level(config.runtime.log_level))
    spdlog::warn("unknown log level '{}'", config.runtime.log_level);
  if (old->runtime.ring_capacity != config.runtime.ring_capacity)
    spdlog::warn("runtime.ring_capacity changes at the next start (now {})", old->runtime.ring_capacity);
  std::string diff;
  PipelineConfig a = *old, b = config;
  a.runtime = b.runtime;
  a.feedback = b.feedback;
  a.odometry = b.odometry;
  if (m.live && !config_equal(a, b, &diff) && diff.rfind("capture.", 0) == 0)
    spdlog::info("capture settings apply when the camera is next opened ({})", diff);
  m.ring_all();
  return true;
}

RuntimeStats Runtime::stats() const { return impl_->stats(); }

int Runtime::exit_code() const { return impl_->exit_code.load(); }

std::string Runtime::failure() const {
  std::lock_guard<std::mutex> lk(impl_->desc_mutex);
  return impl_->failure;
}

std::string Runtime::describe_input() const {
  std::lock_guard<std::mutex> lk(impl_->desc_mutex);
  return impl_->input_desc;
}

}  // namespace stairguide::runtime
