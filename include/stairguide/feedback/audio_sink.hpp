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
/// Implementations: `NullAudioSink`, `RecordingAudioSink` (a fake for tests: keeps what it was
/// asked to play) and, in the runtime room (it owns a playback thread),
/// `runtime::devices::AlsaAudioSink` (stairguide/runtime/devices/alsa_audio_sink.hpp).

#include <chrono>
#include <cstdint>
#include <mutex>
#include <string>
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

}  // namespace stairguide::feedback
