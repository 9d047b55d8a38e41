// The ALSA sink heard for real: an ALSA `type file` PCM (a test configuration through
// ALSA_CONFIG_PATH) writes exactly the samples the sink plays; the cues are found in them, in
// order, by correlation with the WAVs.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <thread>

#include "feedback_test_util.hpp"
#include "stairguide/feedback/audio_sink.hpp"
#include "stairguide/feedback/cue.hpp"
#include "stairguide/runtime/devices/alsa_audio_sink.hpp"

using namespace stairguide::feedback;
using namespace stairguide::runtime::devices;
namespace fs = std::filesystem;

namespace {

// One folder per process: ctest runs each test case in a process of its own, two at once, and a
// case that rewrote the shared asound.conf took away the PCM another had just added.
const fs::path kDir = sgtest::process_dir("devices_audio_files");

/// ALSA reads its configuration once per process (and again when the file changes): one file
/// with every PCM the tests use, set before the first ALSA call.
const std::vector<std::string> kPcms = {"sg_order", "sg_cut", "sg_latency", "sg_mix", "sg_step", "sg_pan"};
const std::vector<std::string> kMonoPcms = {"sg_monodev"};  // refuse two channels
void alsa_setup() {
  static bool done = false;
  if (done) return;
  done = true;
  sgtest::write_alsa_config(kDir / "asound.conf", kDir, kPcms, kMonoPcms);
  setenv("ALSA_CONFIG_PATH", (kDir / "asound.conf").c_str(), 1);
}

SoundBank bank(float volume = 0.8f) {
  return load_sound_bank(sgtest::sounds_dir(), all_clip_names(), volume);
}

/// What a sink reports from its thread, in order: its warnings, its info lines and the utterances
/// started. Declared before the sink (it outlives the sink's thread).
class SinkLog {
 public:
  AudioEvents events() {
    AudioEvents ev;
    ev.warn = [this](const std::string& s) { add(warn_, s); };
    ev.info = [this](const std::string& s) { add(info_, s); };
    ev.on_start = [this](std::uint64_t id, SteadyClock::time_point) { add(started_, id); };
    return ev;
  }
  std::vector<std::string> warnings() const { return get(warn_); }
  std::vector<std::string> info() const { return get(info_); }
  std::vector<std::uint64_t> started() const { return get(started_); }

 private:
  template <class T>
  void add(std::vector<T>& v, T x) {
    std::lock_guard<std::mutex> lk(m_);
    v.push_back(std::move(x));
  }
  template <class T>
  std::vector<T> get(const std::vector<T>& v) const {
    std::lock_guard<std::mutex> lk(m_);
    return v;
  }
  mutable std::mutex m_;
  std::vector<std::string> warn_, info_;
  std::vector<std::uint64_t> started_;
};

Utterance utt(std::uint64_t id, int priority, std::vector<std::string> clips) {
  Utterance u;
  u.id = id;
  u.priority = priority;
  u.clips = std::move(clips);
  return u;
}

}  // namespace

