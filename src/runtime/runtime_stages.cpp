// The odometry and perception threads: a frame in, a stage's output out, with the config
// generation they ran under; the odometry's poses by frame for perception's Manhattan carry; the
// watchdog from the perception loop.
#include "runtime_internal.hpp"

namespace stairguide::runtime {

void Runtime::Impl::apply_config(std::uint64_t& gen,
                                 const std::function<void(const PipelineConfig&)>& apply) {
  const std::uint64_t g = cfg_gen.load();
  if (g == gen) return;
  auto c = config();
  apply(*c);
  gen = g;
}

OdoMsg Runtime::Impl::run_odometry(const FramePacket& p) {
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

void Runtime::Impl::odometry_loop() {
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

PoseAnswer Runtime::Impl::odometry_pose_of(std::uint64_t seq, OdometryLink& link, bool wait) {
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

PercMsg Runtime::Impl::run_perception(const FramePacket& p, std::uint64_t gen) {
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

void Runtime::Impl::maybe_watchdog() {
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

void Runtime::Impl::perception_loop() {
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

}  // namespace stairguide::runtime
