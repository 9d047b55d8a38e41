// End to end on the live path: stairguided with no --replay, its capture on the virtual OpenNI2
// camera (src/vcam; LD_LIBRARY_PATH=build/vcam, a staircase dataset looping at 30 Hz). It sees the
// staircase; an unplug is logged as camera lost, cued (camera_lost) and put in STATUS; the
// reconnect attempts follow the back-off (retry_min, doubling, capped at retry_max: asserted from
// the log's time stamps); after the replug the camera is back and the frames go on.
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <fstream>
#include <regex>
#include <sstream>

#include "daemon_test_util.hpp"
#include "stairguide/config/config_loader.hpp"
#include "vcam_test_util.hpp"

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using namespace stairguide;

namespace {

const fs::path kDir = fs::path(STAIRGUIDE_BINARY_DIR) / "vcam_test_files";
constexpr double kRetryMin = 0.2, kRetryMax = 0.8;

/// A log line of stairguided: "YYYY-mm-dd HH:MM:SS.mmm stairguided LEVEL: text".
struct LogLine {
  double t = 0.0;  // s since midnight
  std::string text;
};
std::vector<LogLine> parse_log(const std::string& log) {
  static const std::regex re(R"(^\d{4}-\d\d-\d\d (\d\d):(\d\d):(\d\d\.\d{3}) stairguided \w+: (.*)$)");
  std::vector<LogLine> out;
  std::istringstream is(log);
  std::string line;
  std::smatch m;
  while (std::getline(is, line))
    if (std::regex_match(line, m, re))
      out.push_back({std::stoi(m[1]) * 3600.0 + std::stoi(m[2]) * 60.0 + std::stod(m[3]), m[4]});
  return out;
}

/// stairguided on the live camera: the virtual camera's environment, its log (stderr) to a file
/// read back by line.
class LiveDaemon : public sgtest::Daemon {
 public:
  LiveDaemon(const fs::path& config, const fs::path& dataset, const fs::path& control, const fs::path& log)
      : Daemon({"--config", config.string()}, options(dataset, control, log)) {}
  std::string log() const { return stderr_text(); }
  /// Waits until the log has a line containing `text` after the first `skip` such lines; false on
  /// timeout.
  bool wait_log(const std::string& text, double timeout_s, int skip = 0) {
    const auto until = Clock::now() + std::chrono::duration<double>(timeout_s);
    for (;;) {
      if (count_log(text) > skip) return true;
      if (Clock::now() >= until) return false;
      drain(50);
    }
  }
  int count_log(const std::string& text) const {
    int n = 0;
    for (const auto& l : parse_log(log())) n += l.text.find(text) != std::string::npos;
    return n;
  }

 private:
  static sgtest::DaemonOptions options(const fs::path& dataset, const fs::path& control,
                                       const fs::path& log) {
    sgtest::DaemonOptions o;
    const char* old = std::getenv("LD_LIBRARY_PATH");
    o.env = {{"LD_LIBRARY_PATH", test::vcam_dir() + (old && *old ? std::string(":") + old : "")},
             {"SGVCAM_DATASET", dataset.string()},
             {"SGVCAM_CONTROL", control.string()}};
    o.err_path = log.string();
    return o;
  }
};

}  // namespace