TEST(FeedbackAlsa, CuesHeardInOrderThroughAFilePcm) {
  alsa_setup();
  SinkLog log;
  {
    AlsaSinkOptions o;
    o.device = "sg_order";
    o.stereo = false;    // the very samples of the WAVs
    o.max_age_s = 10.0;  // the three wait behind each other longer than the default 3 s
    AlsaAudioSink sink(o, bank(), log.events());
    const auto t0 = SteadyClock::now();
    sink.play(utt(1, 4, {"stairs_up", "n3", "metres"}));
    sink.play(utt(2, 1, {"tick"}));
    sink.play(utt(3, 4, {"last_step"}));  // same priority as the first: after it, before the tick
    const double play_ms = std::chrono::duration<double, std::milli>(SteadyClock::now() - t0).count();
    EXPECT_LT(play_ms, 20.0);  // play() never waits on the device
    ASSERT_TRUE(sink.drain(std::chrono::seconds(10)));
    const double total_s = std::chrono::duration<double>(SteadyClock::now() - t0).count();
    // Played in real time (the sink holds itself to the device's pace): ~3.2 s of sound.
    const double expected_s =
        static_cast<double>(sgtest::clip("stairs_up").size() + sgtest::clip("n3").size() +
                            sgtest::clip("metres").size() + sgtest::clip("last_step").size() +
                            sgtest::clip("tick").size()) /
        kSoundRate;
    EXPECT_GT(total_s, expected_s - 3 * 0.05 - 0.05);  // each ends a device buffer (50 ms) early
    EXPECT_LT(total_s, expected_s + 1.0);
    const auto c = sink.counters();
    EXPECT_EQ(c.played, 3u);
    EXPECT_EQ(c.cut, 0u);
  }
  EXPECT_EQ(log.started(), (std::vector<std::uint64_t>{1, 3, 2}));
  const auto cap = sgtest::read_raw(kDir / "sg_order.raw");
  const auto h =
      sgtest::heard(cap, {"stairs_up", "stairs_down", "n3", "metres", "tick", "last_step", "first_step"});
  ASSERT_EQ(sgtest::names_of(h),
            (std::vector<std::string>{"stairs_up", "n3", "metres", "last_step", "tick"}));
  // Back to back, each where the previous one ended, starting at the first sample.
  EXPECT_EQ(h[0].pos, 0);
  EXPECT_EQ(h[1].pos, h[0].pos + static_cast<long>(sgtest::clip("stairs_up").size()));
  EXPECT_EQ(h[2].pos, h[1].pos + static_cast<long>(sgtest::clip("n3").size()));
  for (const auto& x : h) EXPECT_GT(x.score, 0.999) << x.name;  // the very samples, at 80 % volume
}

TEST(FeedbackAlsa, HigherPriorityCutsWhatIsPlaying) {
  alsa_setup();
  std::vector<std::string> low;
  for (int i = 1; i <= 10; ++i) low.push_back("n" + std::to_string(i));
  std::size_t low_len = 0;
  for (const auto& n : low) low_len += sgtest::clip(n).size();
  {
    AlsaSinkOptions o;
    o.device = "sg_cut";
    o.stereo = false;
    o.max_age_s = 10.0;
    AlsaAudioSink sink(o, bank(), {});
    sink.play(utt(1, 1, low));
    std::this_thread::sleep_for(std::chrono::milliseconds(600));
    sink.play(utt(2, 8, {"warning", "stairs_down"}));
    sink.play(utt(3, 1, {"tick"}));  // lower than the warning: waits for it
    ASSERT_TRUE(sink.drain(std::chrono::seconds(10)));
    EXPECT_EQ(sink.counters().cut, 1u);
  }
  const auto cap = sgtest::read_raw(kDir / "sg_cut.raw");
  std::vector<std::string> names = low;
  names.insert(names.end(), {"warning", "stairs_down", "tick"});
  const auto h = sgtest::heard(cap, names);
  const auto n = sgtest::names_of(h);
  ASSERT_GE(n.size(), 4u) << ::testing::PrintToString(n);
  EXPECT_EQ(n.front(), "n1");
  // The count was cut within its first second: n4..n10 never heard; then the warning, whole.
  for (int i = 4; i <= 10; ++i) EXPECT_EQ(std::count(n.begin(), n.end(), "n" + std::to_string(i)), 0) << i;
  const std::vector<std::string> tail(n.end() - 3, n.end());
  EXPECT_EQ(tail, (std::vector<std::string>{"warning", "stairs_down", "tick"}));
  EXPECT_LT(cap.size(), low_len);
}

TEST(FeedbackAlsa, DeviceThatCannotBeOpenedIsNamedAndRetried) {
  alsa_setup();
  SinkLog log;
  AlsaSinkOptions o;
  o.device = "sg_no_such_pcm";
  o.retry_s = 0.3;
  o.max_age_s = 1.0;
  AlsaAudioSink sink(o, bank(), log.events());
  const auto t0 = SteadyClock::now();
  for (int i = 0; i < 5; ++i) sink.play(utt(static_cast<std::uint64_t>(i), 4, {"ready"}));
  const double play_ms = std::chrono::duration<double, std::milli>(SteadyClock::now() - t0).count();
  EXPECT_LT(play_ms, 20.0);
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  const auto c = sink.counters();
  EXPECT_GE(c.open_failures, 3u);  // retried every 0.3 s while there was something to say
  EXPECT_LE(c.open_failures, 6u);
  EXPECT_EQ(c.stale, 5u);  // dropped once stale, never played late
  EXPECT_FALSE(c.device_open);
  const auto warnings = log.warnings();
  ASSERT_EQ(warnings.size(), 1u);  // said once, not on every retry
  EXPECT_NE(warnings[0].find("cannot open ALSA device 'sg_no_such_pcm'"), std::string::npos) << warnings[0];
}

