// End to end: the stairguided binary replaying a synthetic .oni written into the build tree, with
// NOTIFY_SOCKET on a test datagram socket (READY / WATCHDOG / STATUS), its per-frame lines,
// SIGTERM, SIGHUP with a valid and an invalid config, a replay that ends, a corrupt recording, an
// unreadable config; and the systemd unit (verify prints nothing, security rating <= 2.5).
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "daemon_test_util.hpp"
#include "file_test_util.hpp"
#include "stairguide/capture/dataset.hpp"
#include "stairguide/capture/oni.hpp"
#include "stairguide/capture/synth_source.hpp"
#include "stairguide/config/config_loader.hpp"

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using namespace stairguide;
using test::parse_kv;
using test::read_file;

namespace {

const fs::path kDir = fs::path(STAIRGUIDE_BINARY_DIR) / "e2e_daemon_files";
constexpr long kOniFrames = 150;  // 5 s at 30 Hz

void write_file(const fs::path& p, const std::string& text) {
  std::ofstream f(p);
  f << text;
}

/// Runs a command, returns its exit code and combined stdout+stderr.
int run_capture(const std::string& cmd, std::string& out) {
  out.clear();
  std::FILE* p = popen((cmd + " 2>&1").c_str(), "r");
  if (!p) return -1;
  std::array<char, 4096> buf{};
  std::size_t n = 0;
  while ((n = std::fread(buf.data(), 1, buf.size(), p)) > 0) out.append(buf.data(), n);
  const int st = pclose(p);
  return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

using sgtest::Daemon;

/// A replay's daemon: stdout (the frame lines) through a pipe, stderr to kDir/<name>.stderr, the
/// watchdog on at 0.3 s.
sgtest::DaemonOptions io(const std::string& name) {
  sgtest::DaemonOptions o;
  o.out = sgtest::Stdout::pipe;
  o.err_path = (kDir / (name + ".stderr")).string();
  o.env = {{"WATCHDOG_USEC", "300000"}};
  return o;
}

class DaemonE2E : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    fs::create_directories(kDir);
    oni_ = kDir / "climb.oni";
    // The recording: a synthetic approach-and-climb at 320x240 (the daemon takes any size; the
    // smaller one keeps this test quick), written as an .oni that OpenNI2's own player replays.
    if (!fs::exists(oni_)) {
      synth::SynthOptions so;
      so.width = 320;
      so.height = 240;
      auto src = synth::make_source("ascending_approach_climb", kOniFrames, 7, so);
      // ctest runs each test case as its own process, maybe two at once: write under a unique
      // name, then rename (atomic; both writers produce the same file).
      const fs::path tmp = kDir / ("climb.oni.part" + std::to_string(getpid()));
      {
        OniWriter w(tmp.string(), src->intrinsics(), true, 30);
        RgbdFrame f;
        for (long i = 0; i < kOniFrames; ++i) {
          ASSERT_TRUE(src->read(f).ok());
          w.write(f);
        }
        w.close();
      }
      fs::rename(tmp, oni_);
    }
    // The config: shipped defaults with counters every 0.3 s.
    PipelineConfig c;
    c.runtime.status_interval = 0.3f;
    config_ = kDir / "daemon.yaml";
    const fs::path tmp_cfg = kDir / ("daemon.yaml.part" + std::to_string(getpid()));
    write_file(tmp_cfg, dump_config_yaml(c));
    fs::rename(tmp_cfg, config_);
  }
  static fs::path oni_, config_;
};
fs::path DaemonE2E::oni_, DaemonE2E::config_;

}  // namespace

