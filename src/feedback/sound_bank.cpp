#include "stairguide/feedback/sound_bank.hpp"

#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>

namespace stairguide::feedback {

namespace {
std::uint32_t u32(const unsigned char* p) {
  return static_cast<std::uint32_t>(p[0]) | static_cast<std::uint32_t>(p[1]) << 8 |
         static_cast<std::uint32_t>(p[2]) << 16 | static_cast<std::uint32_t>(p[3]) << 24;
}
std::uint16_t u16(const unsigned char* p) { return static_cast<std::uint16_t>(p[0] | p[1] << 8); }
}  // namespace

bool read_wav(const std::string& path, std::vector<std::int16_t>& samples, int& rate, std::string& why) {
  std::ifstream f(path, std::ios::binary);
  if (!f) {
    why = "missing or unreadable";
    return false;
  }
  const std::vector<unsigned char> b((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  if (b.size() < 12 || std::memcmp(b.data(), "RIFF", 4) != 0 || std::memcmp(b.data() + 8, "WAVE", 4) != 0) {
    why = "not a RIFF/WAVE file";
    return false;
  }
  bool have_fmt = false;
  std::size_t pos = 12;
  while (pos + 8 <= b.size()) {
    const std::uint32_t len = u32(&b[pos + 4]);
    const std::size_t body = pos + 8;
    if (body + len > b.size()) {
      why = "truncated chunk";
      return false;
    }
    if (std::memcmp(&b[pos], "fmt ", 4) == 0 && len >= 16) {
      const std::uint16_t tag = u16(&b[body]), channels = u16(&b[body + 2]), bits = u16(&b[body + 14]);
      rate = static_cast<int>(u32(&b[body + 4]));
      // 0xFFFE: WAVE_FORMAT_EXTENSIBLE, whose sub-format is PCM for the files sox writes.
      if ((tag != 1 && tag != 0xFFFE) || channels != 1 || bits != 16) {
        why = "not 16-bit mono PCM (format " + std::to_string(tag) + ", " + std::to_string(channels) +
              " channels, " + std::to_string(bits) + " bits)";
        return false;
      }
      have_fmt = true;
    } else if (std::memcmp(&b[pos], "data", 4) == 0) {
      if (!have_fmt) {
        why = "data before the fmt chunk";
        return false;
      }
      samples.resize(len / 2);
      for (std::size_t i = 0; i < samples.size(); ++i)
        samples[i] = static_cast<std::int16_t>(u16(&b[body + 2 * i]));
      if (samples.empty()) {
        why = "no samples";
        return false;
      }
      return true;
    }
    pos = body + len + (len & 1);
  }
  why = have_fmt ? "no data chunk" : "no fmt chunk";
  return false;
}

SoundSet sound_set_for(const std::string& sounds_dir, const std::string& language) {
  SoundSet set{sounds_dir, sounds_dir, "en", ""};
  if (language.empty() || language == "en") return set;
  const std::string dir = sounds_dir + "/" + language;
  struct stat st {};
  if (::stat(dir.c_str(), &st) == 0 && S_ISDIR(st.st_mode)) {
    set.speech_dir = dir;
    set.language = language;
  } else {
    set.problem =
        "no sounds for language '" + language + "' (feedback.language): " + dir + " is not a folder";
  }
  return set;
}

SoundBank load_sound_bank(const std::string& dir, const std::vector<std::string>& names, float volume) {
  SoundBank bank;
  const float g = std::min(1.f, std::max(0.f, volume));
  for (const auto& n : names) {
    const std::string path = dir + "/" + n + ".wav";
    std::vector<std::int16_t> s;
    int rate = 0;
    std::string why;
    if (!read_wav(path, s, rate, why)) {
      bank.problems.push_back(path + ": " + why);
      continue;
    }
    if (rate != kSoundRate) {
      bank.problems.push_back(path + ": " + std::to_string(rate) + " Hz, expected " +
                              std::to_string(kSoundRate));
      continue;
    }
    if (g != 1.f)
      for (auto& v : s) v = static_cast<std::int16_t>(std::lround(v * g));
    bank.clips[n] = std::move(s);
  }
  return bank;
}

}  // namespace stairguide::feedback
