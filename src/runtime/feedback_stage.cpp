// The feedback stage: the cue policy (feedback room, pure) on every perceived frame, its cues
// played through the sound sink and the buzzer. The sinks are opened on first use (so that a
// stage made only to describe itself opens nothing); each keeps its own thread, so decide()
// never waits on a device. A sink that cannot be had is logged and the other goes on.
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <atomic>
#include <mutex>
#include <unordered_map>

#include "stairguide/feedback/audio_sink.hpp"
#include "stairguide/feedback/button.hpp"
#include "stairguide/feedback/cue_policy.hpp"
#include "stairguide/feedback/haptic.hpp"
#include "stairguide/feedback/power_supply.hpp"
#include "stairguide/runtime/devices/alsa_audio_sink.hpp"
#include "stairguide/runtime/devices/button_reader.hpp"
#include "stairguide/runtime/devices/haptic_player.hpp"
#include "stairguide/runtime/latency.hpp"
#include "stairguide/runtime/pipeline.hpp"

namespace stairguide::runtime {

namespace fb = stairguide::feedback;
using SteadyClock = std::chrono::steady_clock;

namespace {
// s a step's cue may wait for the sound device before it is stale (the device is closed or
// failing, or a phrase that outranks it is speaking and it has no earcon to be told by): the next
// step comes some 0.4 s later at a brisk pace, and a count heard after it is a wrong count.
constexpr double kStepMaxWait = 0.15;
}  // namespace

struct FeedbackStage::Impl {
  PipelineConfig config;
  fb::CuePolicy policy;
  // Cue latency: written by decide() and by the sound thread's on_start
  // (declared before the sinks: their threads are joined first).
  mutable std::mutex lat_mutex;
  struct Pending {
    SteadyClock::time_point captured, decided;
    std::vector<fb::Cue> kinds;  // the cues the utterance says
    bool step_timed = false;     // ... of which one marks a step (its step can pass)
    bool superseded = false;     // a newer step's cue was given before this one started
    SteadyClock::time_point next_step{};
  };
  std::unordered_map<std::uint64_t, Pending> pending;  // utterance id -> what it says, when
  LatencyHistogram latency;
  std::vector<CueKindLatency> by_kind = std::vector<CueKindLatency>(fb::kCueKinds);
  std::uint64_t cues = 0;
  std::string last_cue;

  std::unique_ptr<fb::AudioSink> audio;
  // `audio` when it is the ALSA sink (its counters); read by cue_latency() from any thread.
  std::atomic<devices::AlsaAudioSink*> alsa{nullptr};
  // Cues lost to a sound outage (issue 41: they left no trace): dropped unplayed because they
  // waited past their age or overflowed the queue, not made stale on purpose by a newer step.
  std::uint64_t lost_seen = 0;
  std::unique_ptr<fb::Haptic> haptic;
  bool sinks_open = false;
  std::string last_state = "none";
  double last_t = 0.0;
  std::uint64_t next_id = 1;
  SteadyClock::time_point next_battery_poll{};  // the first frame reads it
  bool battery_seen = false;
  // The wearer's button: read on a thread of its own, opened on the first poll or frame.
  std::unique_ptr<devices::ButtonReader> button;
  bool button_tried = false;
  SteadyClock::time_point last_decide = SteadyClock::now();  // the frames' clock is carried on from it

  explicit Impl(const PipelineConfig& c) : config(c), policy(c.feedback) {}

  void open_button() {
    if (button_tried) return;
    button_tried = true;
    const FeedbackConfig& f = config.feedback;
    if (!f.button_enabled) return;
    auto warn = [](const std::string& s) { spdlog::warn("{}", s); };
    try {
      fb::PressTiming tm{f.button_debounce, f.button_long_press, f.button_double_press};
      button = std::make_unique<devices::ButtonReader>(
          devices::make_button_line(f.button_chip, f.button_line, f.button_active_low, warn), tm, warn);
      spdlog::info(
          "button: reading presses on {} (short: where are the stairs; long: mute {:.0f} s; double: "
          "verbosity)",
          button->describe(), f.mute);
    } catch (const std::exception& e) {
      spdlog::error("{}; going on without the button (feedback.button_enabled: false silences this)",
                    e.what());
    }
  }

