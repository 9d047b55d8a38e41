// The daemon's threads: capture -> (odometry || perception) -> feedback, joined by SPSC rings.
//
// Data moves only through the lock-free rings (spsc_ring.hpp). The mutex + condition variable
// pairs ("doorbells") carry no data: a thread that found its ring empty (or full) sleeps on one
// until the other side rings it or a short timeout passes, so no thread spins on the two shared
// cores. The only other locks guard the config hand-over on SIGHUP, the latest pose, and the
// counters snapshot. This file: start, run, stop, reload, the synchronous mode and the stats; the
// threads' loops are in runtime_capture.cpp, runtime_stages.cpp and runtime_sink.cpp.
#include "stairguide/runtime/runtime.hpp"

#include "runtime_internal.hpp"

namespace stairguide::runtime {

std::string RuntimeStats::summary() const {
  char buf[768];
  const double drop_pct = 100.0 * perception_drop_rate;
  std::snprintf(buf, sizeof buf,
                "%s: %llu frames, %.1f fps, odometry %llu (failed %llu, lost %llu), perception %llu "
                "(%.1f fps, skipped %llu = %.1f%%), latency p50 %.1f ms p99 %.1f ms, odometry lag p50 %.1f "
                "ms p99 %.1f ms, "
                "camera lost %llu, cfg %llu, timestamps replaced %llu, traversal %s step %d left %d known "
                "%d, cues %llu "
                "(lost %llu, last %s)",
                state.c_str(), static_cast<unsigned long long>(frames_captured), fps,
                static_cast<unsigned long long>(odometry_frames),
                static_cast<unsigned long long>(odometry_failures),
                static_cast<unsigned long long>(odometry_frames_lost),
                static_cast<unsigned long long>(perception_frames), perception_fps,
                static_cast<unsigned long long>(perception_skipped), drop_pct, latency_p50_ms, latency_p99_ms,
                odometry_lag_p50_ms, odometry_lag_p99_ms, static_cast<unsigned long long>(camera_losses),
                static_cast<unsigned long long>(config_generation),
                static_cast<unsigned long long>(timestamps_replaced), traversal_state.c_str(), traversal_step,
                traversal_left, traversal_known, static_cast<unsigned long long>(cues),
                static_cast<unsigned long long>(cues_lost), last_cue.empty() ? "-" : last_cue.c_str());
  return buf;
}

Runtime::Impl::Impl(const PipelineConfig& c, RuntimeOptions o, Notifier* n) : opt(std::move(o)), notifier(n) {
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

void Runtime::Impl::fail_worker(int w, const char* name, const char* why) noexcept {
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

void Runtime::Impl::finish(int w) {
  {
    std::lock_guard<std::mutex> lk(exit_mutex);
    done[w].store(true, std::memory_order_release);
  }
  exit_cv.notify_all();
  ring_all();
}

RuntimeStats Runtime::Impl::stats() const {
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
      m.threads[w] =
          m.opt.start_thread ? m.opt.start_thread(worker_name(w), loops[w]) : std::thread(loops[w]);
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
  m.guarded(
      kCapture, [&] { m.run_synchronous(gen); }, "pipeline (one thread)");
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