TEST_F(DaemonE2E, ReplayNotifiesReadyWatchdogStatusPrintsFramesAndStopsOnSigterm) {
  Daemon d({"--config", config_.string(), "--replay", oni_.string(), "--realtime"}, io("sigterm"));
  ASSERT_TRUE(d.wait_notify("READY=1", 30)) << d.stderr_text();
  std::vector<std::string> lines;
  std::string l;
  while (lines.size() < 45 && d.read_line(l, 20)) lines.push_back(l);  // 1.5 s of frames
  ASSERT_TRUE(d.wait_notify("WATCHDOG=1", 5));
  ASSERT_TRUE(d.wait_notify("STATUS=running: capture", 5)) << "counters in STATUS";
  for (const auto& m : d.notes())
    if (m.rfind("STATUS=running: capture", 0) == 0) {
      for (const char* key : {"odometry", "perception", "fps", "skipped", "lost", "latency p50", "p99"})
        EXPECT_NE(m.find(key), std::string::npos) << key << " missing from " << m;
      break;
    }
  const auto t0 = Clock::now();
  d.signal(SIGTERM);
  const int code = d.wait_exit(5.0, &lines);
  const double stop_s = std::chrono::duration<double>(Clock::now() - t0).count();
  EXPECT_EQ(code, 0) << d.stderr_text();
  EXPECT_LT(stop_s, 1.0) << "SIGTERM must stop the daemon within 1 s";
  EXPECT_GE(d.count_notify("STOPPING=1"), 1);

  // Frame lines: consecutive from 0, every one through odometry; skips counted in the summary.
  ASSERT_FALSE(lines.empty());
  ASSERT_EQ(lines.back().rfind("summary ", 0), 0u) << lines.back();
  const auto summary = parse_kv(lines.back());
  lines.pop_back();
  ASSERT_GE(lines.size(), 45u);
  long skipped = 0;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const auto kv = parse_kv(lines[i]);
    ASSERT_EQ(kv.at("frame"), std::to_string(i)) << lines[i];
    EXPECT_TRUE(kv.at("odom") == "ok" || kv.at("odom").rfind("fail:", 0) == 0) << lines[i];
    skipped += kv.at("perception") == "skipped";
  }
  EXPECT_EQ(summary.at("state"), "stopped");
  EXPECT_EQ(std::stol(summary.at("odometry_lost")), 0);
  EXPECT_EQ(std::stol(summary.at("odometry_frames")), std::stol(summary.at("frames")));
  // Frames captured but not yet printed when SIGTERM came are not in the lines; the printed ones
  // account for their skips exactly.
  EXPECT_LE(skipped, std::stol(summary.at("perception_skipped")));
  EXPECT_GE(std::stol(summary.at("frames")), static_cast<long>(lines.size()));
}

TEST_F(DaemonE2E, ReplayThatEndsExitsZeroWithEveryFrameThroughOdometry) {
  Daemon d({"--config", config_.string(), "--replay", oni_.string(), "--fast"}, io("ends"));
  std::vector<std::string> lines;
  const int code = d.wait_exit(120.0, &lines);
  ASSERT_EQ(code, 0) << d.stderr_text();
  ASSERT_EQ(lines.size(), static_cast<std::size_t>(kOniFrames + 1));
  const auto summary = parse_kv(lines.back());
  EXPECT_EQ(summary.at("state"), "ended");
  EXPECT_EQ(std::stol(summary.at("odometry_frames")), kOniFrames);
  EXPECT_EQ(std::stol(summary.at("odometry_lost")), 0);
  long skipped = 0, perceived = 0, stairs = 0;
  for (long i = 0; i < kOniFrames; ++i) {
    const auto kv = parse_kv(lines[static_cast<std::size_t>(i)]);
    EXPECT_EQ(kv.at("frame"), std::to_string(i));
    EXPECT_NE(kv.at("odom"), "none");
    if (kv.at("perception") == "skipped")
      ++skipped;
    else
      ++perceived;
    stairs += kv.at("perception") == "ascending";
  }
  EXPECT_EQ(skipped, std::stol(summary.at("perception_skipped"))) << "every skipped frame is reported";
  EXPECT_EQ(perceived, std::stol(summary.at("perception_frames")));
  EXPECT_GT(stairs, 0) << "the climb's staircase is seen at least once";
  EXPECT_TRUE(d.wait_notify("READY=1", 1));
  // The wearer's rig, learned from the first clear views of the floor (a chest camera 1.2-1.45 m
  // up in this walk), is logged once.
  const std::string err = d.stderr_text();
  const auto at = err.find("rig learned: the camera 1.");
  EXPECT_NE(at, std::string::npos) << err;
  EXPECT_EQ(err.find("rig learned", at + 1), std::string::npos) << err;
}