TEST(LiveDaemonOnVirtualCamera, SeesStairsLosesTheCameraOnUnplugBacksOffAndComesBackOnReplug) {
  const fs::path dataset = kDir / "ascending_640";
  test::write_vcam_dataset(dataset, "ascending_static", 6, 3);
  const fs::path control = kDir / ("daemon-control." + std::to_string(getpid()));
  const fs::path config = kDir / ("daemon." + std::to_string(getpid()) + ".yaml");
  test::set_plugged(control, true);
  PipelineConfig c;
  c.capture.device_uri = "sgvcam://0";
  c.capture.read_timeout = 5.0f;  // the unplug must be told by OpenNI2's event, not by a timeout
  c.capture.retry_min = static_cast<float>(kRetryMin);
  c.capture.retry_max = static_cast<float>(kRetryMax);
  c.runtime.status_interval = 0.3f;
  c.feedback.audio_enabled = false;
  c.feedback.haptic_enabled = false;
  {
    std::ofstream f(config);
    f << dump_config_yaml(c);
  }

  const fs::path log_path = kDir / ("daemon." + std::to_string(getpid()) + ".log");
  LiveDaemon d(config, dataset, control, log_path);
  ASSERT_TRUE(d.wait_log("camera open: OpenNI2 device stairguide virtual camera (sgvcam://0)", 20))
      << d.log();
  ASSERT_TRUE(d.wait_notify("READY=1", 5));
  ASSERT_TRUE(d.wait_log("state ascending", 20)) << "the staircase is seen on the live frames\n" << d.log();
  ASSERT_TRUE(d.wait_notify("STATUS=running: capture", 5));
  ASSERT_TRUE(d.wait_log("running: capture", 5, 2)) << "a second of frames before the unplug\n" << d.log();

  // Unplug: the camera is lost at once (OpenNI2's disconnect event), the user is told (cue), the
  // daemon says so in STATUS and retries with back-off; four failed attempts: delays 0.2, 0.4,
  // 0.8 (doubled) and 0.8 s (capped).
  test::set_plugged(control, false);
  const auto unplugged = Clock::now();
  ASSERT_TRUE(d.wait_log("camera lost:", 3)) << d.log();
  const double noticed = std::chrono::duration<double>(Clock::now() - unplugged).count();
  EXPECT_LT(noticed, 1.5) << "told by the disconnect event, not after read_timeout (5 s)";
  EXPECT_TRUE(d.wait_log("cue camera_lost", 3)) << d.log();
  EXPECT_TRUE(d.wait_notify("STATUS=camera lost: ", 3));
  ASSERT_TRUE(d.wait_log("camera not available", 10, 3)) << d.log();
  test::set_plugged(control, true);
  ASSERT_TRUE(d.wait_log("camera back: OpenNI2 device stairguide virtual camera (sgvcam://0)", kRetryMax + 3))
      << d.log();
  EXPECT_TRUE(d.wait_log("cue camera_back", 3)) << d.log();
  // Frames go on: two status reports after the camera is back, the later one with at least
  // 0.5 s more frames captured than when it came back, and perception running on them.
  const int status_before = d.count_log("running: capture");
  EXPECT_TRUE(d.wait_log("running: capture", 10, status_before + 3)) << d.log();
  EXPECT_EQ(d.stop(5.0), 0) << d.log();

  // The back-off, from the log's time stamps.
  const auto lines = parse_log(d.log());
  double t_lost = -1.0;
  std::vector<double> t_fail, announced;
  double t_back = -1.0;
  static const std::regex retry_re(R"(retrying in ([0-9.]+) s)");
  for (const auto& l : lines) {
    if (t_lost < 0 && l.text.rfind("camera lost:", 0) == 0) {
      t_lost = l.t;
      EXPECT_NE(l.text.find("unplugged"), std::string::npos) << l.text;
      EXPECT_NE(l.text.find("back-off 0.20 .. 0.80 s"), std::string::npos) << l.text;
    }
    std::smatch m;
    if (t_lost >= 0 && t_back < 0 && l.text.rfind("camera not available", 0) == 0 &&
        std::regex_search(l.text, m, retry_re)) {
      t_fail.push_back(l.t);
      announced.push_back(std::stod(m[1]));
    }
    if (l.text.rfind("camera back:", 0) == 0) t_back = l.t;
  }
  ASSERT_GE(t_fail.size(), 4u) << d.log();
  ASSERT_GT(t_back, 0.0);
  // Each delay lasts at least what was announced (less 20 ms of log-stamp rounding) and not much
  // more (the open attempt itself is milliseconds; 0.3 s of slack for a loaded machine).
  const auto check = [](double measured, double want, const std::string& what) {
    EXPECT_GE(measured, want - 0.02) << what;
    EXPECT_LE(measured, want + 0.3) << what;
  };
  check(t_fail[0] - t_lost, kRetryMin, "lost -> first attempt (retry_min)");
  double want = kRetryMin;
  for (std::size_t i = 0; i < t_fail.size(); ++i) {
    want = std::min(2.0 * want, kRetryMax);
    EXPECT_NEAR(announced[i], want, 1e-6) << "attempt " << i + 1 << ": the delay doubles up to retry_max";
    const double next = i + 1 < t_fail.size() ? t_fail[i + 1] : t_back;
    check(next - t_fail[i], announced[i], "attempt " + std::to_string(i + 1) + " -> next");
  }
  static const std::regex status_re(
      R"(^running: capture ([0-9.]+) fps, odometry ([0-9.]+) fps, perception ([0-9.]+) fps.*totals (\d+) frames)");
  long frames_at_back = -1, frames_last = -1;
  double perception_fps_after = 0.0;
  for (const auto& l : lines) {
    std::smatch m;
    if (!std::regex_search(l.text, m, status_re)) continue;
    if (l.t < t_back) {
      frames_at_back = std::stol(m[4]);
    } else {
      frames_last = std::stol(m[4]);
      perception_fps_after = std::max(perception_fps_after, std::stod(m[3]));
    }
  }
  EXPECT_GE(frames_at_back, 20) << "frames before the unplug\n" << d.log();
  EXPECT_GE(frames_last, frames_at_back + 15) << "frames after the replug\n" << d.log();
  EXPECT_GT(perception_fps_after, 0.0) << d.log();
  const std::string log = d.log();
  EXPECT_NE(log.find("camera lost 1,"), std::string::npos) << "the summary counts one loss\n" << log;
  fs::remove(control);
  fs::remove(config);
  if (!HasFailure()) fs::remove(log_path);  // kept for a look when the test failed
}

