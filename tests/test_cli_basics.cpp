// The stairguide binary: check-config, --config on every command, synth --list and a small synth.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "cli_test_util.hpp"

namespace {

using cli_test::CliRun;
using cli_test::run;
std::string tmp(const std::string& name) { return cli_test::tmp("test_cli_", name); }

}  // namespace

TEST(Cli, CheckConfigAcceptsTheShippedFile) {
  const CliRun r = run(std::string("check-config ") + STAIRGUIDE_SOURCE_DIR + "/config/stairguide.yaml");
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find(": ok"), std::string::npos) << r.out;
}

TEST(Cli, CheckConfigNamesTheProblem) {
  const std::string path = tmp("bad.yaml");
  std::ofstream(path) << "stair_detection:\n  connection_radius_m: -1\n";
  const CliRun r = run("check-config " + path);
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.out.find(path + ":2"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("stair_detection.connection_radius_m"), std::string::npos) << r.out;
}

TEST(Cli, EveryCommandTakesConfigAndABadOneStopsIt) {
  const std::string path = tmp("bad2.yaml");
  std::ofstream(path) << "odometry:\n  iterations: lots\n";
  const CliRun r = run("--config " + path + " synth --list");
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.out.find("odometry.iterations"), std::string::npos) << r.out;
  const CliRun ok =
      run(std::string("synth --list --config ") + STAIRGUIDE_SOURCE_DIR + "/config/stairguide.yaml");
  EXPECT_EQ(ok.code, 0) << ok.out;
}

TEST(Cli, SynthListsAtLeastTwentyPresets) {
  const CliRun r = run("synth --list");
  ASSERT_EQ(r.code, 0) << r.out;
  int lines = 0;
  for (char c : r.out) lines += c == '\n';
  EXPECT_GE(lines, 20) << r.out;
  EXPECT_NE(r.out.find("ascending_approach_climb"), std::string::npos);
  EXPECT_NE(r.out.find("descending_approach_descend"), std::string::npos);
}

TEST(Cli, SynthWritesALabelledDatasetAndRefusesUnknownScenes) {
  const std::string out = tmp("synth_ds");
  std::filesystem::remove_all(out);
  const CliRun r = run("synth --scene descending_static --frames 3 --seed 7 --out " + out);
  ASSERT_EQ(r.code, 0) << r.out;
  for (const char* f : {"camera.yaml", "rgb.txt", "depth.txt", "groundtruth.txt", "labels.yaml"})
    EXPECT_TRUE(std::filesystem::exists(out + "/" + f)) << f;
  std::ifstream depth(out + "/depth.txt");
  int entries = 0;
  for (std::string line; std::getline(depth, line);) entries += !line.empty() && line[0] != '#';
  EXPECT_EQ(entries, 3);
  const CliRun bad = run("synth --scene no_such_scene --frames 1 --out " + tmp("synth_bad"));
  EXPECT_NE(bad.code, 0);
  EXPECT_NE(bad.out.find("no_such_scene"), std::string::npos) << bad.out;
}

TEST(Cli, UnknownCommandAndOptionAreUsageErrors) {
  EXPECT_EQ(run("frobnicate").code, 2);
  EXPECT_EQ(run("check-config --frobnicate").code, 2);
}