TEST_F(DaemonE2E, SighupAppliesAValidConfigAndRejectsAnInvalidOne) {
  const fs::path cfg = kDir / "reload.yaml";
  fs::copy_file(config_, cfg, fs::copy_options::overwrite_existing);
  Daemon d({"--config", cfg.string(), "--replay", oni_.string(), "--realtime"}, io("sighup"));
  ASSERT_TRUE(d.wait_notify("READY=1", 30)) << d.stderr_text();
  std::string l;
  ASSERT_TRUE(d.read_line(l));
  EXPECT_EQ(parse_kv(l).at("cfg"), "1");

  // A valid change: applied without restart (the frame lines show config generation 2).
  PipelineConfig c = load_config(cfg.string());
  c.segmentation.voxel_size = 0.05f;
  write_file(cfg, dump_config_yaml(c));
  d.signal(SIGHUP);
  bool applied = false;
  for (int i = 0; i < 60 && !applied && d.read_line(l, 10); ++i) applied = parse_kv(l).at("cfg") == "2";
  ASSERT_TRUE(applied) << d.stderr_text();

  // An invalid file: logged error naming the file and key, old config kept, still running.
  write_file(cfg, "segmentation:\n  voxel_size_cm: banana\n");
  d.signal(SIGHUP);
  const auto until = Clock::now() + std::chrono::seconds(5);
  while (Clock::now() < until && d.stderr_text().find("reload rejected") == std::string::npos)
    d.read_line(l, 0.1);
  const std::string err = d.stderr_text();
  EXPECT_NE(err.find("config reload rejected"), std::string::npos) << err;
  EXPECT_NE(err.find("reload.yaml"), std::string::npos) << "the message names the file";
  EXPECT_NE(err.find("voxel_size_cm"), std::string::npos) << "the message names the key";
  for (int i = 0; i < 5; ++i) {
    ASSERT_TRUE(d.read_line(l, 5)) << "the daemon kept running";
    EXPECT_EQ(parse_kv(l).at("cfg"), "2");
  }

  // An empty file (an editor that truncates before it writes): refused, the running config kept
  // (issue 41: every key went back to its default).
  write_file(cfg, "# being edited\n\n");
  d.signal(SIGHUP);
  const auto until2 = Clock::now() + std::chrono::seconds(5);
  while (Clock::now() < until2 && d.stderr_text().find("the config is empty") == std::string::npos)
    d.read_line(l, 0.1);
  EXPECT_NE(d.stderr_text().find("config reload rejected, keeping the running config: " + cfg.string() +
                                 ": the config is empty"),
            std::string::npos)
      << d.stderr_text();
  for (int i = 0; i < 3; ++i) {
    ASSERT_TRUE(d.read_line(l, 5)) << "the daemon kept running";
    EXPECT_EQ(parse_kv(l).at("cfg"), "2");
  }
  d.signal(SIGTERM);
  EXPECT_EQ(d.wait_exit(5.0), 0);
}

// The daemon's per-frame lines ("frame=..."), each cut down to `keys` ("k=v " in that order): the
// decisions two runs are compared by.
static std::vector<std::string> decisions(const std::vector<std::string>& lines,
                                          std::initializer_list<const char*> keys) {
  std::vector<std::string> out;
  for (const auto& line : lines) {
    if (line.rfind("frame=", 0) != 0) continue;
    auto kv = parse_kv(line);
    std::string keep;
    for (const char* k : keys) keep += std::string(k) + "=" + kv[k] + " ";
    out.push_back(keep);
  }
  return out;
}

// Issue 41: 50 SIGHUPs of an unchanged config in a second, before the flight, delayed "first step"
// by 25 frames and said "6 steps left" where it was 5. Through the whole daemon on a climb of 8 steps
// (one thread, paced as the camera would give the frames, so every frame's decision can be
// compared), a storm with the stairs ahead leaves every frame's decision as in a run without it.
TEST_F(DaemonE2E, ABurstOfSighupsOfAnUnchangedConfigLeavesEveryDecisionAsWithout) {
  auto run = [&](bool storm) {
    const std::string name = storm ? "storm" : "calm";
    const fs::path cfg = kDir / (name + ".yaml");
    fs::copy_file(config_, cfg, fs::copy_options::overwrite_existing);
    Daemon d({"--config", cfg.string(), "--replay", "synth:climb_8_steps", "--realtime", "--sync"}, io(name));
    EXPECT_TRUE(d.wait_notify("READY=1", 30)) << d.stderr_text();
    std::vector<std::string> lines;
    std::string l;
    if (storm) {
      for (int i = 0; i < 130 && d.read_line(l, 30); ++i) lines.push_back(l);
      for (int i = 0; i < 50; ++i) {
        d.signal(SIGHUP);
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
        while (d.read_line(l, 0.0)) lines.push_back(l);
      }
    }
    EXPECT_EQ(d.wait_exit(600.0, &lines), 0) << d.stderr_text();
    if (storm) {
      const std::string err = d.stderr_text();
      EXPECT_NE(err.find("unchanged; the running config and its state are kept"), std::string::npos) << err;
      EXPECT_EQ(err.find("config reloaded from"), std::string::npos) << err;
    }
    return decisions(lines, {"frame", "odom", "perception", "cfg", "manhattan", "traversal", "step", "left",
                             "known", "cue"});
  };
  const auto calm = run(false), storm = run(true);
  ASSERT_GT(calm.size(), 300u);
  ASSERT_EQ(storm.size(), calm.size());
  int steps = 0;
  for (std::size_t i = 0; i < calm.size(); ++i) {
    EXPECT_EQ(storm[i], calm[i]) << "frame " << i;
    steps += calm[i].find(" step=0 ") == std::string::npos;
  }
  std::printf("%d of %zu frames on a step, every decision identical with and without 50 SIGHUPs\n", steps,
              calm.size());
  EXPECT_GT(steps, 100) << "the walk has no flight to count";
}

