#include <alsa/asoundlib.h>

#include <algorithm>
#include <cerrno>
#include <cstdarg>

#include "stairguide/feedback/audio_sink.hpp"

namespace stairguide::feedback {

namespace {
snd_pcm_t* as_pcm(void* p) { return static_cast<snd_pcm_t*>(p); }
// libasound prints its own errors to stderr; the sink reports through its events instead.
void quiet_alsa(const char*, int, const char*, int, const char*, ...) {}
constexpr snd_pcm_uframes_t kChunk = 512;  // frames per write (23 ms at 22050 Hz)
// At stop, what is playing or queued may go on this long (drain() first to hear everything).
constexpr auto kStopGrace = std::chrono::milliseconds(300);
}  // namespace

AlsaAudioSink::AlsaAudioSink(AlsaSinkOptions options, SoundBank bank, AudioEvents events)
    : opt_(std::move(options)), bank_(std::move(bank)), ev_(std::move(events)) {
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

void AlsaAudioSink::play(Utterance u) {
  {
    std::lock_guard<std::mutex> lk(m_);
    u.queued = SteadyClock::now();
    if (playing_priority_ >= 0 && u.priority > playing_priority_) cut_ = true;
    const auto at = std::find_if(queue_.begin(), queue_.end(),
                                 [&](const Utterance& q) { return q.priority < u.priority; });
    queue_.insert(at, std::move(u));
    if (queue_.size() > opt_.max_queue) {
      queue_.pop_back();
      ++counters_.stale;
    }
  }
  cv_.notify_all();
}

bool AlsaAudioSink::drain(std::chrono::milliseconds timeout) {
  std::unique_lock<std::mutex> lk(m_);
  return cv_.wait_for(lk, timeout, [&] { return queue_.empty() && playing_priority_ < 0; });
}

bool AlsaAudioSink::open_device() {
  snd_pcm_t* p = nullptr;
  int e = snd_pcm_open(&p, opt_.device.c_str(), SND_PCM_STREAM_PLAYBACK, SND_PCM_NONBLOCK);
  if (e >= 0) {
    e = snd_pcm_set_params(p, SND_PCM_FORMAT_S16_LE, SND_PCM_ACCESS_RW_INTERLEAVED, 1, kSoundRate, 1,
                           opt_.latency_us);
    if (e < 0) snd_pcm_close(p);
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
  failing_ = false;
  counters_.device_open = true;
  if (ev_.info)
    ev_.info("audio: ALSA device '" + opt_.device + "' open (16-bit mono " + std::to_string(kSoundRate) +
             " Hz)");
  return true;
}

void AlsaAudioSink::close_device() {
  if (!pcm_) return;
  snd_pcm_nonblock(as_pcm(pcm_), 0);
  snd_pcm_drain(as_pcm(pcm_));  // plays out the device buffer (at most latency_us)
  snd_pcm_close(as_pcm(pcm_));
  pcm_ = nullptr;
  std::lock_guard<std::mutex> lk(m_);
  counters_.device_open = false;
}

bool AlsaAudioSink::play_one(const Utterance& u) {
  std::vector<std::int16_t> buf;
  for (const auto& c : u.clips)
    if (const auto* s = bank_.find(c)) buf.insert(buf.end(), s->begin(), s->end());
  if (buf.empty()) return true;
  snd_pcm_t* pcm = as_pcm(pcm_);
  std::size_t off = 0;
  bool started = false;
  // Never more than the device's buffer ahead of real time: a real card holds us back by itself,
  // a PCM that takes samples at once (null, file) is held back here, so that a cut comes when
  // it would on a card.
  const auto t0 = SteadyClock::now();
  const double buffer_s = opt_.latency_us * 1e-6;
  while (off < buf.size()) {
    {
      std::unique_lock<std::mutex> lk(m_);
      const double ahead = static_cast<double>(off) / kSoundRate -
                           std::chrono::duration<double>(SteadyClock::now() - t0).count();
      if (ahead > buffer_s && !cut_ && !stop_) {
        cv_.wait_for(lk, std::chrono::duration<double>(std::min(ahead - buffer_s, 0.02)),
                     [&] { return cut_ || stop_; });
        continue;
      }
      if (cut_ || (stop_ && SteadyClock::now() > stop_deadline_)) {
        snd_pcm_drop(pcm);
        snd_pcm_prepare(pcm);
        ++counters_.cut;
        return true;
      }
    }
    const auto n = std::min<snd_pcm_uframes_t>(kChunk, buf.size() - off);
    const snd_pcm_sframes_t r = snd_pcm_writei(pcm, buf.data() + off, n);
    if (r == -EAGAIN) {
      snd_pcm_wait(pcm, 100);
      continue;
    }
    if (r < 0) {
      if (r == -EPIPE) {
        std::lock_guard<std::mutex> lk(m_);
        ++counters_.underruns;  // the device ran dry (it does between two cues): start again
      }
      const int e = snd_pcm_recover(pcm, static_cast<int>(r), 1);
      if (e < 0) {
        if (ev_.warn)
          ev_.warn("audio: ALSA device '" + opt_.device + "' failed: " + snd_strerror(e) + "; reopening");
        snd_pcm_close(pcm);
        pcm_ = nullptr;
        std::lock_guard<std::mutex> lk(m_);
        counters_.device_open = false;
        return false;
      }
      continue;
    }
    if (!started) {
      started = true;
      if (ev_.on_start) ev_.on_start(u.id, SteadyClock::now());
    }
    off += static_cast<std::size_t>(r);
  }
  std::lock_guard<std::mutex> lk(m_);
  ++counters_.played;
  return true;
}

void AlsaAudioSink::run() {
  auto next_open = SteadyClock::now();
  const auto retry =
      std::chrono::duration_cast<SteadyClock::duration>(std::chrono::duration<double>(opt_.retry_s));
  for (;;) {
    Utterance u;
    {
      std::unique_lock<std::mutex> lk(m_);
      const bool closed = pcm_ == nullptr;
      if (closed && !queue_.empty() && SteadyClock::now() < next_open)
        cv_.wait_until(lk, next_open, [&] { return stop_; });
      else
        cv_.wait_for(lk, std::chrono::milliseconds(200), [&] { return stop_ || !queue_.empty(); });
      const auto now = SteadyClock::now();
      const auto max_age = std::chrono::duration<double>(opt_.max_age_s);
      while (!queue_.empty() && now - queue_.front().queued > max_age) {
        queue_.pop_front();
        ++counters_.stale;
      }
      if (stop_ && now > stop_deadline_) queue_.clear();
      if (queue_.empty() || (stop_ && pcm_ == nullptr)) {
        cv_.notify_all();
        if (stop_) break;
        continue;
      }
      if (pcm_ == nullptr && now < next_open) continue;
    }
    if (pcm_ == nullptr && !open_device()) {
      next_open = SteadyClock::now() + retry;
      continue;
    }
    {
      std::lock_guard<std::mutex> lk(m_);
      if (queue_.empty()) continue;
      u = std::move(queue_.front());
      queue_.pop_front();
      playing_priority_ = u.priority;
      cut_ = false;
    }
    if (!play_one(u)) next_open = SteadyClock::now() + retry;
    {
      std::lock_guard<std::mutex> lk(m_);
      playing_priority_ = -1;
    }
    cv_.notify_all();
  }
}

}  // namespace stairguide::feedback
