#pragma once
// Internals of runtime::Runtime shared by its .cpp files (not part of the public API): the
// messages between the threads, their doorbells, and Runtime::Impl, whose members are defined
// by topic: runtime.cpp (start, run, stop, reload, the synchronous mode, stats),
// runtime_capture.cpp (the capture thread: open, read, reconnect, timestamps, pacing),
// runtime_stages.cpp (the odometry and perception threads), runtime_sink.cpp (the feedback
// thread: decisions, frame lines, camera events, STATUS reports).
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
#include "stairguide/runtime/runtime.hpp"
#include "stairguide/runtime/frame_clock.hpp"
#include "stairguide/runtime/latency.hpp"
#include "stairguide/runtime/logging.hpp"
#include "stairguide/runtime/pipeline.hpp"
#include "stairguide/runtime/spsc_ring.hpp"

namespace stairguide::runtime {

using Clock = std::chrono::steady_clock;
using Ms = std::chrono::milliseconds;

inline double seconds_between(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}
inline double ms_between(Clock::time_point a, Clock::time_point b) {
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
inline const char* state_name(State s) {
  switch (s) {
    case State::kStarting: return "starting";
    case State::kRunning: return "running";
    case State::kCameraLost: return "camera lost";
    case State::kEnded: return "ended";
    case State::kStopped: return "stopped";
    case State::kFailed: return "failed";
  }
  return "?";
}

enum Worker { kCapture = 0, kOdometry, kPerception, kSink, kWorkers };
inline const char* worker_name(int w) {
  static const char* names[] = {"capture", "odometry", "perception", "feedback"};
  return names[w];
}

inline std::string token(std::string s) {
  for (char& c : s)
    if (c == ' ' || c == '\t' || c == '=') c = '_';
  return s.empty() ? "-" : s;
}

enum class NextFrame { kFrame, kEnd, kError, kStopped };

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

  Impl(const PipelineConfig& c, RuntimeOptions o, Notifier* n);

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
  void sleep_interruptible(Clock::duration d);

  void set_input_desc(const std::string& d) {
    std::lock_guard<std::mutex> lk(desc_mutex);
    input_desc = d;
  }

  // ================================ capture ================================

  void camera_lost(const std::string& why);

  /// Opens (live: reopens with back-off) the source when needed and reads the next frame into
  /// `p`, paced for a real-time replay. Used by the capture thread and by synchronous mode.
  NextFrame next_frame(FramePacket& p);

  /// Frame times the stages can trust (frame_clock.hpp): a timestamp that is not finite, does not
  /// increase or leaps forward is replaced, with a warning naming the frame; the run goes on.
  /// A live camera's replacement step is the wall-clock time since the previous frame, a
  /// replay's one nominal frame period.
  void check_timestamp(RgbdFrame& f, int fps);

  /// Real-time replay: hold the frame until its timestamp comes due on the wall clock.
  void pace(double ts, int fps);

  void capture_loop();

  // ================================ odometry ================================

  void apply_config(std::uint64_t& gen, const std::function<void(const PipelineConfig&)>& apply);

  OdoMsg run_odometry(const FramePacket& p);

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

  void odometry_loop();

  // ================================ perception ================================

  /// The odometry's trusted pose of frame `seq`, with `wait` waiting up to kPoseWait for the
  /// odometry thread to reach it.
  static constexpr Ms kPoseWait{100};
  PoseAnswer odometry_pose_of(std::uint64_t seq, OdometryLink& link, bool wait);

  PercMsg run_perception(const FramePacket& p, std::uint64_t gen);

  /// WATCHDOG=1 when every other running thread has shown life recently: a thread stuck in a
  /// stage (or perception itself) stops the pings and systemd restarts the service.
  Clock::time_point last_watchdog{};
  void maybe_watchdog();

  void perception_loop();

  // ================================ feedback / reporting ================================

  int logged_rig = 0;  // PerceptionOutput::rig_learned last logged (feedback thread)

  std::uint64_t skipped_count() const { return perc_in.overwritten(); }
  std::uint64_t lost_count() const { return odo_in->dropped() + odo_lost_sync.load(); }

  void on_perception(PercMsg& m);

  void on_odometry(OdoMsg& m);

  void print_line(const OdoMsg* o, const PercMsg* p);

  /// Emits the frame lines that are complete: a frame's odometry result is in and perception
  /// has either reported on it or moved past it (skipped).
  void emit_lines(std::uint64_t perc_taken, bool odo_finished, bool perc_finished);

  void handle_camera_events();

  void maybe_report(bool force = false);

  static constexpr double kLagWarnMs = 1000.0;

  void sink_loop();

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

  void fail_worker(int w, const char* name, const char* why) noexcept;

  void finish(int w);

  void run_synchronous(std::uint64_t& gen);

  bool all_done() const {
    for (const auto& d : done)
      if (!d.load()) return false;
    return true;
  }

  RuntimeStats stats() const;
};

}  // namespace stairguide::runtime