// Issue 41: a dataset whose clock jumps back 5 s mid-flight counted 6 of 8 steps, exit 0 and no
// warning. The daemon warns naming the frame, times it by the frame clock, and every frame's
// decision is that of the same dataset with a good clock (a climb of 8 steps at 320x240, the
// clock jumping back on frame 300, on the flight).
TEST_F(DaemonE2E, ADatasetWhoseClockJumpsBackIsWarnedAndCountsAsWithAGoodClock) {
  const long frames = synth::find_preset_info("climb_8_steps")->default_frames;
  auto write = [&](const std::string& name, double jump_at) {
    const fs::path dir = kDir / name;
    fs::remove_all(dir);
    synth::SynthOptions so;
    so.width = 320;
    so.height = 240;
    auto src = synth::make_source("climb_8_steps", frames, 7, so);
    DatasetWriter w(dir.string(), src->intrinsics());
    RgbdFrame f;
    for (long i = 0; i < frames && src->read(f).ok(); ++i) {
      if (i >= jump_at) f.timestamp -= 5.0;
      w.write(f);
    }
    w.close();
    return dir;
  };
  auto run = [&](const fs::path& dir, const std::string& name, std::string* err) {
    Daemon d({"--config", config_.string(), "--replay", dir.string(), "--fast", "--sync"}, io(name));
    std::vector<std::string> lines;
    EXPECT_EQ(d.wait_exit(300.0, &lines), 0) << d.stderr_text();
    if (err) *err = d.stderr_text();
    return decisions(
        lines, {"frame", "odom", "perception", "manhattan", "traversal", "step", "left", "known", "cue"});
  };
  const auto good = run(write("clock_good", 1e9), "clock_good", nullptr);
  std::string err;
  const auto jumped = run(write("clock_back", 300), "clock_back", &err);
  ASSERT_EQ(good.size(), static_cast<std::size_t>(frames));
  ASSERT_EQ(jumped.size(), good.size());
  // The frames after the jump are timed a few tens of nanoseconds off the good clock (depth.txt
  // holds microseconds; the frame clock steps one nominal period): a state that changes on a time
  // limit may change one frame apart. Every state, count and cue comes, in the same order, and
  // all but a few frames are identical.
  auto field = [](const std::string& line, const std::string& key) {
    const auto at = line.find(" " + key + "=");
    return line.substr(at + key.size() + 2, line.find(' ', at + 1) - at - key.size() - 2);
  };
  auto story = [&](const std::vector<std::string>& lines, std::vector<std::string>& cues) {
    std::vector<std::string> states;
    for (const auto& l : lines) {
      const std::string st = field(l, "traversal") + " step " + field(l, "step") + " left " +
                             field(l, "left") + " known " + field(l, "known");
      if (states.empty() || states.back() != st) states.push_back(st);
      if (field(l, "cue") != "-") cues.push_back(field(l, "cue"));
    }
    return states;
  };
  std::vector<std::string> good_cues, jumped_cues;
  EXPECT_EQ(story(jumped, jumped_cues), story(good, good_cues));
  EXPECT_EQ(jumped_cues, good_cues);
  int on_flight = 0, differ = 0;
  for (std::size_t i = 0; i < good.size(); ++i) {
    differ += jumped[i] != good[i];
    on_flight += good[i].find(" step=0 ") == std::string::npos;
  }
  EXPECT_LE(differ, 4) << "frames whose decision differs from the good clock's";
  std::printf(
      "%d of %ld frames on a step; with the clock jumping back 5 s at frame 300 the same states, counts and "
      "cues in the same order, %d frames' decisions one frame apart\n",
      on_flight, frames, differ);
  EXPECT_GT(on_flight, 100);
  EXPECT_NE(err.find("frame 300 (#300 of the run): timestamp"), std::string::npos) << err;
  EXPECT_NE(err.find("goes back 4.96"), std::string::npos) << err;
  EXPECT_NE(err.find("1 of " + std::to_string(frames) + " frames had a timestamp that could not be trusted"),
            std::string::npos)
      << err;
}