TEST(FeedbackAlsa, DeviceThatAppearsLaterIsOpenedAtTheNextRetry) {
  alsa_setup();
  SinkLog log;
  AlsaSinkOptions o;
  o.device = "sg_late";
  o.stereo = false;
  o.retry_s = 0.3;
  o.max_age_s = 10.0;
  fs::remove(kDir / "sg_late.raw");
  {
    AlsaAudioSink sink(o, bank(), log.events());
    sink.play(utt(1, 4, {"camera_back"}));
    std::this_thread::sleep_for(std::chrono::milliseconds(400));
    EXPECT_GE(sink.counters().open_failures, 1u);
    // The device comes (ALSA reads its configuration again when the file changes). ALSA tells a
    // changed file by its modification time in whole seconds: a rewrite within the same second
    // as the first write went unseen (the case failed on half its runs), so wait for the next.
    std::this_thread::sleep_for(std::chrono::milliseconds(1100));
    std::vector<std::string> pcms = kPcms;
    pcms.push_back("sg_late");
    sgtest::write_alsa_config(kDir / "asound.conf", kDir, pcms, kMonoPcms);
    ASSERT_TRUE(sink.drain(std::chrono::seconds(5)));
    EXPECT_TRUE(sink.counters().device_open);
    EXPECT_EQ(sink.counters().played, 1u);
    const auto info = log.info();
    ASSERT_EQ(info.size(), 1u);
    EXPECT_NE(info[0].find("'sg_late' open"), std::string::npos) << info[0];
  }  // closed: the file PCM has written everything
  const auto h = sgtest::heard(sgtest::read_raw(kDir / "sg_late.raw"), {"camera_back", "camera_lost"});
  EXPECT_EQ(sgtest::names_of(h), (std::vector<std::string>{"camera_back"}));
}

namespace {
std::vector<std::int16_t> concat(const std::vector<std::string>& names) {
  std::vector<std::int16_t> s;
  for (const auto& n : names) {
    const auto c = sgtest::clip(n);
    s.insert(s.end(), c.begin(), c.end());
  }
  return s;
}
std::int16_t sat(int v) { return static_cast<std::int16_t>(std::clamp(v, -32768, 32767)); }
constexpr long kChunk = 256;  // AlsaSinkOptions::chunk_frames
}  // namespace

// A tick does not wait for the phrase speaking: it is mixed over it within a chunk, the phrase
// lowered 6 dB under it and going on where it was (neither cut nor delayed), the sum saturated.
// Found in the file PCM as the one chunk boundary where the samples are exactly that mix.
TEST(FeedbackAlsa, EarconIsMixedOverAPhraseAtOnce) {
  alsa_setup();
  std::vector<std::string> words;
  for (int i = 1; i <= 10; ++i) words.push_back("n" + std::to_string(i));
  const auto phrase = concat(words), tick = sgtest::clip("tick");
  SinkLog log;
  {
    AlsaSinkOptions o;
    o.device = "sg_mix";
    o.stereo = false;
    AlsaAudioSink sink(o, bank(1.0f), log.events());
    sink.play(utt(1, 4, words));
    std::this_thread::sleep_for(std::chrono::milliseconds(400));
    Utterance t = utt(2, 1, {"tick"});
    t.delivery = Delivery::kMix;
    sink.play(t);
    ASSERT_TRUE(sink.drain(std::chrono::seconds(10)));
    EXPECT_EQ(sink.counters().played, 2u);
    EXPECT_EQ(sink.counters().cut, 0u);
  }
  EXPECT_EQ(log.started(), (std::vector<std::uint64_t>{1, 2}));
  const auto cap = sgtest::read_raw(kDir / "sg_mix.raw");
  ASSERT_GE(cap.size(), phrase.size());
  long at = -1;
  for (long k = kChunk; k + static_cast<long>(tick.size()) <= static_cast<long>(phrase.size()) && at < 0;
       k += kChunk) {
    bool all = true;
    for (std::size_t i = 0; i < tick.size() && all; ++i) all = cap[k + i] == sat(phrase[k + i] / 2 + tick[i]);
    if (all) at = k;
  }
  ASSERT_GE(at, 0) << "no chunk holds the phrase with the tick mixed over it";
  std::printf("tick mixed in at sample %ld (%.3f s), %zu samples into a %zu-sample phrase\n", at,
              static_cast<double>(at) / kSoundRate, static_cast<std::size_t>(at), phrase.size());
  // Within the phrase (it did not wait for its end: 4 s of numbers, played 0.4 s in).
  EXPECT_LT(at + static_cast<long>(tick.size()), static_cast<long>(phrase.size()) / 2);
  long differ = 0;
  for (long j = 0; j < static_cast<long>(phrase.size()); ++j)
    if (j < at || j >= at + static_cast<long>(tick.size())) differ += cap[j] != phrase[j];
  EXPECT_EQ(differ, 0) << "the phrase around the tick is not the phrase";
}

