#pragma once
// Helpers of the feedback tests: an ALSA configuration whose PCMs write what is played to raw
// files (`type file` over `type null`), finding the cues in the captured samples by normalised
// cross-correlation with the WAVs, and stairguided run end to end with its cues heard that way.
#include <gtest/gtest.h>
#include <stdlib.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "stairguide/feedback/sound_bank.hpp"

namespace sgtest {

namespace fs = std::filesystem;

/// Adds the real 7-Scenes kitchen (no stairs, no drop) to `runs` as {name, its folder} when the
/// shared data has it; says so on stderr when it does not.
inline void add_real_kitchen(std::vector<std::pair<std::string, std::string>>& runs,
                             const std::string& name) {
  const fs::path kitchen = fs::path(STAIRGUIDE_SHARED_DATA) / "7scenes-redkitchen-0000-0299";
  if (fs::exists(kitchen))
    runs.push_back({name, kitchen.string()});
  else
    std::fprintf(stderr, "note: %s absent, the %s run is skipped\n", kitchen.c_str(), name.c_str());
}

inline std::string sounds_dir() { return std::string(STAIRGUIDE_SOURCE_DIR) + "/sounds"; }

/// A folder of this test process's own, `NAME.PID` in the build tree (ctest runs each case in a
/// process of its own, two at once), removed when the process ends with every case passed and
/// kept for a look when one failed. Meant for a namespace-scope constant of the test file.
inline fs::path process_dir(const std::string& name) {
  struct RemoveWhenPassed : ::testing::Environment {
    explicit RemoveWhenPassed(fs::path d) : dir(std::move(d)) {}
    void TearDown() override {
      std::error_code ec;
      if (!::testing::UnitTest::GetInstance()->Failed()) fs::remove_all(dir, ec);
    }
    fs::path dir;
  };
  const fs::path dir = fs::path(STAIRGUIDE_BINARY_DIR) / (name + "." + std::to_string(getpid()));
  ::testing::AddGlobalTestEnvironment(new RemoveWhenPassed(dir));
  return dir;
}

/// Writes `conf` with one file PCM per name (pcm.NAME writes DIR/NAME.raw, S16 raw, interleaved
/// as many channels as the sink opened it with). The names in `mono_only` are PCMs that refuse
/// two channels (a `multi` PCM of one binding over the file PCM), as a mono sound card does.
inline void write_alsa_config(const fs::path& conf, const fs::path& dir,
                              const std::vector<std::string>& names,
                              const std::vector<std::string>& mono_only = {}) {
  fs::create_directories(dir);
  std::ofstream f(conf);
  for (const auto& n : names)
    f << "pcm." << n << " {\n  type file\n  slave.pcm { type null }\n  file \""
      << (dir / (n + ".raw")).string() << "\"\n  format \"raw\"\n}\n";
  for (const auto& n : mono_only)
    f << "pcm." << n << "_file {\n  type file\n  slave.pcm { type null }\n  file \""
      << (dir / (n + ".raw")).string() << "\"\n  format \"raw\"\n}\npcm." << n
      << " {\n  type multi\n  slaves.a { pcm \"" << n
      << "_file\" channels 1 }\n  bindings.0 { slave a channel 0 }\n}\n";
}

inline std::vector<std::int16_t> read_raw(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  const std::vector<char> b((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  std::vector<std::int16_t> s(b.size() / 2);
  for (std::size_t i = 0; i < s.size(); ++i)
    s[i] = static_cast<std::int16_t>(static_cast<unsigned char>(b[2 * i]) |
                                     (static_cast<unsigned char>(b[2 * i + 1]) << 8));
  return s;
}

/// A stereo capture split into its channels.
struct Stereo {
  std::vector<std::int16_t> left, right;
  /// (left + right) / 2: a centred cue is its clip scaled, a panned one too (for `heard`).
  std::vector<std::int16_t> mid() const {
    std::vector<std::int16_t> m(left.size());
    for (std::size_t i = 0; i < m.size(); ++i) m[i] = static_cast<std::int16_t>((left[i] + right[i]) / 2);
    return m;
  }
};
inline Stereo split(const std::vector<std::int16_t>& interleaved) {
  Stereo s;
  for (std::size_t i = 0; i + 1 < interleaved.size(); i += 2) {
    s.left.push_back(interleaved[i]);
    s.right.push_back(interleaved[i + 1]);
  }
  return s;
}
/// Energy of samples [from, to) (whole capture by default).
inline double energy(const std::vector<std::int16_t>& s, std::size_t from = 0,
                     std::size_t to = ~std::size_t{0}) {
  double e = 0.0;
  for (std::size_t i = from; i < std::min(to, s.size()); ++i) e += static_cast<double>(s[i]) * s[i];
  return e;
}

/// The samples of clip `name` of `dir` (the English set by default; sounds_dir()/es for Spanish).
inline std::vector<std::int16_t> clip(const std::string& name, const std::string& dir = sounds_dir()) {
  std::vector<std::int16_t> s;
  int rate = 0;
  std::string why;
  stairguide::feedback::read_wav(dir + "/" + name + ".wav", s, rate, why);
  return s;
}

struct Hit {
  std::string name;
  long pos = -1;  ///< sample index in the capture
  double score = 0.0;
};

/// Every place `name`'s WAV (of `dir`) occurs in `cap` with a normalised correlation above
/// `min_score` (peaks at least a clip's length apart).
inline std::vector<Hit> find_all(const std::vector<std::int16_t>& cap, const std::string& name,
                                 double min_score = 0.97, const std::string& dir = sounds_dir()) {
  const std::vector<std::int16_t> c = clip(name, dir);
  std::vector<Hit> hits;
  if (c.empty() || cap.size() < c.size()) return hits;
  cv::Mat a(1, static_cast<int>(cap.size()), CV_32F), t(1, static_cast<int>(c.size()), CV_32F), r;
  for (std::size_t i = 0; i < cap.size(); ++i) a.at<float>(0, static_cast<int>(i)) = cap[i];
  for (std::size_t i = 0; i < c.size(); ++i) t.at<float>(0, static_cast<int>(i)) = c[i];
  cv::matchTemplate(a, t, r, cv::TM_CCOEFF_NORMED);
  const int n = r.cols, len = static_cast<int>(c.size());
  for (int i = 0; i < n; ++i) {
    const float v = r.at<float>(0, i);
    if (!(v >= min_score)) continue;
    // the peak of this run
    int best = i;
    for (int j = i; j < std::min(n, i + len); ++j)
      if (r.at<float>(0, j) > r.at<float>(0, best)) best = j;
    hits.push_back({name, best, r.at<float>(0, best)});
    i = best + len - 1;
  }
  return hits;
}

/// The clips among `names` heard in `cap`, in the order heard.
inline std::vector<Hit> heard(const std::vector<std::int16_t>& cap, const std::vector<std::string>& names,
                              double min_score = 0.97) {
  std::vector<Hit> all;
  for (const auto& n : names)
    for (const auto& h : find_all(cap, n, min_score)) all.push_back(h);
  std::sort(all.begin(), all.end(), [](const Hit& a, const Hit& b) { return a.pos < b.pos; });
  return all;
}

inline std::vector<std::string> names_of(const std::vector<Hit>& h) {
  std::vector<std::string> n;
  for (const auto& x : h) n.push_back(x.name);
  return n;
}

/// What stairguided did in a replay run by run_daemon().
struct DaemonRun {
  int code = -1;
  std::vector<std::string> cues;                     ///< frame-line cue tokens, in frame order
  std::vector<std::pair<double, std::string>> told;  ///< each cue token (split at '+') with its frame's ts
  std::string summary;                               ///< the summary line
  Stereo stereo;                                     ///< what was played (stereo: the default)
  std::vector<std::int16_t> audio;                   ///< (left + right) / 2 of it
  std::vector<std::pair<double, int>> edges;         ///< the buzzer's: ms, level
  std::string log;                                   ///< stderr
};

/// Runs stairguided on `replay` with `extra_args`, its cues played to the ALSA file PCM `name`
/// (DIR/NAME.raw) and its buzzer's edges written to DIR/NAME.edges; `extra_yaml` is added to the
/// config's feedback section (indented keys).
inline DaemonRun run_daemon(const fs::path& dir, const std::string& name, const std::string& replay,
                            const std::string& extra_args, const std::string& extra_yaml = "") {
  fs::create_directories(dir);
  const fs::path conf = dir / (name + ".yaml"), alsa = dir / (name + ".asound.conf");
  const fs::path edges = dir / (name + ".edges"), err = dir / (name + ".stderr");
  write_alsa_config(alsa, dir, {name});
  fs::remove(dir / (name + ".raw"));
  {
    std::ofstream f(conf);
    f << "feedback:\n  audio_device: \"default\"\n  sounds_dir: \"" << sounds_dir()
      << "\"\n  gpio_chip: \"file:" << edges.string() << "\"\n"
      << extra_yaml;
  }
  const std::string cmd = "ALSA_CONFIG_PATH=" + alsa.string() + " " + STAIRGUIDED + " --config " +
                          conf.string() + " --replay " + replay + " --audio " + name + " " + extra_args +
                          " 2>" + err.string();
  DaemonRun r;
  std::FILE* p = popen(cmd.c_str(), "r");
  if (!p) return r;
  std::array<char, 8192> buf{};
  while (std::fgets(buf.data(), buf.size(), p)) {
    const std::string line = buf.data();
    if (line.rfind("summary ", 0) == 0) r.summary = line;
    const auto at = line.find(" cue=");
    if (line.rfind("frame=", 0) != 0 || at == std::string::npos) continue;
    std::istringstream is(line.substr(at + 5));
    std::string tok;
    is >> tok;
    if (tok == "-") continue;
    r.cues.push_back(tok);
    const auto ts = line.find(" ts=");
    const double t = ts == std::string::npos ? -1.0 : std::atof(line.c_str() + ts + 4);
    std::istringstream parts(tok);
    for (std::string one; std::getline(parts, one, '+');) r.told.push_back({t, one});
  }
  const int st = pclose(p);
  r.code = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  r.stereo = split(read_raw(dir / (name + ".raw")));
  r.audio = r.stereo.mid();
  std::ifstream ef(edges);
  double t;
  int v;
  while (ef >> t >> v) r.edges.push_back({t, v});
  std::ifstream lf(err);
  std::stringstream ss;
  ss << lf.rdbuf();
  r.log = ss.str();
  return r;
}

}  // namespace sgtest
