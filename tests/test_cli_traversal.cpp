// `stairguide replay`, `eval-traversal` and `bench traversal` as a user runs them, the replay held
// to the daemon's decisions, and its failures named.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <ostream>
#include <string>
#include <vector>

#include "cli_test_util.hpp"

using cli_test::run;

namespace {
std::string tmp(const std::string& name) { return cli_test::tmp("cli_traversal_", name); }

long lines_of(const std::string& path) {
  std::ifstream in(path);
  long n = 0;
  std::string l;
  while (std::getline(in, l)) ++n;
  return n;
}
}  // namespace

// A 3-step climb replayed end to end (odometry, perception, stairs, traversal): the three files,
// a line per frame, and eval-traversal's JSON with the keys and the count exact.
TEST(CliTraversal, ReplayThenEvalAClimb) {
  const std::string dir = tmp("climb3");
  std::filesystem::remove_all(dir);
  const auto r = run("replay synth:climb_3_steps:300:11 --out " + dir);
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(lines_of(dir + "/frames.jsonl"), 300);
  EXPECT_EQ(lines_of(dir + "/trajectory.txt"), 301);  // and its header
  EXPECT_GT(std::filesystem::file_size(dir + "/traversal.png"), 1000u);
  const auto e = run("eval-traversal " + dir + " --json");
  ASSERT_EQ(e.code, 0) << e.out;
  for (const char* key :
       {"sequences", "frames_on_stairs", "step_index_accuracy", "count_exact", "phantom_steps",
        "missed_last_step", "gap_corrected_max_m", "gap_uncorrected_max_m", "fused_riser_err_m",
        "fused_tread_err_m", "single_frame_riser_err_m", "single_frame_tread_err_m"})
    EXPECT_NE(e.out.find(std::string("\"") + key + "\""), std::string::npos) << key << " in " << e.out;
  EXPECT_NE(e.out.find("\"count_exact\": 1"), std::string::npos) << e.out;
  EXPECT_NE(e.out.find("\"phantom_steps\": 0"), std::string::npos) << e.out;
  EXPECT_NE(e.out.find("\"missed_last_step\": 0"), std::string::npos) << e.out;
}

TEST(CliTraversal, BadInputIsNamed) {
  auto r = run("replay synth:climb_3_steps:2 --out " + tmp("bad") + " --drift 2");
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.out.find("--drift '2'"), std::string::npos) << r.out;
  r = run("eval-traversal " + tmp("does-not-exist"));
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.out.find("frames.jsonl: cannot read"), std::string::npos) << r.out;
  r = run("bench traversal --walks no_such_walk");
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.out.find("unknown walk 'no_such_walk'"), std::string::npos) << r.out;
}

namespace {

// The decisions of one frame, as the daemon's frame line or the replay's frames.jsonl gives them.
struct Decision {
  std::string perception, manhattan, traversal, step, left, known, cue;
  bool operator==(const Decision& o) const {
    return perception == o.perception && manhattan == o.manhattan && traversal == o.traversal &&
           step == o.step && left == o.left && known == o.known && cue == o.cue;
  }
};
std::ostream& operator<<(std::ostream& os, const Decision& d) {
  return os << "perception=" << d.perception << " manhattan=" << d.manhattan << " traversal=" << d.traversal
            << " step=" << d.step << " left=" << d.left << " known=" << d.known << " cue=" << d.cue;
}

// `key=value` of a daemon frame line.
std::string field(const std::string& line, const std::string& key) {
  const std::string k = " " + key + "=";
  const std::size_t p = line.find(k);
  if (p == std::string::npos) return "?";
  const std::size_t b = p + k.size();
  return line.substr(b, line.find(' ', b) - b);
}
// `"key": value` of a frames.jsonl line (strings without their quotes).
std::string json_field(const std::string& line, const std::string& key) {
  const std::string k = "\"" + key + "\": ";
  const std::size_t p = line.find(k);
  if (p == std::string::npos) return "?";
  std::size_t b = p + k.size();
  if (line[b] == '"') return line.substr(b + 1, line.find('"', b + 1) - b - 1);
  return line.substr(b, line.find_first_of(",}", b) - b);
}

std::vector<std::string> file_lines(const std::string& path) {
  std::vector<std::string> v;
  std::ifstream in(path);
  for (std::string l; std::getline(in, l);) v.push_back(l);
  return v;
}

}  // namespace

// One composition (issue 40): `stairguide replay` runs the daemon's runtime, so on a walk with a
// fast turn (where the Manhattan frame must be carried by the odometry between views) its
// frames.jsonl holds, frame by frame, the decisions `stairguided --sync` prints: perception's state,
// the Manhattan frame seen / carried / none, the traversal state, step, steps left and known, and
// the cues.
TEST(CliTraversal, ReplayDecidesAsTheDaemonFrameByFrame) {
  const std::string dir = tmp("same"), cfg = tmp("same.yaml");
  std::filesystem::remove_all(dir);
  {
    std::ofstream c(cfg);
    c << "feedback:\n  audio_enabled: false\n  haptic_enabled: false\n";
  }
  const std::string input = "synth:ascending_turn_fast:200:7";
  const auto r = run("--config " + cfg + " replay " + input + " --out " + dir);
  ASSERT_EQ(r.code, 0) << r.out;
  const auto d = cli_test::run_shell(std::string(STAIRGUIDED) + " --config " + cfg + " --replay " + input +
                                     " --sync --fast 2>/dev/null");
  ASSERT_EQ(d.code, 0) << d.out;
  std::vector<Decision> daemon;
  std::size_t p = 0;
  while (p < d.out.size()) {
    const std::size_t e = std::min(d.out.find('\n', p), d.out.size());
    const std::string line = d.out.substr(p, e - p);
    p = e + 1;
    if (line.rfind("frame=", 0) != 0) continue;
    const std::string l = " " + line;
    daemon.push_back({field(l, "perception"), field(l, "manhattan"), field(l, "traversal"), field(l, "step"),
                      field(l, "left"), field(l, "known"), field(l, "cue")});
  }
  const auto lines = file_lines(dir + "/frames.jsonl");
  ASSERT_EQ(daemon.size(), 200u) << d.out.substr(0, 2000);
  ASSERT_EQ(lines.size(), daemon.size());
  int carried = 0, differ = 0;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const std::string& l = lines[i];
    const Decision rep{json_field(l, "perception"), json_field(l, "manhattan"), json_field(l, "state"),
                       json_field(l, "step"),       json_field(l, "left"),      json_field(l, "known"),
                       json_field(l, "cue")};
    carried += rep.manhattan == "carried";
    if (!(rep == daemon[i]) && ++differ <= 5)
      ADD_FAILURE() << "frame " << i << ": replay " << rep << "\n  daemon " << daemon[i];
  }
  EXPECT_EQ(differ, 0);
  EXPECT_GE(carried, 3) << "the walk no longer has the Manhattan frame carried: the test lost its point";
}