TEST_F(DaemonE2E, CorruptOrMissingRecordingFailsWithAClearMessage) {
  const fs::path bad = kDir / "corrupt.oni";
  write_file(bad, std::string(4096, '\x5a'));
  {
    Daemon d({"--config", config_.string(), "--replay", bad.string()}, io("corrupt"));
    EXPECT_EQ(d.wait_exit(30.0), 4);
    EXPECT_NE(d.stderr_text().find("corrupt.oni"), std::string::npos) << d.stderr_text();
    EXPECT_EQ(d.count_notify("READY=1"), 0);
  }
  {
    Daemon d({"--config", config_.string(), "--replay", (kDir / "missing.oni").string()}, io("missing"));
    EXPECT_EQ(d.wait_exit(30.0), 4);
    EXPECT_NE(d.stderr_text().find("missing.oni"), std::string::npos) << d.stderr_text();
  }
}

TEST_F(DaemonE2E, UnreadableOrInvalidConfigIsNamedAndNothingRuns) {
  {
    Daemon d({"--config", (kDir / "nope.yaml").string(), "--replay", oni_.string()}, io("noconfig"));
    EXPECT_EQ(d.wait_exit(10.0), 3);
    EXPECT_NE(d.stderr_text().find("nope.yaml"), std::string::npos) << d.stderr_text();
  }
  const fs::path bad = kDir / "bad.yaml";
  write_file(bad, "runtime:\n  ring_capacity: 1\n");
  {
    Daemon d({"--config", bad.string(), "--replay", oni_.string()}, io("badconfig"));
    std::vector<std::string> lines;
    EXPECT_EQ(d.wait_exit(10.0, &lines), 3);
    EXPECT_TRUE(lines.empty()) << "no frame may run on a rejected config";
    EXPECT_NE(d.stderr_text().find("ring_capacity"), std::string::npos) << d.stderr_text();
  }
  std::string out;
  EXPECT_EQ(run_capture(std::string(STAIRGUIDED) + " --check-config " + config_.string(), out), 0) << out;
  EXPECT_NE(run_capture(std::string(STAIRGUIDED) + " --check-config " + bad.string(), out), 0);
  EXPECT_NE(out.find("ring_capacity"), std::string::npos) << out;
  EXPECT_EQ(run_capture(std::string(STAIRGUIDED) + " --bogus", out), 2);
  // An empty config is invalid at start too, the file named (issue 41: check-config called it valid).
  const fs::path empty = kDir / "empty.yaml";
  write_file(empty, "   \n# nothing yet\n");
  EXPECT_EQ(run_capture(std::string(STAIRGUIDED) + " --check-config " + empty.string(), out), 3) << out;
  EXPECT_NE(out.find(empty.string() + ": the config is empty"), std::string::npos) << out;
  {
    Daemon d({"--config", empty.string(), "--replay", oni_.string()}, io("emptyconfig"));
    EXPECT_EQ(d.wait_exit(10.0), 3);
    EXPECT_NE(d.stderr_text().find("the config is empty"), std::string::npos) << d.stderr_text();
  }
}

