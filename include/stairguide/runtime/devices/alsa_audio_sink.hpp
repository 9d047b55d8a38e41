#pragma once
/// \file alsa_audio_sink.hpp
/// The sound device: `AlsaAudioSink` plays the cues on an ALSA PCM from a playback thread of its
/// own (the runtime room holds the threads). How an utterance meets what is already sounding, the
/// pan law and the sink's interface, fake and null sink are the feedback room's
/// (stairguide/feedback/audio_sink.hpp).

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "stairguide/feedback/audio_sink.hpp"
#include "stairguide/feedback/sound_bank.hpp"

namespace stairguide::runtime::devices {

/// What the ALSA sink reports (called on its playback thread).
struct AudioEvents {
  std::function<void(const std::string&)> warn;  ///< device trouble, a recovered underrun...
  std::function<void(const std::string&)> info;  ///< device opened
  /// The first sample of utterance `id` has been handed to the device.
  std::function<void(std::uint64_t id, feedback::SteadyClock::time_point)> on_start;
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
class AlsaAudioSink : public feedback::AudioSink {
 public:
  using SteadyClock = feedback::SteadyClock;
  AlsaAudioSink(AlsaSinkOptions options, feedback::SoundBank bank, AudioEvents events);
  ~AlsaAudioSink() override;  ///< plays on at most 0.3 s (call drain() to hear all), then closes
  void play(feedback::Utterance u) override;
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
  Voice voice_of(const feedback::Utterance& u, const std::vector<std::string>& clips) const;
  void start_locked(feedback::Utterance& u, std::vector<std::uint64_t>& started);  // m_ held
  void enqueue_locked(feedback::Utterance u);                                      // m_ held
  void promote_locked(SteadyClock::time_point now);                                // m_ held
  bool idle_locked() const { return queue_.empty() && speech_.empty() && mix_.empty(); }
  void render_locked(std::vector<std::int16_t>& out, std::size_t frames, std::vector<std::uint64_t>& started);

  AlsaSinkOptions opt_;
  feedback::SoundBank bank_;
  AudioEvents ev_;
  void* pcm_ = nullptr;  // snd_pcm_t*, kept out of this header
  mutable std::mutex m_;
  std::condition_variable cv_;
  std::deque<feedback::Utterance> queue_;
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

}  // namespace stairguide::runtime::devices
