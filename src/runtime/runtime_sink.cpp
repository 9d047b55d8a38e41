// The feedback thread: decisions and cues from perception's results, the frame lines joining
// each frame's odometry and perception, camera lost/back, and the periodic STATUS report.
#include "runtime_internal.hpp"

namespace stairguide::runtime {

void Runtime::Impl::on_perception(PercMsg& m) {
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
                 logged_rig > 0 ? "relearned" : "learned", m.out.rig_height_m,
                 m.out.rig_tilt_rad * 57.29578f);
    logged_rig = m.out.rig_learned;
  }
  if (!d.cue.empty()) spdlog::info("frame {}: cue {}", m.out.seq, d.cue);
  perc_pending.push_back(std::move(m));
}

void Runtime::Impl::on_odometry(OdoMsg& m) {
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

void Runtime::Impl::print_line(const OdoMsg* o, const PercMsg* p) {
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
  std::fprintf(opt.frame_out,
               "frame=%llu ts=%.6f odom=%s perception=%s cfg=%llu latency_ms=%s odom_ms=%s perception_ms=%s "
               "manhattan=%s "
               "traversal=%s step=%d left=%d known=%d cue=%s\n",
               static_cast<unsigned long long>(seq), ts, odom.c_str(),
               p ? token(p->out.state).c_str() : "skipped",
               static_cast<unsigned long long>(p ? p->config_generation : cfg_gen.load()), lat, oms, pms,
               !p                         ? "-"
               : !p->out.manhattan_found  ? "none"
               : p->out.manhattan_carried ? "carried"
                                          : "seen",
               p && p->out.traversal.ran ? to_string(p->out.traversal.state) : "-",
               p ? p->out.traversal.step_index : 0, p ? p->out.traversal.steps_left : -1,
               p ? p->out.traversal.steps_known : 0, p && !p->cue.empty() ? p->cue.c_str() : "-");
  std::fflush(opt.frame_out);
}

void Runtime::Impl::emit_lines(std::uint64_t perc_taken, bool odo_finished, bool perc_finished) {
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

void Runtime::Impl::handle_camera_events() {
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

void Runtime::Impl::maybe_report(bool force) {
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
      state_name(get_state()), d(0) * inv, d(1) * inv, d(2) * inv, d(3), seen > 0 ? 100.0 * d(3) / seen : 0.0,
      d(4), p50, p99, lag50, lag99, static_cast<unsigned long long>(cur[0]),
      static_cast<unsigned long long>(cur[3]), static_cast<unsigned long long>(cur[4]),
      static_cast<unsigned long long>(cfg_gen.load()));
  // The step count and its cues are only as fresh as the odometry's poses.
  if (lag99 > kLagWarnMs)
    spdlog::warn(
        "odometry {:.1f} s behind the camera (p99 over the last {:.1f} s): step counts and their cues "
        "come that late; the machine is too slow for this frame size and rate",
        lag99 / 1000.0, dt);
  std::copy(cur, cur + 5, status_base);
  last_status = now;
  spdlog::info("{}", buf);
  notify(std::string("STATUS=") + buf);
}

void Runtime::Impl::sink_loop() {
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

}  // namespace stairguide::runtime