// Issue 41: under a 250 MB address-space limit the daemon died of an uncaught std::bad_alloc (exit
// 134, no log line). At any limit it now ends either well or with a line naming the memory and a
// non-zero exit (5 while starting, 1 once running), never through a signal. Where it runs out
// depends on the machine (before the first log line at 256000 kB here, in OpenCV at 270000 kB).
TEST(DaemonMemory, UnderATightAddressSpaceLimitItSaysOutOfMemoryAndExitsNonZero) {
  // (Below about 250000 kB the dynamic loader itself cannot map the libraries: exit 127, before
  // any of the daemon's code runs.)
  for (const int kb : {256000, 270000, 300000}) {
    std::string out;
    const int rc = run_capture("ulimit -v " + std::to_string(kb) + "; exec " + std::string(STAIRGUIDED) +
                                   " --replay synth:climb_3_steps:5 --fast --sync --no-frame-lines",
                               out);
    std::printf("ulimit -v %d: exit %d\n", kb, rc);
    EXPECT_EQ(out.find("terminate called"), std::string::npos) << kb << ": " << out;
    if (rc == 0) {
      EXPECT_NE(out.find("summary frames=5"), std::string::npos) << kb << ": " << out;
      continue;
    }
    EXPECT_TRUE(rc == 1 || rc == 5) << kb << ": exit " << rc << "\n" << out;
    EXPECT_TRUE(out.find("out of memory") != std::string::npos ||
                out.find("Insufficient memory") != std::string::npos)
        << kb << ": " << out;
  }
}

// The unit as installed points at the installed binary; verify it with the built one in its place.
TEST(SystemdUnit, VerifyPrintsNothingAndSecurityRatingIsAtMost0_8) {
  std::string out;
  if (run_capture("command -v systemd-analyze", out) != 0) GTEST_SKIP() << "systemd-analyze not installed";
  fs::create_directories(kDir);
  const std::string unit = read_file(fs::path(STAIRGUIDE_SOURCE_DIR) / "systemd" / "stairguide.service");
  ASSERT_NE(unit.find("ExecStart=/usr/bin/stairguided "), std::string::npos);
  const fs::path test_unit = kDir / "stairguide.service";
  write_file(test_unit,
             std::regex_replace(unit, std::regex("/usr/bin/stairguided"), std::string(STAIRGUIDED)));

  const int rc = run_capture("systemd-analyze verify " + test_unit.string(), out);
  EXPECT_EQ(rc, 0);
  EXPECT_EQ(out, "") << "systemd-analyze verify must print nothing";

  run_capture("systemd-analyze security --offline=true --no-pager " + test_unit.string(), out);
  std::smatch m;
  ASSERT_TRUE(
      std::regex_search(out, m, std::regex("Overall exposure level for stairguide.service: ([0-9.]+)")))
      << out;
  // 0.8 as the unit stands (issue 41: it was 1.0 while the README said 0.8; PrivateMounts=yes took
  // it there). What is left is what the daemon needs: the devices, their groups, the buzzer's
  // real-time priority (sched_setscheduler, from @resources), AF_UNIX and AF_NETLINK.
  EXPECT_LE(std::stod(m[1]), 0.8) << out;

  // What the daemon relies on is in the unit.
  for (const char* key :
       {"Type=notify", "WatchdogSec=", "User=stairguide", "ExecReload=", "DevicePolicy=closed",
        "DeviceAllow=char-usb_device rw", "DeviceAllow=char-alsa rw", "DeviceAllow=char-gpiochip rw",
        "SupplementaryGroups=audio video gpio", "PrivateMounts=yes"})
    EXPECT_NE(unit.find(key), std::string::npos) << key;
}

TEST(SystemdUnit, SysusersCreatesTheUserAndGpioGroup) {
  std::string out;
  if (run_capture("command -v systemd-sysusers", out) != 0) GTEST_SKIP() << "systemd-sysusers not installed";
  const fs::path root = kDir / "sysroot";
  fs::remove_all(root);
  fs::create_directories(root / "etc");
  const fs::path conf = fs::path(STAIRGUIDE_SOURCE_DIR) / "systemd" / "stairguide.sysusers";
  ASSERT_EQ(run_capture("systemd-sysusers --root=" + root.string() + " " + conf.string(), out), 0) << out;
  const std::string passwd = read_file(root / "etc" / "passwd"), group = read_file(root / "etc" / "group");
  EXPECT_NE(passwd.find("stairguide:x:"), std::string::npos) << passwd;
  EXPECT_NE(passwd.find("nologin"), std::string::npos) << passwd;
  EXPECT_TRUE(std::regex_search(group, std::regex("(^|\n)gpio:x:[0-9]+:stairguide"))) << group;
  const std::string rules =
      read_file(fs::path(STAIRGUIDE_SOURCE_DIR) / "systemd" / "60-stairguide-gpio.rules");
  EXPECT_NE(rules.find("SUBSYSTEM==\"gpio\""), std::string::npos);
  EXPECT_NE(rules.find("GROUP=\"gpio\""), std::string::npos);
}