// A step's phrase cuts what its step made stale ("stairs ahead" when the first step comes), drops
// the stale ones waiting, and when a phrase that outranks it is speaking (camera lost) its step is
// marked at once by a tick mixed over that phrase instead of waiting behind it.
TEST(FeedbackAlsa, StepPhraseCutsTheStaleAndIsTickedOverAHigherPhrase) {
  alsa_setup();
  SinkLog log;
  auto step_utt = [](std::uint64_t id, Cue c, std::vector<std::string> clips) {
    Utterance u = utt(id, cue_priority(c), std::move(clips));
    u.delivery = Delivery::kCut;
    u.kinds = cue_bit(c);
    u.supersedes = cue_supersedes(c) & ~u.kinds;
    u.fallback = {"tick"};
    return u;
  };
  AlsaSinkOptions o;
  o.device = "sg_step";
  o.stereo = false;
  {
    AlsaAudioSink sink(o, bank(1.0f), log.events());
    Utterance a = utt(1, cue_priority(Cue::kStairsAhead), {"stairs_up", "n3", "metres"});
    a.kinds = cue_bit(Cue::kStairsAhead);
    sink.play(a);
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    sink.play(step_utt(2, Cue::kFirstStep, {"first_step"}));
    ASSERT_TRUE(sink.drain(std::chrono::seconds(10)));
    EXPECT_EQ(sink.counters().cut, 1u);
    Utterance lost = utt(3, cue_priority(Cue::kCameraLost), {"camera_lost"});
    lost.kinds = cue_bit(Cue::kCameraLost);
    sink.play(lost);
    Utterance ahead = utt(4, cue_priority(Cue::kStairsAhead), {"stairs_down"});
    ahead.kinds = cue_bit(Cue::kStairsAhead);
    sink.play(ahead);  // waits behind "camera lost"...
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    sink.play(step_utt(5, Cue::kCount, {"n5"}));  // ... and is made stale by the next step
    ASSERT_TRUE(sink.drain(std::chrono::seconds(10)));
    const auto c = sink.counters();
    EXPECT_EQ(c.cut, 1u);
    EXPECT_EQ(c.superseded, 1u);
    EXPECT_EQ(c.fallbacks, 1u);
  }
  EXPECT_EQ(log.started(), (std::vector<std::uint64_t>{1, 2, 3, 5}));
  const auto cap = sgtest::read_raw(kDir / "sg_step.raw");
  const auto h = sgtest::heard(cap, {"stairs_up", "first_step", "stairs_down", "n5", "metres"});
  EXPECT_EQ(sgtest::names_of(h), (std::vector<std::string>{"first_step"}));
  // "camera lost" whole, a tick mixed over it (the phrase under it lowered: a lower correlation).
  const auto lost = sgtest::find_all(cap, "camera_lost", 0.5);
  ASSERT_EQ(lost.size(), 1u);
  std::printf("camera_lost with the count's tick over it: correlation %.3f\n", lost[0].score);
  const auto tick = sgtest::clip("tick"), cl = sgtest::clip("camera_lost");
  long ticked = 0;  // chunks of the phrase with exactly the tick mixed over them
  for (long k = 0; k + static_cast<long>(tick.size()) <= static_cast<long>(cl.size()); k += kChunk) {
    bool all = true;
    for (std::size_t i = 0; i < tick.size() && all; ++i)
      all = cap[lost[0].pos + k + i] == sat(cl[k + i] / 2 + tick[i]);
    ticked += all;
  }
  EXPECT_EQ(ticked, 1);
}
// Stereo through a file PCM: a staircase at 3 o'clock is heard at least 6 dB louder on the right,
// one at 9 o'clock on the left, one straight ahead the same on both; each channel is the clip
// times its gain.
TEST(FeedbackAlsa, CuesArePannedByTheStaircasesBearing) {
  alsa_setup();
  const auto clip = sgtest::clip("stairs_up");
  const long len = static_cast<long>(clip.size());
  const long next = (len + kChunk - 1) / kChunk * kChunk;  // the next phrase starts at a chunk
  const float bearings[3] = {static_cast<float>(M_PI / 2), static_cast<float>(-M_PI / 2), 0.f};
  {
    AlsaSinkOptions o;
    o.device = "sg_pan";
    o.max_age_s = 10.0;
    AlsaAudioSink sink(o, bank(1.0f), {});
    for (int i = 0; i < 3; ++i) {
      CueEvent e;
      e.bearing_rad = bearings[i];
      Utterance u = utt(static_cast<std::uint64_t>(i + 1), 4, {"stairs_up"});
      u.pan = cue_pan(e);
      sink.play(u);
    }
    ASSERT_TRUE(sink.drain(std::chrono::seconds(10)));
    EXPECT_EQ(sink.counters().channels, 2);
  }
  const auto st = sgtest::split(sgtest::read_raw(kDir / "sg_pan.raw"));
  ASSERT_GE(static_cast<long>(st.left.size()), 2 * next + len);
  double db[3];
  for (int i = 0; i < 3; ++i) {
    const std::size_t from = static_cast<std::size_t>(i * next), to = from + static_cast<std::size_t>(len);
    db[i] = 10.0 * std::log10(sgtest::energy(st.right, from, to) / sgtest::energy(st.left, from, to));
    CueEvent e;
    e.bearing_rad = bearings[i];
    float gl = 0.f, gr = 0.f;
    pan_gains(cue_pan(e), gl, gr);
    long off = 0;
    for (long j = 0; j < len; ++j)
      off +=
          st.left[from + j] != std::lround(clip[j] * gl) || st.right[from + j] != std::lround(clip[j] * gr);
    EXPECT_EQ(off, 0) << i;
  }
  std::printf("right - left: 3 o'clock %+.1f dB, 9 o'clock %+.1f dB, 12 o'clock %+.1f dB\n", db[0], db[1],
              db[2]);
  EXPECT_GE(db[0], 6.0);
  EXPECT_LE(db[1], -6.0);
  EXPECT_NEAR(db[2], 0.0, 0.01);
}

// A device that refuses two channels (a mono card) is served mono: the cue is the clip itself.
TEST(FeedbackAlsa, MonoDeviceIsServedMono) {
  alsa_setup();
  SinkLog log;
  {
    AlsaSinkOptions o;
    o.device = "sg_monodev";
    AlsaAudioSink sink(o, bank(1.0f), log.events());
    Utterance u = utt(1, 4, {"ready"});
    u.pan = 0.8f;  // ignored: one channel
    sink.play(u);
    ASSERT_TRUE(sink.drain(std::chrono::seconds(10)));
    EXPECT_EQ(sink.counters().channels, 1);
  }
  const auto h = sgtest::heard(sgtest::read_raw(kDir / "sg_monodev.raw"), {"ready"});
  ASSERT_EQ(sgtest::names_of(h), (std::vector<std::string>{"ready"}));
  EXPECT_EQ(h[0].pos, 0);
  EXPECT_GT(h[0].score, 0.999);
  const auto info = log.info();
  ASSERT_EQ(info.size(), 1u);
  EXPECT_NE(info[0].find("refused two channels"), std::string::npos) << info[0];
}
