#pragma once
/// \file audio_sink.hpp
/// Where the cues are heard. `play()` never blocks: it hands an utterance (clips played back to
/// back) to the sink and returns. How it meets what is already sounding is its `delivery`:
///
/// - `kQueue` (a phrase: "stairs ahead, going up, 3 metres"): waits its turn, ordered by priority
///   then arrival; one of higher priority than the phrase speaking cuts it off.
/// - `kCut` (a phrase tied to a moment, a step: "first step", "five", "last step"): starts at once,
///   cutting the phrase speaking, unless that phrase outranks it and is not made stale by it; then
///   its `fallback` earcon (a tick) is mixed over the phrase instead, so that the step is still
///   marked on time.
/// - `kMix` (an earcon: the tick, the approach beep): mixed over whatever sounds, at once. While an
///   earcon sounds, the phrase under it is lowered by 6 dB; the sum is saturated (never wraps).
///
/// An utterance makes stale the kinds in its `supersedes` (a newer step's cue makes the older ones
/// stale): those still waiting are dropped unplayed, a phrase of them speaking is cut. One waiting
/// longer than its `max_wait_s` is stale and dropped unplayed: a cue is never heard late.
///
/// The output is stereo (each utterance placed by its `pan` with a constant-power law) unless the
/// options ask for mono or the device refuses two channels, then mono.
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

/// How an utterance meets what is already sounding (see the file comment).
enum class Delivery { kQueue, kCut, kMix };

struct Utterance {
  std::uint64_t id = 0;            ///< caller's number (reported back by `on_start`)
  int priority = 0;                ///< higher cuts lower
  std::vector<std::string> clips;  ///< sound bank names, played back to back
  std::string label;               ///< for logs ("stairs_ahead_up:3m")
  Delivery delivery = Delivery::kQueue;
  std::uint32_t kinds = 0;            ///< what it says, as a bit set of the caller's numbering
  std::uint32_t supersedes = 0;       ///< kinds it makes stale (waiting: dropped; speaking: cut)
  std::vector<std::string> fallback;  ///< kCut outranked: this earcon is mixed instead (empty: waits)
  float pan = 0.f;                    ///< -1 left .. 0 centre .. +1 right (stereo output only)
  double max_wait_s = -1.0;           ///< s it may wait before it is stale; < 0: the sink's max_age_s
  SteadyClock::time_point queued{};
};

/// Constant-power pan law: the left and right gains of `pan` (-1 left .. +1 right), with
/// left^2 + right^2 = 1 (each 0.707, -3 dB, at the centre).
void pan_gains(float pan, float& left, float& right);

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
  bool stereo = true;              ///< two channels, panned (mono when false or refused)
  unsigned chunk_frames = 256;     ///< frames mixed per write (11.6 ms at kSoundRate)
  double ahead_s = 0.035;          ///< s written ahead of the device's play position
};

/// Plays on an ALSA PCM from a thread of its own. While the device is open the sink streams
/// without a break (silence between cues): every `chunk_frames` it mixes what sounds and writes it,
/// never more than `ahead_s` ahead of the device, so that a new cue is handed to the device within
/// a chunk and a cut comes when it would on a card (a PCM that takes samples at once, null or
/// file, is held to the pace of the clock: its samples are then a time line, one per 1/kSoundRate
/// s). Non-blocking open and writes (snd_pcm_wait on -EAGAIN), snd_pcm_recover on underruns; a
/// device that cannot be opened (or fails) is logged and retried every `retry_s` while utterances
/// are dropped as they go stale. The thread asks for real-time scheduling (as the buzzer's does).
class AlsaAudioSink : public AudioSink {
 public:
  AlsaAudioSink(AlsaSinkOptions options, SoundBank bank, AudioEvents events);
  ~AlsaAudioSink() override;  ///< plays on at most 0.3 s (call drain() to hear all), then closes
  void play(Utterance u) override;
  bool drain(std::chrono::milliseconds timeout) override;
  std::string describe() const override;

  struct Counters {
    std::uint64_t played = 0;      ///< utterances started (phrases and earcons)
    std::uint64_t cut = 0;         ///< phrases cut off while speaking
    std::uint64_t stale = 0;       ///< utterances dropped unplayed (waited too long, queue full)
    std::uint64_t superseded = 0;  ///< ... of them, made stale by a newer one (counted in stale too)
    std::uint64_t fallbacks = 0;   ///< kCut utterances told by their earcon over a higher phrase
    std::uint64_t underruns = 0, open_failures = 0;
    bool device_open = false;
    int channels = 0;       ///< of the open device (0 closed)
    bool realtime = false;  ///< the thread got real-time scheduling
  };
  Counters counters() const;

 private:
  struct Voice {
    std::uint64_t id = 0;
    int priority = 0;
    std::uint32_t kinds = 0;
    std::vector<std::int16_t> samples;
    std::size_t pos = 0;
    float gl = 1.f, gr = 1.f;  // channel gains (mono: gl)
  };
  void run();
  bool open_device();
  void close_device();
  Voice voice_of(const Utterance& u, const std::vector<std::string>& clips) const;
  void start_locked(Utterance& u, std::vector<std::uint64_t>& started);  // m_ held
  void enqueue_locked(Utterance u);                                      // m_ held
  void promote_locked(SteadyClock::time_point now);                      // m_ held
  bool idle_locked() const { return queue_.empty() && speech_.empty() && mix_.empty(); }
  void render_locked(std::vector<std::int16_t>& out, std::size_t frames, std::vector<std::uint64_t>& started);

  AlsaSinkOptions opt_;
  SoundBank bank_;
  AudioEvents ev_;
  void* pcm_ = nullptr;  // snd_pcm_t*, kept out of this header
  mutable std::mutex m_;
  std::condition_variable cv_;
  std::deque<Utterance> queue_;
  std::vector<Voice> speech_;  // at most one phrase speaking
  std::vector<Voice> mix_;     // earcons sounding over it
  bool open_ = false;          // pcm_ open (read by play() under m_)
  int channels_ = 1;
  bool stop_ = false;
  SteadyClock::time_point stop_deadline_{};
  bool failing_ = false;  // the device failed; warned once until it opens again
  Counters counters_;
  std::thread thread_;
};

}  // namespace stairguide::feedback
