#pragma once
/// \file sound_bank.hpp
/// The WAV cues, read once at start into memory (16-bit mono PCM at kSoundRate).

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace stairguide::feedback {

/// Hz: the rate of every WAV in sounds/ and the rate the sink opens the device at.
constexpr int kSoundRate = 22050;

/// Reads a RIFF/WAVE file of 16-bit mono PCM. False with `why` (what is wrong with it) otherwise.
bool read_wav(const std::string& path, std::vector<std::int16_t>& samples, int& rate, std::string& why);

struct SoundBank {
  std::map<std::string, std::vector<std::int16_t>> clips;  ///< by name (file name without .wav)
  /// One line per clip that could not be used: "DIR/NAME.wav: missing" / ": not 16-bit mono ...".
  std::vector<std::string> problems;
  const std::vector<std::int16_t>* find(const std::string& name) const {
    const auto it = clips.find(name);
    return it == clips.end() ? nullptr : &it->second;
  }
};

/// Where the clips of a language are: the spoken ones in `speech_dir`, the earcons (no words, one
/// set for all) in `earcon_dir`.
struct SoundSet {
  std::string speech_dir, earcon_dir;
  std::string language;  ///< the language spoken ("en" when the one asked for is missing)
  std::string problem;   ///< why the language asked for is not spoken ("" when it is)
};

/// The set for `language` under `sounds_dir`: English is `sounds_dir` itself (where installs have
/// always had it); another language is the folder `sounds_dir/<language>` when it exists, else
/// English with `problem` naming the language and the folder looked for.
SoundSet sound_set_for(const std::string& sounds_dir, const std::string& language);

/// Loads `names` from `dir` (DIR/NAME.wav), scaled by `volume` (0..1). A clip that is missing,
/// unreadable, or not 16-bit mono at kSoundRate is left out and named in `problems`.
SoundBank load_sound_bank(const std::string& dir, const std::vector<std::string>& names, float volume);

}  // namespace stairguide::feedback