  /// The presses since the last look, logged.
  std::vector<fb::Press> take_presses() {
    open_button();
    std::vector<fb::Press> out;
    if (!button) return out;
    for (const fb::PressEvent& p : button->take()) {
      spdlog::info("button: {} press", fb::to_string(p.press));
      out.push_back(p.press);
    }
    return out;
  }

  /// Loads the clips of the configured language (English, logged, when it is missing).
  fb::SoundBank load_sounds(const FeedbackConfig& f) {
    const fb::SoundSet set = fb::sound_set_for(f.sounds_dir, f.language);
    if (!set.problem.empty()) spdlog::error("audio: {}; speaking English from {}", set.problem, f.sounds_dir);
    std::vector<std::string> words, earcons;
    for (const auto& n : fb::all_clip_names()) (fb::is_earcon_clip(n) ? earcons : words).push_back(n);
    fb::SoundBank bank = fb::load_sound_bank(set.speech_dir, words, f.volume);
    fb::SoundBank shared = fb::load_sound_bank(set.earcon_dir, earcons, f.volume);
    bank.clips.insert(shared.clips.begin(), shared.clips.end());
    bank.problems.insert(bank.problems.end(), shared.problems.begin(), shared.problems.end());
    if (!bank.clips.empty())
      spdlog::info("audio: cues in {} ({}), earcons from {}", set.language, set.speech_dir, set.earcon_dir);
    return bank;
  }

  void open_sinks() {
    if (sinks_open) return;
    sinks_open = true;
    const FeedbackConfig& f = config.feedback;
    fb::SoundBank bank;
    if (f.audio_enabled) {
      bank = load_sounds(f);
      if (bank.clips.empty())
        spdlog::error(
            "audio: no usable sound in '{}' (feedback.sounds_dir; {}): cues are silent, the buzzer "
            "goes on",
            f.sounds_dir, bank.problems.empty() ? std::string("empty") : bank.problems.front());
      else
        for (const auto& p : bank.problems) spdlog::error("audio: sound {}: that cue is silent", p);
    }
    if (f.audio_enabled && !bank.clips.empty()) {
      devices::AlsaSinkOptions o;
      o.device = f.audio_device;
      o.retry_s = f.audio_retry;
      o.stereo = f.stereo_pan;
      devices::AudioEvents ev;
      ev.warn = [](const std::string& s) { spdlog::warn("{}", s); };
      ev.info = [](const std::string& s) { spdlog::info("{}", s); };
      ev.on_start = [this](std::uint64_t id, SteadyClock::time_point t) { started(id, t); };
      auto sink = std::make_unique<devices::AlsaAudioSink>(o, std::move(bank), std::move(ev));
      alsa = sink.get();
      audio = std::move(sink);
    } else {
      audio = std::make_unique<fb::NullAudioSink>();
    }
    haptic = std::make_unique<fb::NullHaptic>();
    if (f.haptic_enabled) {
      try {
        auto player =
            std::make_unique<devices::HapticPlayer>(devices::make_haptic_line(f.gpio_chip, f.gpio_line));
        if (player->realtime()) {
          spdlog::info("haptic: buzzer on {}, timed at real-time priority", player->describe());
        } else {
          spdlog::warn(
              "haptic: buzzer on {}, but its timing thread was refused real-time priority "
              "(needs root or LimitRTPRIO>={}); pulses may come a few ms late on a busy machine",
              player->describe(), devices::HapticPlayer::kRealtimePriority);
        }
        haptic = std::move(player);
      } catch (const std::exception& e) {
        spdlog::error("{}; going on with audio only (feedback.haptic_enabled: false silences this)",
                      e.what());
      }
    }
  }

  /// Cues the sound device dropped unplayed so far (0 without the ALSA sink).
  std::uint64_t lost() const {
    const devices::AlsaAudioSink* sink = alsa.load();
    if (!sink) return 0;
    const auto c = sink->counters();
    return c.stale > c.superseded ? c.stale - c.superseded : 0;
  }