// A dataset the driver cannot serve is named on stderr (so in the daemon's log), and the daemon
// waits for a camera as it does with none plugged in.
TEST(LiveDaemonOnVirtualCamera, ADatasetItCannotServeIsNamedAndTheDaemonWaitsForACamera) {
  fs::create_directories(kDir);
  PipelineConfig c;
  c.capture.device_uri = "sgvcam://0";
  c.capture.retry_min = 0.2f;
  c.feedback.audio_enabled = false;
  c.feedback.haptic_enabled = false;
  const fs::path config = kDir / ("bad-dataset." + std::to_string(getpid()) + ".yaml");
  {
    std::ofstream f(config);
    f << dump_config_yaml(c);
  }
  const fs::path control = kDir / ("bad-dataset-control." + std::to_string(getpid()));
  const fs::path log_path = kDir / ("bad-dataset." + std::to_string(getpid()) + ".log");
  const fs::path missing = kDir / "no-such-dataset";
  struct Case {
    fs::path dataset;
    std::string says;
  };
  for (const Case& k :
       {Case{missing, "sgvcam: SGVCAM_DATASET=" + missing.string() + ": " + missing.string() +
                          "/camera.yaml: missing; the virtual camera is not there"},
        Case{"vcam_test_files/ascending_640",
             "sgvcam: SGVCAM_DATASET=vcam_test_files/ascending_640: must be an absolute path"}}) {
    LiveDaemon d(config, k.dataset, control, log_path);
    SCOPED_TRACE(k.dataset.string());
    EXPECT_TRUE(d.wait_log("camera not available", 20)) << d.log();
    EXPECT_NE(d.log().find(k.says), std::string::npos) << d.log();
    EXPECT_EQ(d.count_log("camera open"), 0) << d.log();
    EXPECT_EQ(d.stop(5.0), 0) << d.log();
  }
  fs::remove(config);
  if (!HasFailure()) fs::remove(log_path);
}
