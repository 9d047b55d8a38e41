// The sounds and the ALSA sink heard for real: an ALSA `type file` PCM (a test configuration
// through ALSA_CONFIG_PATH) writes exactly the samples the sink plays; the cues are found in
// them, in order, by correlation with the WAVs.
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <thread>

#include "feedback_test_util.hpp"
#include "stairguide/feedback/audio_sink.hpp"
#include "stairguide/feedback/cue.hpp"

using namespace stairguide::feedback;
namespace fs = std::filesystem;

namespace {

// One folder per process: ctest runs each test case in a process of its own, two at once, and a
// case that rewrote the shared asound.conf took away the PCM another had just added.
const fs::path kDir = fs::path(STAIRGUIDE_BINARY_DIR) / ("feedback_audio_files." + std::to_string(getpid()));
// Kept for a look when a case failed, removed otherwise.
struct RemoveFilesWhenPassed : ::testing::Environment {
  void TearDown() override {
    std::error_code ec;
    if (!::testing::UnitTest::GetInstance()->Failed()) fs::remove_all(kDir, ec);
  }
};
[[maybe_unused]] ::testing::Environment* const kRemoveFiles =
    ::testing::AddGlobalTestEnvironment(new RemoveFilesWhenPassed);

/// ALSA reads its configuration once per process (and again when the file changes): one file
/// with every PCM the tests use, set before the first ALSA call.
void alsa_setup() {
  static bool done = false;
  if (done) return;
  done = true;
  sgtest::write_alsa_config(kDir / "asound.conf", kDir, {"sg_order", "sg_cut", "sg_latency"});
  setenv("ALSA_CONFIG_PATH", (kDir / "asound.conf").c_str(), 1);
}

SoundBank bank(float volume = 0.8f) {
  return load_sound_bank(sgtest::sounds_dir(), all_clip_names(), volume);
}

Utterance utt(std::uint64_t id, int priority, std::vector<std::string> clips) {
  Utterance u;
  u.id = id;
  u.priority = priority;
  u.clips = std::move(clips);
  return u;
}

}  // namespace

TEST(FeedbackSounds, EveryCueClipIsThereAndSmall) {
  const SoundBank b = bank(1.0f);
  EXPECT_TRUE(b.problems.empty()) << ::testing::PrintToString(b.problems);
  EXPECT_EQ(b.clips.size(), all_clip_names().size());
  std::uintmax_t bytes = 0;
  for (const auto& [name, s] : b.clips) {
    const double secs = static_cast<double>(s.size()) / kSoundRate;
    EXPECT_GE(secs, 0.03) << name;
    EXPECT_LE(secs, 2.0) << name;
    bytes += fs::file_size(sgtest::sounds_dir() + "/" + name + ".wav");
  }
  EXPECT_LT(bytes, 3u * 1024 * 1024);
  // Every cue the policy can give has all its clips.
  for (int c = 0; c <= static_cast<int>(Cue::kEndOfStairs); ++c)
    for (int dir : {-1, 1}) {
      CueEvent e;
      e.cue = static_cast<Cue>(c);
      e.direction = dir;
      e.number = 7;
      e.clock = 2;
      for (const auto& clip : clips_for(e)) EXPECT_NE(b.find(clip), nullptr) << token(e) << ": " << clip;
    }
}

TEST(FeedbackSounds, MissingAndBadFilesAreNamed) {
  const fs::path d = kDir / "bad_sounds";
  fs::create_directories(d);
  { std::ofstream(d / "text.wav") << "this is not a wave file"; }
  {
    // A valid header of a stereo file.
    std::ofstream f(d / "stereo.wav", std::ios::binary);
    const unsigned char h[44] = {'R',  'I', 'F', 'F', 40, 0, 0,   0,   'W', 'A',  'V',  'E', 'f', 'm',  't',
                                 ' ',  16,  0,   0,   0,  1, 0,   2,   0,   0x22, 0x56, 0,   0,   0x88, 0x58,
                                 0x01, 0,   4,   0,   16, 0, 'd', 'a', 't', 'a',  4,    0,   0,   0};
    f.write(reinterpret_cast<const char*>(h), 44);
    f.write("\0\0\0\0", 4);
  }
  fs::copy_file(sgtest::sounds_dir() + "/tick.wav", d / "tick.wav", fs::copy_options::overwrite_existing);
  const SoundBank b = load_sound_bank(d.string(), {"tick", "gone", "text", "stereo"}, 1.0f);
  ASSERT_EQ(b.problems.size(), 3u);
  EXPECT_EQ(b.problems[0], (d / "gone.wav").string() + ": missing or unreadable");
  EXPECT_EQ(b.problems[1], (d / "text.wav").string() + ": not a RIFF/WAVE file");
  EXPECT_NE(b.problems[2].find("stereo.wav: not 16-bit mono PCM"), std::string::npos) << b.problems[2];
  EXPECT_NE(b.find("tick"), nullptr);
  EXPECT_EQ(b.clips.size(), 1u);
}

