// The sounds (every cue's clips there, short, in every language; bad files named) and the pan law
// the sinks place a cue by. The ALSA sink that plays them is heard in test_runtime_devices_audio.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "feedback_test_util.hpp"
#include "stairguide/feedback/audio_sink.hpp"
#include "stairguide/feedback/cue.hpp"

using namespace stairguide::feedback;
namespace fs = std::filesystem;

namespace {
const fs::path kDir = sgtest::process_dir("feedback_audio_files");
}  // namespace

TEST(FeedbackSounds, EveryCueClipIsThereAndSmall) {
  const SoundBank b = load_sound_bank(sgtest::sounds_dir(), all_clip_names(), 1.0f);
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
  for (int c = 0; c < kCueKinds; ++c)
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
TEST(FeedbackAlsa, PanLawIsConstantPowerAndNeverAllInOneEar) {
  float l = 0.f, r = 0.f;
  pan_gains(0.f, l, r);
  EXPECT_NEAR(l, std::sqrt(0.5f), 1e-6);
  EXPECT_NEAR(r, std::sqrt(0.5f), 1e-6);
  for (float p : {-1.f, -0.8f, -0.3f, 0.2f, 0.8f, 1.f}) {
    pan_gains(p, l, r);
    EXPECT_NEAR(l * l + r * r, 1.f, 1e-6) << p;
  }
  CueEvent e;
  e.bearing_rad = static_cast<float>(M_PI / 2);  // 3 o'clock
  EXPECT_FLOAT_EQ(cue_pan(e), kMaxPan);
  e.bearing_rad = static_cast<float>(-M_PI / 2);  // 9 o'clock
  EXPECT_FLOAT_EQ(cue_pan(e), -kMaxPan);
  e.bearing_rad = static_cast<float>(M_PI);  // behind: as far as the side
  EXPECT_FLOAT_EQ(cue_pan(e), kMaxPan);
  e.bearing_rad = std::numeric_limits<float>::quiet_NaN();
  EXPECT_FLOAT_EQ(cue_pan(e), 0.f);
  pan_gains(kMaxPan, l, r);
  EXPECT_GT(l, 0.1f);  // the far ear still hears it
}

// Every language's folder (tools/make-sounds --lang L) has the words of every clip the English set
// has, numbers included, and no earcon (those are shared from sounds/ itself); each is a short
// 16-bit mono clip at the sink's rate. en, es, de and fr at least.
TEST(FeedbackSounds, EveryLanguageHasEveryWord) {
  std::vector<std::string> words;
  for (const auto& n : all_clip_names())
    if (!is_earcon_clip(n)) words.push_back(n);
  std::vector<std::string> langs;
  for (const auto& e : fs::directory_iterator(sgtest::sounds_dir()))
    if (e.is_directory()) langs.push_back(e.path().filename().string());
  for (const char* l : {"es", "de", "fr"})
    EXPECT_NE(std::find(langs.begin(), langs.end(), l), langs.end()) << "no sounds/" << l;
  for (const auto& l : langs) {
    const std::string dir = sgtest::sounds_dir() + "/" + l;
    const SoundBank b = load_sound_bank(dir, words, 1.0f);
    EXPECT_TRUE(b.problems.empty()) << l << ": " << ::testing::PrintToString(b.problems);
    for (const auto& [name, s] : b.clips)
      EXPECT_LE(static_cast<double>(s.size()) / kSoundRate, 2.0) << l << "/" << name;
    std::size_t files = 0;
    for (const auto& e : fs::directory_iterator(dir)) {
      ++files;
      EXPECT_FALSE(is_earcon_clip(e.path().stem().string())) << l << ": " << e.path();
    }
    EXPECT_EQ(files, words.size()) << l;
    // The words are the language's own: "ready" differs from the English clip.
    EXPECT_NE(b.find("ready") ? *b.find("ready") : std::vector<std::int16_t>{}, sgtest::clip("ready")) << l;
  }
  // The set a language names: its folder, the earcons from the top; a missing one falls back.
  const SoundSet es = sound_set_for(sgtest::sounds_dir(), "es");
  EXPECT_EQ(es.speech_dir, sgtest::sounds_dir() + "/es");
  EXPECT_EQ(es.earcon_dir, sgtest::sounds_dir());
  EXPECT_TRUE(es.problem.empty());
  const SoundSet en = sound_set_for(sgtest::sounds_dir(), "en");
  EXPECT_EQ(en.speech_dir, sgtest::sounds_dir());
  const SoundSet xx = sound_set_for(sgtest::sounds_dir(), "xx");
  EXPECT_EQ(xx.speech_dir, sgtest::sounds_dir());
  EXPECT_EQ(xx.language, "en");
  EXPECT_NE(xx.problem.find("no sounds for language 'xx'"), std::string::npos) << xx.problem;
}
