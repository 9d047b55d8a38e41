// The daemon's start-up as systemd sees it (issue 35): READY=1 once it runs even with no camera
// plugged in (STATUS= says it waits for one), and a SIGTERM in its first milliseconds is a clean
// stop (exit 0), not a kill (exit 143).
#include <gtest/gtest.h>
#include <signal.h>

#include <chrono>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>

#include "daemon_test_util.hpp"
#include "file_test_util.hpp"

using Clock = std::chrono::steady_clock;

namespace {

const std::string kShipped = std::string(STAIRGUIDE_SOURCE_DIR) + "/config/stairguide.yaml";

}  // namespace

TEST(DaemonStart, ReadyWithoutACameraAndStatusSaysItWaitsForOne) {
  // Live path, no camera on this machine: READY=1 used to wait for the first frame, so
  // `systemctl enable --now` blocked for ever (TimeoutStartSec=infinity).
  sgtest::Daemon d({"--config", kShipped});
  const auto t0 = Clock::now();
  ASSERT_TRUE(d.wait_notify("READY=1", 20));
  ASSERT_EQ(d.notify_line("READY=1"), "READY=1");
  const double ready_s = std::chrono::duration<double>(Clock::now() - t0).count();
  EXPECT_LT(ready_s, 20.0);
  RecordProperty("ready_s", std::to_string(ready_s));
  EXPECT_TRUE(d.wait_notify("STATUS=waiting for camera", 5))
      << "STATUS must say the daemon waits for a camera";
  // The failed opens are reported as a wait for the camera, never as a camera lost.
  std::this_thread::sleep_for(std::chrono::milliseconds(700));
  d.drain(100);
  for (const auto& n : d.notes()) EXPECT_EQ(n.find("STATUS=camera lost"), std::string::npos) << n;
  d.signal(SIGTERM);
  EXPECT_EQ(d.wait_exit(5), 0);
}

TEST(DaemonStart, SigtermInTheFirstMillisecondsIsACleanStop) {
  // A unit stopped right after it was started: SIGTERM while the ~190 shared libraries load
  // killed the process (exit 143).
  for (const int delay_ms : {5, 10, 30, 60, 150}) {
    sgtest::Daemon d(
        {"--config", kShipped, "--replay", "synth:ascending_static:1000", "--realtime", "--no-frame-lines"});
    std::this_thread::sleep_for(std::chrono::milliseconds(delay_ms));
    d.signal(SIGTERM);
    EXPECT_EQ(d.wait_exit(20), 0) << "SIGTERM " << delay_ms << " ms after exec";
  }
}

TEST(DaemonStart, UnitTimesOutAStuckStartAndDoesNotRestartOnABadConfig) {
  const std::string unit =
      stairguide::test::read_file(std::string(STAIRGUIDE_SOURCE_DIR) + "/systemd/stairguide.service");
  EXPECT_EQ(unit.find("TimeoutStartSec=infinity"), std::string::npos);
  EXPECT_NE(unit.find("\nTimeoutStartSec=30s\n"), std::string::npos);
  EXPECT_NE(unit.find("\nRestart=on-failure\n"), std::string::npos);
  // 3 is what stairguided exits with on a config error, 2 on bad arguments (its usage text).
  EXPECT_NE(unit.find("\nRestartPreventExitStatus=2 3\n"), std::string::npos);
  // The buzzer's timing thread may have SCHED_FIFO 10 as the unprivileged user, and no more.
  EXPECT_EQ(unit.find("RestrictRealtime=yes"), std::string::npos);
  EXPECT_NE(unit.find("\nLimitRTPRIO=10\n"), std::string::npos);
  EXPECT_NE(unit.find("\nSystemCallFilter=sched_setscheduler"), std::string::npos);
  sgtest::Daemon d({"--config", "/nonexistent/stairguide.yaml"});
  EXPECT_EQ(d.wait_exit(20), 3);
  sgtest::Daemon e({"--frobnicate"});
  EXPECT_EQ(e.wait_exit(20), 2);
}
