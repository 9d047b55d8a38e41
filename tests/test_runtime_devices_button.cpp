// The wearer's button's devices: the file backend the daemon's tests drive, the reader's thread,
// and a missing GPIO chip named. (The decoding of edges into presses: test_feedback_button.)
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "stairguide/runtime/devices/button_reader.hpp"

using namespace stairguide::feedback;
using namespace stairguide::runtime::devices;
namespace fs = std::filesystem;

namespace {
const fs::path kDir = fs::path(STAIRGUIDE_BINARY_DIR) / "feedback_button_files";
}  // namespace

TEST(ButtonFileLine, ReadsTimedEdgesAndNamesBadLines) {
  fs::create_directories(kDir);
  const fs::path f = kDir / "presses.txt";
  std::ofstream(f) << "# a comment\n0.05 down\n0.20 up\nbogus line\n0.1 down\n\n0.30 down  # pressed again\n";
  std::vector<std::string> warnings;
  FileButtonLine line(f.string(), [&](const std::string& w) { warnings.push_back(w); });
  const double t0 = steady_seconds();
  std::vector<ButtonEdge> edges;
  while (edges.size() < 3 && steady_seconds() - t0 < 2.0) line.wait(std::chrono::milliseconds(100), edges);
  ASSERT_EQ(edges.size(), 3u);
  EXPECT_TRUE(edges[0].down);
  EXPECT_FALSE(edges[1].down);
  EXPECT_TRUE(edges[2].down);
  EXPECT_NEAR(edges[1].t - edges[0].t, 0.15, 1e-6);  // the file's times, not the reading's
  EXPECT_GE(steady_seconds() - t0, 0.29);            // each given at its time, not before
  ASSERT_EQ(warnings.size(), 2u);
  EXPECT_NE(
      warnings[0].find("file:" + f.string() + " line 4: expected '<seconds> down|up', found 'bogus line'"),
      std::string::npos)
      << warnings[0];
  EXPECT_NE(warnings[1].find("line 5: time 0.1 s is before the line above it"), std::string::npos)
      << warnings[1];
  // Lines appended later are read (the file is followed as it grows).
  std::ofstream(f, std::ios::app) << "0.31 up\n";
  edges.clear();
  line.wait(std::chrono::milliseconds(300), edges);
  ASSERT_EQ(edges.size(), 1u);
  EXPECT_FALSE(edges[0].down);
}

TEST(ButtonFileLine, MissingFileIsNamed) {
  try {
    FileButtonLine line((kDir / "no_such_presses").string(), nullptr);
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("button: cannot open the press file '"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("no_such_presses"), std::string::npos) << e.what();
  }
}

TEST(ButtonGpiodLine, MissingChipIsNamed) {
  try {
    make_button_line("gpiochip_sg_absent", 27, true, nullptr);
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(
        std::string(e.what()).find("button: GPIO chip 'gpiochip_sg_absent' line 27: cannot open the chip"),
        std::string::npos)
        << e.what();
  }
}

// Through the reader's thread, from a FIFO written while it runs: a double press, then a long one.
TEST(ButtonReader, PressesFromAFifo) {
  fs::create_directories(kDir);
  const fs::path fifo = kDir / "presses.fifo";
  fs::remove(fifo);
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  ButtonReader r(make_button_line("file:" + fifo.string(), 0, true, nullptr), PressTiming{}, nullptr);
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  {
    std::ofstream w(fifo);  // opens once the reader has the FIFO open
    w << "0.1 down\n0.2 up\n0.35 down\n0.45 up\n1.0 down\n2.2 up\n";
  }
  std::vector<PressEvent> got;
  const double t0 = steady_seconds();
  while (got.size() < 2 && steady_seconds() - t0 < 5.0) {
    for (const auto& p : r.take()) got.push_back(p);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0].press, Press::kDouble);
  EXPECT_EQ(got[1].press, Press::kLong);
  EXPECT_NEAR(got[1].t - got[0].t, 2.0 - 0.45, 0.01);  // at 1.0 + 1 s held, from the double's release
}
