#include <alsa/asoundlib.h>
#include <pthread.h>
#include <sched.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdarg>

#include "stairguide/runtime/devices/alsa_audio_sink.hpp"

namespace stairguide::runtime::devices {

using feedback::Delivery;
using feedback::kSoundRate;
using feedback::pan_gains;
using feedback::Utterance;

namespace {
snd_pcm_t* as_pcm(void* p) { return static_cast<snd_pcm_t*>(p); }
// libasound prints its own errors to stderr; the sink reports through its events instead.
void quiet_alsa(const char*, int, const char*, int, const char*, ...) {}
// At stop, what is playing or queued may go on this long (drain() first to hear everything).
constexpr auto kStopGrace = std::chrono::milliseconds(300);
// Earcons sounding at once; beyond, the oldest is dropped (they are tens of ms long).
constexpr std::size_t kMaxMix = 4;
// The thread's real-time priority (SCHED_FIFO), as the buzzer's: a cue handed a chunk late on a
// busy 2-core laptop is a tick out of step.
constexpr int kRealtimePriority = 10;
}  // namespace

AlsaAudioSink::AlsaAudioSink(AlsaSinkOptions options, feedback::SoundBank bank, AudioEvents events)
    : opt_(std::move(options)), bank_(std::move(bank)), ev_(std::move(events)) {
  opt_.chunk_frames = std::max(16u, opt_.chunk_frames);
  snd_lib_error_set_handler(quiet_alsa);
  thread_ = std::thread([this] { run(); });
}

AlsaAudioSink::~AlsaAudioSink() {
  {
    std::lock_guard<std::mutex> lk(m_);
    stop_ = true;
    stop_deadline_ = SteadyClock::now() + kStopGrace;
  }
  cv_.notify_all();
  if (thread_.joinable()) thread_.join();
  close_device();
}

std::string AlsaAudioSink::describe() const { return "alsa:" + opt_.device; }

AlsaAudioSink::Counters AlsaAudioSink::counters() const {
  std::lock_guard<std::mutex> lk(m_);
  return counters_;
}

AlsaAudioSink::Voice AlsaAudioSink::voice_of(const Utterance& u,
                                             const std::vector<std::string>& clips) const {
  Voice v;
  v.id = u.id;
  v.priority = u.priority;
  v.kinds = u.kinds;
  for (const auto& c : clips)
    if (const auto* s = bank_.find(c)) v.samples.insert(v.samples.end(), s->begin(), s->end());
  if (channels_ == 2)
    pan_gains(u.pan, v.gl, v.gr);
  else
    v.gl = v.gr = 1.f;
  return v;
}

void AlsaAudioSink::enqueue_locked(Utterance u) {
  const auto at =
      std::find_if(queue_.begin(), queue_.end(), [&](const Utterance& q) { return q.priority < u.priority; });
  queue_.insert(at, std::move(u));
  if (queue_.size() > opt_.max_queue) {
    queue_.pop_back();
    ++counters_.stale;
  }
}

void AlsaAudioSink::start_locked(Utterance& u, std::vector<std::uint64_t>& /*started*/) {
  Voice v = voice_of(u, u.clips);
  if (v.samples.empty()) return;  // nothing to hear (its clips are missing): not counted
  ++counters_.played;
  if (u.delivery == Delivery::kMix) {
    if (mix_.size() >= kMaxMix) mix_.erase(mix_.begin());
    mix_.push_back(std::move(v));
  } else {
    if (!speech_.empty()) ++counters_.cut;
    speech_.assign(1, std::move(v));
  }
}

void AlsaAudioSink::promote_locked(SteadyClock::time_point now) {
  for (auto it = queue_.begin(); it != queue_.end();) {
    if (now - it->queued > std::chrono::duration<double>(it->max_wait_s)) {
      it = queue_.erase(it);
      ++counters_.stale;
    } else {
      ++it;
    }
  }
  if (!open_) return;
  std::vector<std::uint64_t> none;
  for (auto it = queue_.begin(); it != queue_.end();) {
    if (it->delivery == Delivery::kMix) {
      start_locked(*it, none);
      it = queue_.erase(it);
    } else {
      ++it;
    }
  }
  if (speech_.empty() && !queue_.empty()) {
    Utterance u = std::move(queue_.front());
    queue_.pop_front();
    start_locked(u, none);
  }
}

void AlsaAudioSink::play(Utterance u) {
  {
    std::lock_guard<std::mutex> lk(m_);
    const auto now = SteadyClock::now();
    u.queued = now;
    if (u.max_wait_s < 0) u.max_wait_s = opt_.max_age_s;
    if (u.supersedes != 0) {
      // What the new one makes stale: never heard late, nor finished over it.
      for (auto it = queue_.begin(); it != queue_.end();) {
        if (it->kinds & u.supersedes) {
          it = queue_.erase(it);
          ++counters_.stale;
          ++counters_.superseded;
        } else {
          ++it;
        }
      }
      if (!speech_.empty() && (speech_[0].kinds & u.supersedes)) {
        speech_.clear();
        ++counters_.cut;
      }
    }
    std::vector<std::uint64_t> none;
    if (!open_) {
      enqueue_locked(std::move(u));
    } else if (u.delivery == Delivery::kMix) {
      start_locked(u, none);
    } else if (u.delivery == Delivery::kCut) {
      if (speech_.empty() || speech_[0].priority <= u.priority) {
        start_locked(u, none);
      } else if (!u.fallback.empty()) {
        Utterance e = u;
        e.clips = u.fallback;
        e.delivery = Delivery::kMix;
        start_locked(e, none);
        ++counters_.fallbacks;
      } else {
        enqueue_locked(std::move(u));
      }
    } else {
      if (!speech_.empty() && u.priority > speech_[0].priority)
        start_locked(u, none);
      else
        enqueue_locked(std::move(u));
      promote_locked(now);
    }
  }
  cv_.notify_all();
}

bool AlsaAudioSink::drain(std::chrono::milliseconds timeout) {
  std::unique_lock<std::mutex> lk(m_);
  return cv_.wait_for(lk, timeout, [&] { return idle_locked(); });
}

bool AlsaAudioSink::open_device() {
  snd_pcm_t* p = nullptr;
  int e = 0;
  int channels = opt_.stereo ? 2 : 1;
  for (;;) {
    e = snd_pcm_open(&p, opt_.device.c_str(), SND_PCM_STREAM_PLAYBACK, SND_PCM_NONBLOCK);
    if (e < 0) break;
    e = snd_pcm_set_params(p, SND_PCM_FORMAT_S16_LE, SND_PCM_ACCESS_RW_INTERLEAVED,
                           static_cast<unsigned>(channels), kSoundRate, 1, opt_.latency_us);
    if (e >= 0) break;
    snd_pcm_close(p);
    p = nullptr;
    if (channels == 1) break;
    channels = 1;  // a mono device: served mono
  }
  std::lock_guard<std::mutex> lk(m_);
  if (e < 0) {
    ++counters_.open_failures;
    if (!failing_) {
      failing_ = true;
      if (ev_.warn)
        ev_.warn("audio: cannot open ALSA device '" + opt_.device + "': " + snd_strerror(e) +
                 "; going on without sound, retrying every " + std::to_string(opt_.retry_s) + " s");
    }
    counters_.device_open = false;
    return false;
  }
  pcm_ = p;
  open_ = true;
  channels_ = channels;
  failing_ = false;
  counters_.device_open = true;
  counters_.channels = channels;
  if (ev_.info)
    ev_.info("audio: ALSA device '" + opt_.device + "' open (16-bit " + (channels == 2 ? "stereo" : "mono") +
             " " + std::to_string(kSoundRate) + " Hz" +
             (opt_.stereo && channels == 1 ? ", the device refused two channels: cues are not panned" : "") +
             ")");
  return true;
}

void AlsaAudioSink::close_device() {
  if (!pcm_) return;
  snd_pcm_nonblock(as_pcm(pcm_), 0);
  snd_pcm_drain(as_pcm(pcm_));  // plays out the device buffer (at most ahead_s)
  snd_pcm_close(as_pcm(pcm_));
  pcm_ = nullptr;
  std::lock_guard<std::mutex> lk(m_);
  open_ = false;
  counters_.device_open = false;
  counters_.channels = 0;
}

void AlsaAudioSink::render_locked(std::vector<std::int16_t>& out, std::size_t frames,
                                  std::vector<std::uint64_t>& started) {
  const std::size_t ch = static_cast<std::size_t>(channels_);
  std::vector<std::int32_t> earcons(frames * ch, 0), speech(frames * ch, 0);
  std::vector<char> ducked(frames, 0);
  auto add = [&](Voice& v, std::vector<std::int32_t>& into, bool duck) {
    if (v.pos == 0) started.push_back(v.id);
    const std::size_t n = std::min(frames, v.samples.size() - v.pos);
    for (std::size_t i = 0; i < n; ++i) {
      const float s = v.samples[v.pos + i];
      if (duck) ducked[i] = 1;
      if (ch == 2) {
        into[2 * i] += static_cast<std::int32_t>(std::lround(s * v.gl));
        into[2 * i + 1] += static_cast<std::int32_t>(std::lround(s * v.gr));
      } else {
        into[i] += static_cast<std::int32_t>(s);
      }
    }
    v.pos += n;
  };
  for (auto& v : mix_) add(v, earcons, true);
  mix_.erase(
      std::remove_if(mix_.begin(), mix_.end(), [](const Voice& v) { return v.pos >= v.samples.size(); }),
      mix_.end());
  if (!speech_.empty()) {
    add(speech_[0], speech, false);
    if (speech_[0].pos >= speech_[0].samples.size()) speech_.clear();
  }
  out.resize(frames * ch);
  for (std::size_t i = 0; i < frames; ++i)
    for (std::size_t c = 0; c < ch; ++c) {
      const std::size_t k = i * ch + c;
      // Under an earcon the phrase is lowered 6 dB (the earcon stays clear), and the sum is
      // saturated: a mix that overflows is clipped, never wrapped round into a crack.
      const std::int32_t v = (ducked[i] ? speech[k] / 2 : speech[k]) + earcons[k];
      out[k] = static_cast<std::int16_t>(std::clamp<std::int32_t>(v, -32768, 32767));
    }
}

void AlsaAudioSink::run() {
  {
    sched_param sp{};
    sp.sched_priority = kRealtimePriority;
    const bool rt = pthread_setschedparam(pthread_self(), SCHED_FIFO, &sp) == 0;
    std::lock_guard<std::mutex> lk(m_);
    counters_.realtime = rt;
  }
  auto next_open = SteadyClock::now();
  const auto retry =
      std::chrono::duration_cast<SteadyClock::duration>(std::chrono::duration<double>(opt_.retry_s));
  SteadyClock::time_point t0{};
  std::uint64_t written = 0;  // frames since t0
  std::vector<std::int16_t> buf;
  std::vector<std::uint64_t> started;
  for (;;) {
    std::unique_lock<std::mutex> lk(m_);
    const auto now = SteadyClock::now();
    if (!open_) {
      promote_locked(now);  // closed: only drops what went stale
      if (stop_) {
        queue_.clear();
        cv_.notify_all();
        break;
      }
      if (queue_.empty()) {
        cv_.notify_all();
        cv_.wait_for(lk, std::chrono::milliseconds(200), [&] { return stop_ || !queue_.empty(); });
        continue;
      }
      if (now < next_open) {
        cv_.wait_until(lk, next_open, [&] { return stop_; });
        continue;
      }
      lk.unlock();
      if (open_device()) {
        t0 = SteadyClock::now();
        written = 0;
      } else {
        next_open = SteadyClock::now() + retry;
      }
      continue;
    }
    if (stop_ && (idle_locked() || now > stop_deadline_)) {
      queue_.clear();
      speech_.clear();
      mix_.clear();
      cv_.notify_all();
      break;
    }
    // Never more than ahead_s ahead of the device: the null and file PCMs take samples at once,
    // a card holds up to its buffer; either way a new cue goes into the next chunk.
    const double ahead =
        static_cast<double>(written) / kSoundRate - std::chrono::duration<double>(now - t0).count();
    if (ahead > opt_.ahead_s) {
      cv_.wait_for(lk, std::chrono::duration<double>(std::min(ahead - opt_.ahead_s, 0.02)),
                   [&] { return stop_; });
      continue;
    }
    if (ahead < -1.0) {
      // Held up for a second (a stopped process, a suspended laptop): start the time line afresh
      // rather than write the missed second of silence.
      t0 = now;
      written = 0;
    }
    promote_locked(now);
    started.clear();
    render_locked(buf, opt_.chunk_frames, started);
    const bool idle = idle_locked();
    const int ch = channels_;
    lk.unlock();
    snd_pcm_t* pcm = as_pcm(pcm_);
    std::size_t off = 0;
    bool failed = false;
    while (off < opt_.chunk_frames) {
      const snd_pcm_sframes_t r =
          snd_pcm_writei(pcm, buf.data() + off * static_cast<std::size_t>(ch), opt_.chunk_frames - off);
      if (r == -EAGAIN) {
        snd_pcm_wait(pcm, 50);
        continue;
      }
      if (r < 0) {
        if (r == -EPIPE) {
          std::lock_guard<std::mutex> g(m_);
          ++counters_.underruns;  // the device ran dry (the thread was held up): start again
        }
        const int e = snd_pcm_recover(pcm, static_cast<int>(r), 1);
        if (e < 0) {
          if (ev_.warn)
            ev_.warn("audio: ALSA device '" + opt_.device + "' failed: " + snd_strerror(e) + "; reopening");
          snd_pcm_close(pcm);
          std::lock_guard<std::mutex> g(m_);
          pcm_ = nullptr;
          open_ = false;
          speech_.clear();
          mix_.clear();
          counters_.device_open = false;
          counters_.channels = 0;
          next_open = SteadyClock::now() + retry;
          failed = true;
          break;
        }
        continue;
      }
      off += static_cast<std::size_t>(r);
    }
    if (failed) continue;
    written += opt_.chunk_frames;
    if (ev_.on_start && !started.empty()) {
      const auto t = SteadyClock::now();
      for (const auto id : started) ev_.on_start(id, t);
    }
    if (idle) cv_.notify_all();  // drain() waits for this
  }
}

}  // namespace stairguide::runtime::devices