TEST(FeedbackAlsa, CuesHeardInOrderThroughAFilePcm) {
  alsa_setup();
  std::vector<std::uint64_t> started;
  std::mutex m;
  {
    AudioEvents ev;
    ev.on_start = [&](std::uint64_t id, SteadyClock::time_point) {
      std::lock_guard<std::mutex> lk(m);
      started.push_back(id);
    };
    AlsaSinkOptions o;
    o.device = "sg_order";
    o.max_age_s = 10.0;  // the three wait behind each other longer than the default 3 s
    AlsaAudioSink sink(o, bank(), ev);
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
  EXPECT_EQ(started, (std::vector<std::uint64_t>{1, 3, 2}));
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
  std::vector<std::string> warnings;
  std::mutex m;
  AudioEvents ev;
  ev.warn = [&](const std::string& s) {
    std::lock_guard<std::mutex> lk(m);
    warnings.push_back(s);
  };
  AlsaSinkOptions o;
  o.device = "sg_no_such_pcm";
  o.retry_s = 0.3;
  o.max_age_s = 1.0;
  AlsaAudioSink sink(o, bank(), ev);
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
  std::lock_guard<std::mutex> lk(m);
  ASSERT_EQ(warnings.size(), 1u);  // said once, not on every retry
  EXPECT_NE(warnings[0].find("cannot open ALSA device 'sg_no_such_pcm'"), std::string::npos) << warnings[0];
}

TEST(FeedbackAlsa, DeviceThatAppearsLaterIsOpenedAtTheNextRetry) {
  alsa_setup();
  std::vector<std::string> info;
  std::mutex m;
  AudioEvents ev;
  ev.info = [&](const std::string& s) {
    std::lock_guard<std::mutex> lk(m);
    info.push_back(s);
  };
  AlsaSinkOptions o;
  o.device = "sg_late";
  o.retry_s = 0.3;
  o.max_age_s = 10.0;
  fs::remove(kDir / "sg_late.raw");
  {
    AlsaAudioSink sink(o, bank(), ev);
    sink.play(utt(1, 4, {"camera_back"}));
    std::this_thread::sleep_for(std::chrono::milliseconds(400));
    EXPECT_GE(sink.counters().open_failures, 1u);
    // The device comes (ALSA reads its configuration again when the file changes). ALSA tells a
    // changed file by its modification time in whole seconds: a rewrite within the same second
    // as the first write went unseen (the case failed on half its runs), so wait for the next.
    std::this_thread::sleep_for(std::chrono::milliseconds(1100));
    sgtest::write_alsa_config(kDir / "asound.conf", kDir, {"sg_order", "sg_cut", "sg_latency", "sg_late"});
    ASSERT_TRUE(sink.drain(std::chrono::seconds(5)));
    EXPECT_TRUE(sink.counters().device_open);
    EXPECT_EQ(sink.counters().played, 1u);
    {
      std::lock_guard<std::mutex> lk(m);
      ASSERT_EQ(info.size(), 1u);
      EXPECT_NE(info[0].find("'sg_late' open"), std::string::npos) << info[0];
    }
  }  // closed: the file PCM has written everything
  const auto h = sgtest::heard(sgtest::read_raw(kDir / "sg_late.raw"), {"camera_back", "camera_lost"});
  EXPECT_EQ(sgtest::names_of(h), (std::vector<std::string>{"camera_back"}));
}
