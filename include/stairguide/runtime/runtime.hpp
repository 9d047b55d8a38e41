#pragma once
/// \file runtime.hpp
/// The daemon's runtime: the only place with threads.
///
/// Threaded mode: a capture thread reads the source and hands each frame to
///   - the odometry thread through a FIFO `SpscRing` (odometry sees every frame; a live camera that
///     outruns it has the excess counted as `odometry_frames_lost`, a replay waits instead), and
///   - the perception thread through a `NewestSlot` (perception always takes the newest frame; the
///     frames it never saw are counted as `perception_skipped`),
/// and the feedback thread joins both result streams (SPSC rings), makes the decision, measures
/// capture-to-decision latency, prints the per-frame lines, and reports the counters (log + STATUS)
/// every `runtime.status_interval`. READY=1 goes out from start() once the input is open (a
/// replay) and the threads are up, with STATUS= "waiting for camera" on the live path (a camera
/// may be plugged in much later); WATCHDOG=1 from the perception loop while every thread is alive.
///
/// Synchronous mode: the same stages, in order, on the calling thread, every frame through every
/// stage (tests, offline replay).
///
/// A live camera that stops sending is reopened with exponential back-off
/// (`capture.retry_min` .. `capture.retry_max`); a replay ends at the end of its recording.

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>

#include "stairguide/capture/frame_source.hpp"
#include "stairguide/core/config.hpp"
#include "stairguide/runtime/latency.hpp"
#include "stairguide/runtime/notifier.hpp"
#include "stairguide/runtime/pipeline.hpp"

namespace stairguide::runtime {

/// Runtime::start() could not start a thread (out of threads or memory): not the input's fault.
struct StartError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// Opens an input by name (default: open_frame_source). Throws SourceError.
using SourceFactory =
    std::function<std::unique_ptr<FrameSource>(const std::string& input, const CaptureConfig&)>;

/// One frame as synchronous mode ran it through every stage, for an observer (offline replay
/// writes its files from these). The references are valid only during the call.
struct FrameObservation {
  const RgbdFrame& frame;
  const FrameSource& source;           ///< the input: truth() of this frame, frame_count()
  const OdometryOutput& odometry;      ///< after RuntimeOptions::pose_filter
  const PerceptionOutput& perception;  ///< with the traversal result
  const SceneResult& scene;            ///< perception's scene of this frame, after the Manhattan carry
  const StairResult& stair;            ///< the stairs stage's full result
  const std::string& cue;              ///< the cues decided on this frame ("" none)
};

struct RuntimeOptions {
  /// Input for open_frame_source: "device" / "device:URI" for the live camera (the default),
  /// or a replay (.oni file, dataset folder, "synth:SCENE[:FRAMES[:SEED]]").
  std::string input = "device";
  /// Replay pacing: true = by the frames' timestamps (as the camera would deliver them),
  /// false = as fast as the pipeline goes. Ignored for a live camera.
  bool realtime = true;
  /// One thread, every stage on every frame, in order.
  bool synchronous = false;
  /// Print one line per frame to `frame_out` (the default for a replay).
  bool frame_lines = false;
  std::FILE* frame_out = stdout;
  /// Stop after this many frames (-1: until the input ends or stop is requested).
  long max_frames = -1;
  SourceFactory open_source;  ///< empty: open_frame_source
  /// Called on the odometry's thread with each frame's odometry output before any stage uses its
  /// pose (offline replay injects drift with it). Empty: none.
  std::function<void(const RgbdFrame&, OdometryOutput&)> pose_filter;
  /// Synchronous mode only: called on the calling thread once a frame has been through every
  /// stage and the feedback decision. An exception it throws ends run() and reaches its caller.
  std::function<void(const FrameObservation&)> observer;
  /// s each frame is held before perception runs: plays a machine that cannot keep up with the
  /// camera (perception falls behind, "slow" is told) in end-to-end tests. 0: none.
  double perception_delay_s = 0.0;
  /// Starts worker thread `name` running `body` (empty: std::thread). A seam for tests of a
  /// thread that cannot be started; throws what std::thread throws.
  std::function<std::thread(const char* name, std::function<void()> body)> start_thread;
};

/// Counters of a run. Rates are over the whole run unless named `interval_`.
struct RuntimeStats {
  std::string state;  ///< "starting", "running", "camera lost", "ended", "stopped", "failed"
  std::uint64_t frames_captured = 0;
  std::uint64_t odometry_frames = 0;       ///< frames odometry processed
  std::uint64_t odometry_failures = 0;     ///< frames whose estimate was not trusted
  std::uint64_t odometry_frames_lost = 0;  ///< captured frames odometry never saw (live overrun)
  std::uint64_t perception_frames = 0;     ///< frames perception processed
  std::uint64_t perception_skipped = 0;    ///< frames perception skipped to stay on the newest
  std::uint64_t decisions = 0;             ///< frames through to the feedback decision
  std::uint64_t camera_losses = 0;         ///< times the camera stopped sending
  std::uint64_t reconnects = 0;            ///< times it came back
  std::uint64_t config_generation = 1;     ///< 1 at start, +1 per applied reload
  double elapsed_s = 0.0;                  ///< from the first frame captured to the last decision
  double fps = 0.0;                        ///< frames through odometry per second over elapsed_s
  double perception_fps = 0.0;
  double perception_drop_rate = 0.0;  ///< skipped / (processed + skipped)
  double latency_p50_ms = 0.0;        ///< capture -> feedback decision
  double latency_p99_ms = 0.0;
  double latency_max_ms = 0.0;
  /// Capture -> the odometry's result at the feedback thread: how old the poses the step count
  /// works with are (a slow odometry shows here; perception always takes the newest frame).
  double odometry_lag_p50_ms = 0.0;
  double odometry_lag_p99_ms = 0.0;
  double odometry_lag_max_ms = 0.0;
  /// Frames whose timestamp could not be trusted (not finite, not increasing, a leap) and were
  /// timed by the frame clock instead (frame_clock.hpp).
  std::uint64_t timestamps_replaced = 0;
  double odometry_ms_mean = 0.0;  ///< mean time in the odometry stage
  double perception_ms_mean = 0.0;
  std::uint64_t cues = 0;           ///< cues given to the user (feedback)
  std::uint64_t cues_sounded = 0;   ///< of them, started on the sound device
  std::uint64_t cues_lost = 0;      ///< of them, never played: the sound device could not take them
  double cue_latency_p50_ms = 0.0;  ///< capture of the frame warranting a cue -> its first sample out
  double cue_latency_p99_ms = 0.0;
  std::string last_cue;                   ///< token of the last cue ("" none)
  std::vector<CueKindLatency> cue_kinds;  ///< the cue latency per cue kind (FeedbackStage)
  /// The traversal as of the last decision (issue 32): state token, step the user stands on,
  /// steps left (-1 unknown), steps known.
  std::string traversal_state = "-";
  int traversal_step = 0, traversal_left = -1, traversal_known = 0;
  /// The systemd STATUS= text / log line for these counters.
  std::string summary() const;
};

class Runtime {
 public:
  /// Does not open anything yet. `notifier` may be null (nothing announced); it must outlive the
  /// runtime.
  Runtime(const PipelineConfig& config, RuntimeOptions options, Notifier* notifier);
  ~Runtime();  ///< stops and joins (no deadline)
  Runtime(const Runtime&) = delete;
  Runtime& operator=(const Runtime&) = delete;