// Issue 41, defect 3: a replay that cannot read a frame half-way, or cannot write its files, ends
// with a non-zero exit naming the frame or the file, and what it wrote holds whole lines.
TEST(CliTraversal, ATruncatedRecordingIsNamedNotASuccess) {
  const std::string src = tmp("trunc_src"), oni = tmp("trunc.oni"), dir = tmp("trunc");
  std::filesystem::remove_all(src);
  std::filesystem::remove_all(dir);
  std::filesystem::remove(oni);
  auto r = run("synth --scene climb_3_steps --frames 30 --seed 3 --out " + src + " --oni " + oni);
  ASSERT_EQ(r.code, 0) << r.out;
  std::filesystem::resize_file(oni, std::filesystem::file_size(oni) * 6 / 10);
  r = run("replay " + oni + " --out " + dir);
  EXPECT_NE(r.code, 0) << r.out;
  EXPECT_NE(r.out.find(oni), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("frame "), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("replay: "), std::string::npos) << "a success line on a failure: " << r.out;
  const long n = lines_of(dir + "/frames.jsonl");
  EXPECT_GT(n, 5);
  EXPECT_LT(n, 30);
  EXPECT_NE(r.out.find("frame " + std::to_string(n) + " cannot be read"), std::string::npos)
      << n << " " << r.out;
}

TEST(CliTraversal, AnUnreadableFrameHalfWayIsNamed) {
  const std::string src = tmp("badframe_src"), dir = tmp("badframe");
  std::filesystem::remove_all(src);
  std::filesystem::remove_all(dir);
  auto r = run("synth --scene climb_3_steps --frames 20 --seed 3 --out " + src);
  ASSERT_EQ(r.code, 0) << r.out;
  std::vector<std::filesystem::path> depth;
  for (const auto& e : std::filesystem::directory_iterator(src + "/depth")) depth.push_back(e.path());
  std::sort(depth.begin(), depth.end());
  ASSERT_EQ(depth.size(), 20u);
  std::ofstream(depth[12], std::ios::trunc) << "not a PNG";
  r = run("replay " + src + " --out " + dir);
  EXPECT_NE(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("frame 12 cannot be read"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find(depth[12].filename().string()), std::string::npos) << r.out;
  EXPECT_EQ(lines_of(dir + "/frames.jsonl"), 12);
}

// A full disk: each output file in turn on /dev/full (every write fails with ENOSPC).
TEST(CliTraversal, AFullDiskIsNamed) {
  if (!std::filesystem::exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
  for (const char* name : {"frames.jsonl", "trajectory.txt"}) {
    const std::string dir = tmp(std::string("full_") + name);
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    std::filesystem::create_symlink("/dev/full", dir + "/" + name);
    const auto r = run("replay synth:climb_3_steps:20:11 --out " + dir);
    EXPECT_NE(r.code, 0) << name << ": " << r.out;
    EXPECT_NE(r.out.find(dir + "/" + name + ": cannot write"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("No space left on device"), std::string::npos) << r.out;
  }
}

// A real full file system (a 64 KiB tmpfs: root only, as in CI): the failure names the file and
// the frame, and frames.jsonl is cut back to whole lines, one per frame before it.
TEST(CliTraversal, AFullFileSystemLeavesWholeLinesAndNamesTheFrame) {
  if (geteuid() != 0) GTEST_SKIP() << "mounting a tmpfs needs root";
  const std::string mnt = tmp("tmpfs");
  std::filesystem::create_directories(mnt);
  if (std::system(("mount -t tmpfs -o size=64k stairguide-test " + mnt + " 2>/dev/null").c_str()) != 0)
    GTEST_SKIP() << "cannot mount a tmpfs here";
  const std::string dir = mnt + "/out";
  const auto r = run("replay synth:climb_3_steps:150:11 --out " + dir);
  const auto lines = file_lines(dir + "/frames.jsonl");
  std::system(("umount " + mnt).c_str());
  EXPECT_NE(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("No space left on device"), std::string::npos) << r.out;
  ASSERT_FALSE(lines.empty()) << r.out;
  EXPECT_LT(lines.size(), 150u);
  for (const auto& l : lines) EXPECT_EQ(l.back(), '}') << "a line cut: " << l.substr(0, 80);
  const bool named = r.out.find(dir + "/frames.jsonl: cannot write frame " + std::to_string(lines.size())) !=
                         std::string::npos ||
                     r.out.find(dir + "/trajectory.txt: cannot write") != std::string::npos;
  EXPECT_TRUE(named) << lines.size() << " lines: " << r.out;
}
