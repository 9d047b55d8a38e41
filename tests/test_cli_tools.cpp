// tools/fresh-machine empties and rebuilds a Debian root of its own: it must refuse a DIR it did
// not make (the system root, this checkout, someone's directory). Every case runs it with
// FRESH_MACHINE_CHECK_ONLY=1, which stops right after those checks having touched nothing: a
// broken check fails the test ("accepted") instead of emptying the directory it should refuse.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "cli_test_util.hpp"

namespace fs = std::filesystem;

namespace {

cli_test::CliRun fresh_machine(const std::string& dir) {
  return cli_test::run_shell("FRESH_MACHINE_CHECK_ONLY=1 " + std::string(STAIRGUIDE_SOURCE_DIR) +
                             "/tools/fresh-machine '" + dir + "'");
}

// A new scratch directory under /tmp (outside the checkout), removed at the end of the test.
struct Scratch {
  fs::path dir;
  Scratch() {
    char tmpl[] = "/tmp/stairguide-fresh-test-XXXXXX";
    if (mkdtemp(tmpl)) dir = tmpl;
  }
  ~Scratch() {
    std::error_code ec;
    if (!dir.empty()) fs::remove_all(dir, ec);
  }
};

TEST(FreshMachine, NeedsRoot) {
  if (geteuid() == 0) GTEST_SKIP() << "running as root: the checks below are tested instead";
  const cli_test::CliRun r = fresh_machine("/var/tmp/stairguide-fresh-test");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("needs root"), std::string::npos) << r.out;
}

TEST(FreshMachine, AcceptsANewOrEmptyDirectory) {
  if (geteuid() != 0) GTEST_SKIP() << "needs root (the tool checks for root first)";
  Scratch s;
  ASSERT_FALSE(s.dir.empty());
  for (const fs::path& dir : {s.dir, s.dir / "new"}) {
    const cli_test::CliRun r = fresh_machine(dir.string());
    EXPECT_EQ(r.code, 0) << dir << ": " << r.out;
    EXPECT_NE(r.out.find("accepted (check only)"), std::string::npos) << dir << ": " << r.out;
  }
  EXPECT_FALSE(fs::exists(s.dir / "new")) << "check only, yet it made the directory";
}

TEST(FreshMachine, RefusesTheSystemRootAndTheCheckout) {
  if (geteuid() != 0) GTEST_SKIP() << "needs root (the tool checks for root first)";
  for (const std::string& dir : {std::string("/"), std::string(STAIRGUIDE_SOURCE_DIR),
                                 std::string(STAIRGUIDE_SOURCE_DIR) + "/build/fresh"}) {
    const cli_test::CliRun r = fresh_machine(dir);
    EXPECT_EQ(r.code, 2) << dir << ": " << r.out;
    EXPECT_NE(r.out.find("refusing DIR"), std::string::npos) << dir << ": " << r.out;
  }
}

TEST(FreshMachine, RefusesADirectoryItDidNotMake) {
  if (geteuid() != 0) GTEST_SKIP() << "needs root (the tool checks for root first)";
  Scratch s;
  ASSERT_FALSE(s.dir.empty());
  fs::create_directories(s.dir / "etc");
  std::ofstream(s.dir / "etc" / "debian_version")
      << "12.0\n";  // looks like a Debian root, not made by the tool
  const cli_test::CliRun r = fresh_machine(s.dir.string());
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("was not made by this script"), std::string::npos) << r.out;
  // Nor a file in its place.
  const fs::path file = s.dir / "keep.txt";
  std::ofstream(file) << "someone's file\n";
  const cli_test::CliRun f = fresh_machine(file.string());
  EXPECT_EQ(f.code, 2) << f.out;
  EXPECT_NE(f.out.find("is not a directory"), std::string::npos) << f.out;
  // With the tool's marker it is one of its roots.
  std::ofstream(s.dir / ".stairguide-fresh").flush();
  EXPECT_EQ(fresh_machine(s.dir.string()).code, 0);
}

}  // namespace