  /// Opens a replay input (throws SourceError naming it when it cannot: a missing or corrupt
  /// recording); a live camera is opened by the capture thread, which keeps retrying.
  /// In threaded mode then starts the threads and returns at once.
  void start();

  /// Synchronous mode: start() must have been called; runs until the input ends, max_frames, or
  /// request_stop(). Returns the exit code (as exit_code()).
  int run();

  /// True once every thread has finished (input ended, max_frames, error or stop).
  bool finished() const;
  /// Blocks until finished() or the timeout; true when finished.
  bool wait_finished(std::chrono::milliseconds timeout);

  /// Asks every thread to stop (thread-safe, returns at once).
  void request_stop();
  /// Joins the threads, waiting at most `timeout` for each to come back; true when all were
  /// joined. A thread blocked in a device read longer than that is left running (false): the
  /// caller should then exit the process.
  bool join(std::chrono::milliseconds timeout);

  /// Hands a new, already validated config to the stages (each applies it between two frames).
  /// Capture settings take effect at the next (re)open; ring capacities at the next start.
  /// A config equal to the running one changes nothing (no new generation, no stage touched) and
  /// returns false: a burst of reloads of the same file must not perturb the count on a flight.
  bool reconfigure(const PipelineConfig& config);

  /// Snapshot of the counters (any thread, any time).
  RuntimeStats stats() const;

  /// 0 when the input ended cleanly or stop was requested, 1 when a replay failed mid-way (an
  /// unreadable frame) or a thread failed (out of memory: logged).
  int exit_code() const;
  /// Why a replay failed mid-way, naming the input and the frame ("" when it did not).
  std::string failure() const;

  /// The input as the source describes it (after start()).
  std::string describe_input() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace stairguide::runtime