  /// Logs the cues the sound device dropped since the last look.
  void check_lost() {
    const std::uint64_t now = lost();
    if (now == lost_seen) return;
    const std::uint64_t n = now - lost_seen;
    spdlog::warn(
        "audio: {} cue{} dropped unplayed: the sound device '{}' could not take {} in time ({} lost so far)",
        n, n == 1 ? "" : "s", config.feedback.audio_device, n == 1 ? "it" : "them", now);
    lost_seen = now;
  }

  void started(std::uint64_t id, SteadyClock::time_point t) {
    std::lock_guard<std::mutex> lk(lat_mutex);
    const auto it = pending.find(id);
    if (it == pending.end()) return;
    const double ms = std::chrono::duration<double, std::milli>(t - it->second.captured).count();
    const double dms = std::chrono::duration<double, std::milli>(t - it->second.decided).count();
    latency.add(ms);
    const bool late = it->second.superseded && t > it->second.next_step;
    for (const fb::Cue c : it->second.kinds) {
      auto& k = by_kind[static_cast<std::size_t>(c)];
      ++k.sounded;
      k.late += late;
      k.samples_ms.push_back(ms);
      k.from_decision_ms.push_back(dms);
    }
    pending.erase(it);
  }

  // Called with lat_mutex held: the cues of a frame are given at `captured`.
  void note_given(std::uint64_t id, const std::vector<fb::Cue>& kinds, SteadyClock::time_point captured) {
    bool timed = false;
    for (const fb::Cue c : kinds) {
      ++by_kind[static_cast<std::size_t>(c)].given;
      timed = timed || fb::marks_a_step(c);
    }
    if (timed)
      for (auto& [other, p] : pending)
        if (p.step_timed && !p.superseded) {
          p.superseded = true;
          p.next_step = captured;
        }
    if (pending.size() > 256) pending.clear();  // cues the device never started (closed)
    pending[id] = Pending{captured, SteadyClock::now(), kinds, timed, false, {}};
  }

