// The capture thread (and the synchronous mode's reads): open the source, reopen a live camera
// with back-off, read, replace timestamps that cannot be trusted, pace a real-time replay, and
// hand every frame to the odometry and the newest to perception.
#include "runtime_internal.hpp"

namespace stairguide::runtime {

void Runtime::Impl::sleep_interruptible(Clock::duration d) {
  const auto until = Clock::now() + d;
  while (!stop.load() && Clock::now() < until) {
    beat(kCapture);
    const auto left = until - Clock::now();
    pace_bell.wait([&] { return stop.load(); }, std::min<Clock::duration>(left, Ms(200)));
  }
}

void Runtime::Impl::camera_lost(const std::string& why) {
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

NextFrame Runtime::Impl::next_frame(FramePacket& p) {
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
        spdlog::warn(
            "{}: {} of {} frames had a timestamp that could not be trusted and were timed by the "
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
    sleep_interruptible(std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(backoff)));
    backoff = std::min<double>(backoff * 2.0, cfg_now->capture.retry_max);
  }
  return NextFrame::kStopped;
}

void Runtime::Impl::check_timestamp(RgbdFrame& f, int fps) {
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
    spdlog::warn("{}: frame {} (#{} of the run): timestamp {} {}; timed {:.6f} s instead{}",
                 source->describe(), f.index, next_seq, raw, t.why, t.t,
                 n == 5  ? " (further ones are logged one in 100)"
                 : n > 5 ? " (" + std::to_string(n) + " so far)"
                         : "");
}

void Runtime::Impl::pace(double ts, int fps) {
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
    due = pace_t0 + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(ts - pace_ts0));
  }
  last_ts = ts;
  last_due = due;
  if (due > now) sleep_interruptible(due - now);
}

void Runtime::Impl::capture_loop() {
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

}  // namespace stairguide::runtime
