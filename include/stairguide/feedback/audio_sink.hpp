#pragma once
/// \file audio_sink.hpp
/// Where the spoken cues go. `play()` never blocks: it queues an utterance (clips played back to
/// back) and returns. The queue is ordered by priority (then arrival); an utterance of higher
/// priority than the one playing cuts it off; an utterance waiting longer than `max_age` is stale
/// and dropped unplayed.
///
/// Implementations: `AlsaAudioSink` (a playback thread of its own: hardware may own one),
/// `NullAudioSink`, and `RecordingAudioSink` (a fake for tests: keeps what it was asked to play).

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "stairguide/feedback/sound_bank.hpp"

namespace stairguide::feedback {

using SteadyClock = std::chrono::steady_clock;

struct Utterance {
  std::uint64_t id = 0;            ///< caller's number (reported back by `on_start`)
  int priority = 0;                ///< higher cuts lower
  std::vector<std::string> clips;  ///< sound bank names, played back to back
  std::string label;               ///< for logs ("stairs_ahead_up:3m")
  SteadyClock::time_point queued{};
};

class AudioSink {
 public:
  virtual ~AudioSink() = default;
  virtual void play(Utterance u) = 0;
  /// Waits until nothing is queued or playing, at most `timeout`; true when idle.
  virtual bool drain(std::chrono::milliseconds timeout) = 0;
  virtual std::string describe() const = 0;
};

class NullAudioSink : public AudioSink {
 public:
  void play(Utterance) override {}
  bool drain(std::chrono::milliseconds) override { return true; }
  std::string describe() const override { return "null"; }
};

/// Test fake: records every utterance asked for, in order.
class RecordingAudioSink : public AudioSink {
 public:
  void play(Utterance u) override {
    std::lock_guard<std::mutex> lk(m_);
    played_.push_back(std::move(u));
  }
  bool drain(std::chrono::milliseconds) override { return true; }
  std::string describe() const override { return "recording"; }
  std::vector<Utterance> played() const {
    std::lock_guard<std::mutex> lk(m_);
    return played_;
  }

 private:
  mutable std::mutex m_;
  std::vector<Utterance> played_;
};

/// What the ALSA sink reports (called on its playback thread).
struct AudioEvents {
  std::function<void(const std::string&)> warn;  ///< device trouble, a recovered underrun...
  std::function<void(const std::string&)> info;  ///< device opened
  /// The first sample of utterance `id` has been handed to the device.
  std::function<void(std::uint64_t id, SteadyClock::time_point)> on_start;
};

struct AlsaSinkOptions {
  std::string device = "default";  ///< ALSA PCM name
  double retry_s = 3.0;            ///< s between attempts to open a device that failed
  unsigned latency_us = 50000;     ///< device buffer (snd_pcm_set_params latency)
  double max_age_s = 3.0;          ///< s an utterance may wait before it is stale
  std::size_t max_queue = 8;       ///< utterances held; beyond, the lowest priority is dropped
};

/// Plays on an ALSA PCM from a thread of its own: non-blocking open and writes (snd_pcm_wait on
/// -EAGAIN), snd_pcm_recover on underruns, a device that cannot be opened (or fails) is logged
/// and retried every `retry_s` while utterances are dropped as they go stale.
class AlsaAudioSink : public AudioSink {
 public:
  AlsaAudioSink(AlsaSinkOptions options, SoundBank bank, AudioEvents events);
  ~AlsaAudioSink() override;  ///< plays on at most 0.3 s (call drain() to hear all), then closes
  void play(Utterance u) override;
  bool drain(std::chrono::milliseconds timeout) override;
  std::string describe() const override;

  struct Counters {
    std::uint64_t played = 0, cut = 0, stale = 0, underruns = 0, open_failures = 0;
    bool device_open = false;
  };
  Counters counters() const;

 private:
  void run();
  bool open_device();
  void close_device();
  bool play_one(const Utterance& u);

  AlsaSinkOptions opt_;
  SoundBank bank_;
  AudioEvents ev_;
  void* pcm_ = nullptr;  // snd_pcm_t*, kept out of this header
  mutable std::mutex m_;
  std::condition_variable cv_;
  std::deque<Utterance> queue_;
  int playing_priority_ = -1;  // -1: idle
  bool cut_ = false;
  bool stop_ = false;
  SteadyClock::time_point stop_deadline_{};
  bool failing_ = false;  // the device failed; warned once until it opens again
  Counters counters_;
  std::thread thread_;
};

}  // namespace stairguide::feedback
