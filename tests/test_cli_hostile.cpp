// Both binaries against bad input from outside (issue 35): a broken $STAIRGUIDE_CONFIG where a
// command is given its own file or needs none, empty file arguments, a truncated .oni, a PCD
// that crashed PCL. Each gives a clear message and the right exit code; none crashes or hangs
// (every run is bounded by timeout(1): 124 would mean it hung).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "cli_test_util.hpp"
#include "stairguide/capture/oni.hpp"
#include "stairguide/capture/synth_source.hpp"

namespace fs = std::filesystem;
using cli_test::CliRun;
using cli_test::run_shell;
using namespace stairguide;

namespace {

std::string tmp(const std::string& name) { return cli_test::tmp("test_cli_hostile_", name); }
const std::string kShipped = std::string(STAIRGUIDE_SOURCE_DIR) + "/config/stairguide.yaml";
std::string cli(const std::string& args) { return "timeout 60 " + std::string(STAIRGUIDE_CLI) + " " + args; }
std::string daemon(const std::string& args) { return "timeout 60 " + std::string(STAIRGUIDED) + " " + args; }

/// A 20-frame synthetic .oni cut to its first 20% (headers and about 3 frames).
std::string truncated_oni() {
  const std::string full = tmp("full.oni"), cut = tmp("cut.oni");
  if (fs::exists(cut)) return cut;
  synth::SynthOptions so;
  so.width = 160;
  so.height = 120;
  auto src = synth::make_source("ascending_approach_climb", 20, 3, so);
  {
    OniWriter w(full, src->intrinsics(), true, 30);
    RgbdFrame f;
    for (int i = 0; i < 20; ++i) {
      EXPECT_TRUE(src->read(f).ok());
      w.write(f);
    }
    w.close();
  }
  const std::string part = cut + ".part";
  fs::copy_file(full, part, fs::copy_options::overwrite_existing);
  fs::resize_file(part, fs::file_size(full) / 5);
  fs::rename(part, cut);
  return cut;
}

}  // namespace

TEST(CliHostile, BrokenEnvConfigDoesNotStopACommandGivenItsFileOrNeedingNone) {
  const std::string bad = tmp("env_bad.yaml");
  std::ofstream(bad) << "floor:\n  tilt_min_deg: [\n";
  const std::string env = "STAIRGUIDE_CONFIG=" + bad + " ";
  CliRun r = run_shell(env + cli("check-config " + kShipped));
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find(kShipped + ": ok"), std::string::npos) << r.out;
  r = run_shell(env + cli("synth --list"));
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("ascending_approach_climb"), std::string::npos) << r.out;
  r = run_shell(env + cli("dump-config --defaults"));
  EXPECT_EQ(r.code, 0) << r.out;
  // A command that runs on the config still stops on the broken one, naming it.
  r = run_shell(env + cli("detect synth:ascending_static:1"));
  EXPECT_EQ(r.code, 3) << r.out;
  EXPECT_NE(r.out.find(bad + ":"), std::string::npos) << r.out;
  r = run_shell(env + cli("check-config"));
  EXPECT_NE(r.code, 0) << r.out;
  EXPECT_NE(r.out.find(bad), std::string::npos) << r.out;
  // The daemon's --check-config FILE never looked at the environment's file.
  r = run_shell(env + daemon("--check-config " + kShipped));
  EXPECT_EQ(r.code, 0) << r.out;
}

TEST(CliHostile, EmptyFileArgumentsAreUsageErrors) {
  // `--check-config ""` and `--replay ""` started the live camera path (and waited for one).
  for (const char* args :
       {"--check-config ''", "--replay ''", "--config '' --replay synth:ascending_static:1"}) {
    const CliRun r = run_shell(daemon(args));
    EXPECT_EQ(r.code, 2) << args << ": " << r.out;
    EXPECT_NE(r.out.find("needs a non-empty value"), std::string::npos) << args << ": " << r.out;
  }
  const CliRun r = run_shell(cli("--config '' synth --list"));
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("--config needs a file name"), std::string::npos) << r.out;
}

TEST(CliHostile, TruncatedRecordingFailsEveryCommandThatReadsIt) {
  const std::string cut = truncated_oni();
  // Exit 0 and "ended early after 3 of 20 frames" at info level before.
  CliRun r = run_shell(cli("odometry " + cut + " --out " + tmp("cut_traj.txt")));
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_NE(r.out.find("cut.oni: recording ended early after"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find(" of 20 frames"), std::string::npos) << r.out;
  r = run_shell(cli("eval-odometry " + cut));
  EXPECT_NE(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("ended early"), std::string::npos) << r.out;
  r = run_shell(cli("detect " + cut + " --frame 15"));
  EXPECT_NE(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("ended early"), std::string::npos) << r.out;
  for (const char* mode : {"--fast", "--fast --sync"}) {
    r = run_shell(daemon("--config " + kShipped + " --replay " + cut + " " + mode + " --no-frame-lines"));
    EXPECT_EQ(r.code, 1) << mode << ": " << r.out;
    EXPECT_NE(r.out.find("error: oni " + cut + ": recording ended early"), std::string::npos) << r.out;
  }
}

TEST(CliHostile, CompressedPcdThatCrashedPclIsACleanError) {
  // Written by test_capture_hostile's recipe, by hand here: an organized 4 x 4 xyz cloud whose
  // compressed body says 0 bytes uncompressed (exit 139 from analyze before).
  const std::string p = tmp("zero.pcd");
  {
    std::ofstream o(p, std::ios::binary);
    o << "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 4\nHEIGHT 4\n"
         "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 16\nDATA binary_compressed\n";
    const char words[8] = {10, 0, 0, 0, 0, 0, 0, 0};
    o.write(words, 8);
    o << "0123456789";
  }
  for (const char* cmd : {"analyze", "detect"}) {
    const CliRun r = run_shell(cli(std::string(cmd) + " " + p));
    EXPECT_EQ(r.code, 1) << cmd << ": " << r.out;
    EXPECT_NE(r.out.find(p + ": corrupt PCD (compressed body says 0 bytes uncompressed"), std::string::npos)
        << cmd << ": " << r.out;
  }
  const CliRun r = run_shell(daemon("--config " + kShipped + " --replay " + p + " --no-frame-lines"));
  EXPECT_EQ(r.code, 4) << r.out;
  EXPECT_NE(r.out.find(p), std::string::npos) << r.out;
}