  // A frame's cues as the wearer hears them: its phrases said as one (the most urgent first), so
  // that none of them waits behind another of the same moment; each earcon mixed on its own.
  std::string deliver(const std::vector<fb::CueEvent>& cues_now, SteadyClock::time_point captured) {
    if (cues_now.empty()) return "";
    open_sinks();
    std::vector<fb::Utterance> out;
    std::vector<std::vector<fb::Cue>> said;  // per utterance of `out`, the cues it says
    fb::Utterance phrase;
    std::vector<fb::Cue> phrase_kinds;
    bool placed = false;
    for (const auto& e : cues_now) {
      const fb::CueSound how = fb::cue_sound(e.cue);
      if (how == fb::CueSound::kEarcon) {
        fb::Utterance u;
        u.priority = e.priority;
        u.clips = fb::clips_for(e);
        u.label = fb::token(e);
        u.delivery = fb::Delivery::kMix;
        u.kinds = fb::cue_bit(e.cue);
        u.pan = fb::cue_pan(e);
        u.max_wait_s = kStepMaxWait;
        out.push_back(std::move(u));
        said.push_back({e.cue});
        continue;
      }
      const auto c = fb::clips_for(e);
      phrase.clips.insert(phrase.clips.end(), c.begin(), c.end());
      phrase.label += (phrase.label.empty() ? "" : "+") + fb::token(e);
      phrase.priority = std::max(phrase.priority, e.priority);
      phrase.kinds |= fb::cue_bit(e.cue);
      phrase.supersedes |= fb::cue_supersedes(e.cue);
      if (how == fb::CueSound::kStepPhrase) {
        phrase.delivery = fb::Delivery::kCut;
        phrase.fallback = {"tick"};
        phrase.max_wait_s = kStepMaxWait;
      }
      if (!placed && std::isfinite(e.bearing_rad)) {
        phrase.pan = fb::cue_pan(e);
        placed = true;
      }
      phrase_kinds.push_back(e.cue);
    }
    // A phrase does not make itself stale.
    phrase.supersedes &= ~phrase.kinds;
    if (!phrase_kinds.empty()) {
      out.insert(out.begin(), std::move(phrase));
      said.insert(said.begin(), phrase_kinds);
    }
    {
      std::lock_guard<std::mutex> lk(lat_mutex);
      cues += cues_now.size();
      last_cue = fb::token(cues_now.back());
      for (std::size_t i = 0; i < out.size(); ++i) {
        out[i].id = next_id++;
        note_given(out[i].id, said[i], captured);
      }
    }
    for (auto& u : out) audio->play(std::move(u));
    // One pattern per frame, the most urgent (the cues come highest priority first).
    for (const auto& e : cues_now) {
      const fb::HapticPattern p = fb::haptic_pattern(e);
      if (!p.empty()) {
        haptic->play(p, e.priority);
        break;
      }
    }
    return fb::tokens(cues_now);
  }
};

FeedbackStage::FeedbackStage(const PipelineConfig& config) : impl_(std::make_unique<Impl>(config)) {}
FeedbackStage::~FeedbackStage() = default;

Decision FeedbackStage::decide(const PerceptionOutput& perception, const OdometryOutput* /*latest_odometry*/,
                               double timestamp_s, SteadyClock::time_point captured) {
  Decision d;
  d.state = perception.state;
  d.changed = d.state != impl_->last_state;
  impl_->last_state = d.state;
  impl_->last_t = timestamp_s;
  impl_->last_decide = SteadyClock::now();
  impl_->check_lost();
  if (!perception.ran) return d;  // no perception stage: nothing to tell
  fb::CueInput in;
  in.presses = impl_->take_presses();
  in.t = timestamp_s;
  in.floor_found = perception.floor_found;
  in.stair = perception.stair;
  in.drop = perception.drop;
  in.traversal = perception.traversal;
  const auto now = SteadyClock::now();
  in.lag_s = std::max(0.0, std::chrono::duration<double>(now - captured).count());
  std::vector<fb::CueEvent> cues = impl_->policy.step(in);
  // The battery, every battery_poll s (a few small sysfs reads, on the feedback thread).
  const FeedbackConfig& f = impl_->config.feedback;
  if (now >= impl_->next_battery_poll) {
    impl_->next_battery_poll = now + std::chrono::duration_cast<SteadyClock::duration>(
                                         std::chrono::duration<double>(f.battery_poll));
    const fb::BatteryStatus b = fb::read_battery(f.power_supply_dir);
    if (b.present != impl_->battery_seen) {
      impl_->battery_seen = b.present;
      if (b.present)
        spdlog::info("battery: {} in {} at {:.0f}%{}", b.name, f.power_supply_dir, b.charge * 100.f,
                     b.charging ? ", charging" : "");
    }
    for (const auto& e : impl_->policy.battery(timestamp_s, b.present, b.charge, b.charging))
      cues.push_back(e);
    std::stable_sort(cues.begin(), cues.end(),
                     [](const fb::CueEvent& a, const fb::CueEvent& b) { return a.priority > b.priority; });
  }
  d.cue = impl_->deliver(cues, captured);
  return d;
}

void FeedbackStage::poll() {
  Impl& m = *impl_;
  const std::vector<fb::Press> presses = m.take_presses();
  if (presses.empty() && !m.policy.muted()) return;
  // The frames' clock carried on by the steady clock since the last frame.
  const double t = m.last_t + std::chrono::duration<double>(SteadyClock::now() - m.last_decide).count();
  const auto c = m.deliver(m.policy.between_frames(t, presses), SteadyClock::now());
  if (!c.empty()) spdlog::info("cue {} (button)", c);
}

void FeedbackStage::camera_lost(const std::string& why) {
  const auto c = impl_->deliver(impl_->policy.camera_lost(impl_->last_t), SteadyClock::now());
  if (!c.empty()) spdlog::info("cue {} ({})", c, why);
}
void FeedbackStage::camera_back() {
  const auto c = impl_->deliver(impl_->policy.camera_back(impl_->last_t), SteadyClock::now());
  if (!c.empty()) spdlog::info("cue {}", c);
}

namespace {
// `f(x, y, button)` on each pair of the feedback settings read when the devices are opened: the
// sound device, the sounds, the language and the buzzer (`button` false; read with the sinks) and
// the button's (true; read when the button is first looked at). They apply at the next start.
template <class A, class B, class F>
void device_settings(A& x, B& y, F f) {
  f(x.audio_enabled, y.audio_enabled, false);
  f(x.audio_device, y.audio_device, false);
  f(x.sounds_dir, y.sounds_dir, false);
  f(x.volume, y.volume, false);
  f(x.stereo_pan, y.stereo_pan, false);
  f(x.haptic_enabled, y.haptic_enabled, false);
  f(x.gpio_chip, y.gpio_chip, false);
  f(x.gpio_line, y.gpio_line, false);
  f(x.language, y.language, false);
  f(x.button_enabled, y.button_enabled, true);
  f(x.button_chip, y.button_chip, true);
  f(x.button_line, y.button_line, true);
  f(x.button_active_low, y.button_active_low, true);
  f(x.button_debounce, y.button_debounce, true);
  f(x.button_long_press, y.button_long_press, true);
  f(x.button_double_press, y.button_double_press, true);
}
}  // namespace

void FeedbackStage::reconfigure(const PipelineConfig& config) {
  const FeedbackConfig& a = impl_->config.feedback;
  const FeedbackConfig& b = config.feedback;
  if (a.verbosity != b.verbosity) spdlog::info("feedback: verbosity {} -> {}", a.verbosity, b.verbosity);
  bool differ = false;
  device_settings(a, b, [&](const auto& x, const auto& y, bool) { differ = differ || x != y; });
  if (impl_->sinks_open && differ)
    spdlog::info(
        "feedback: sound device, sounds, language, buzzer and button settings apply at the next start");
  // The devices stay as opened; only the policy's tunables change now.
  PipelineConfig keep = config;
  device_settings(keep.feedback, a, [&](auto& kept, const auto& old, bool button) {
    if (button ? impl_->button_tried : impl_->sinks_open) kept = old;
  });
  impl_->config = keep;
  impl_->policy.reconfigure(keep.feedback);
}

bool FeedbackStage::available() const { return true; }

std::string FeedbackStage::describe() const {
  const FeedbackConfig& f = impl_->config.feedback;
  return "CuePolicy(" + f.verbosity + ")+audio=" + (f.audio_enabled ? "alsa:" + f.audio_device : "off") +
         "+haptic=" + (f.haptic_enabled ? f.gpio_chip + ":" + std::to_string(f.gpio_line) : "off");
}

void FeedbackStage::drain(std::chrono::milliseconds timeout) {
  if (!impl_->sinks_open) return;
  const auto until = SteadyClock::now() + timeout;
  impl_->audio->drain(timeout);
  impl_->check_lost();
  const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(until - SteadyClock::now());
  impl_->haptic->drain(std::max(left, std::chrono::milliseconds(0)));
}

FeedbackStage::CueLatency FeedbackStage::cue_latency() const {
  const std::uint64_t lost = impl_->lost();  // before lat_mutex: never both held
  std::lock_guard<std::mutex> lk(impl_->lat_mutex);
  CueLatency c;
  c.lost = lost;
  c.cues = impl_->cues;
  c.sounded = impl_->latency.count();
  c.p50_ms = impl_->latency.percentile(50);
  c.p99_ms = impl_->latency.percentile(99);
  c.max_ms = impl_->latency.max();
  c.last = impl_->last_cue;
  for (std::size_t i = 0; i < impl_->by_kind.size(); ++i)
    if (impl_->by_kind[i].given > 0) {
      c.by_kind.push_back(impl_->by_kind[i]);
      c.by_kind.back().kind = fb::to_string(static_cast<fb::Cue>(i));
    }
  return c;
}

void FeedbackStage::clear_cue_latency() {
  std::lock_guard<std::mutex> lk(impl_->lat_mutex);
  impl_->latency.clear();
  impl_->pending.clear();
  impl_->cues = 0;
  impl_->by_kind.assign(fb::kCueKinds, CueKindLatency{});
}

}  // namespace stairguide::runtime
