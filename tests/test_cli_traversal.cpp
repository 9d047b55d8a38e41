// `stairguide replay`, `eval-traversal` and `bench traversal` as a user runs them.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

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
