// `stairguide doctor`: on this machine's hardware (no camera, no GPIO chip) it fails naming the
// camera and the buzzer line and nothing else; with the virtual camera (src/vcam) and a file
// buzzer every check passes and it exits 0; a broken config, a sound device that cannot open,
// a missing cue and a missing user are each named with their fix; a running daemon is named.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "cli_test_util.hpp"
#include "stairguide/feedback/cue.hpp"
#include "daemon_test_util.hpp"
#include "file_test_util.hpp"
#include "stairguide/config/config_loader.hpp"
#include "vcam_test_util.hpp"

namespace fs = std::filesystem;
using namespace stairguide;
using test::read_file;

namespace {

const fs::path kDir = fs::path(STAIRGUIDE_BINARY_DIR) / "doctor_test_files";

/// A config for the doctor: the sounds of the source tree and the ALSA null device (this machine
/// has no sound card; "null" takes the samples as a card would), the rest as given.
fs::path write_config(const std::string& name, PipelineConfig c) {
  fs::create_directories(kDir);
  if (c.feedback.sounds_dir == PipelineConfig{}.feedback.sounds_dir)
    c.feedback.sounds_dir = std::string(STAIRGUIDE_SOURCE_DIR) + "/sounds";
  const fs::path p = kDir / (name + "." + std::to_string(getpid()) + ".yaml");
  std::ofstream(p) << dump_config_yaml(c);
  return p;
}

PipelineConfig null_sound_config() {
  PipelineConfig c;
  c.feedback.audio_device = "null";
  return c;
}

/// `stairguide --config CONFIG doctor ARGS` with `env` before it; the user checked is root, who
/// exists everywhere (the service user exists only where the package is installed).
cli_test::CliRun doctor(const fs::path& config, const std::string& args, const std::string& env = "") {
  return cli_test::run_shell(env + " " + STAIRGUIDE_CLI + " --config '" + config.string() +
                             "' doctor --user root " + args);
}

struct JsonCheck {
  std::string name, status, message, fix;
};

/// The checks of `doctor --json`, in order.
std::vector<JsonCheck> parse_checks(const std::string& json) {
  static const std::regex re(
      R"re(\{"name": "([a-z]+)", "status": "(ok|fail|info)", "message": "((?:[^"\\]|\\.)*)", "fix": "((?:[^"\\]|\\.)*)"\})re");
  std::vector<JsonCheck> out;
  for (std::sregex_iterator it(json.begin(), json.end(), re), end; it != end; ++it)
    out.push_back({(*it)[1], (*it)[2], (*it)[3], (*it)[4]});
  return out;
}

std::string failed_list(const std::string& json) {
  std::smatch m;
  return std::regex_search(json, m, std::regex(R"re("failed": \[([^\]]*)\])re")) ? m[1].str() : "(none)";
}

const JsonCheck* find(const std::vector<JsonCheck>& checks, const std::string& name) {
  for (const auto& c : checks)
    if (c.name == name) return &c;
  return nullptr;
}

}  // namespace

// This machine as it is: no camera, no GPIO chip. Exit 1, the camera and the buzzer line named
// (each with a fix), every other check passing or informational, in the order a helper works.
TEST(Doctor, WithoutCameraAndGpioItFailsNamingTheCameraAndTheBuzzerOnly) {
  if (fs::exists("/dev/gpiochip0"))
    GTEST_SKIP() << "this machine has a GPIO chip: the buzzer check could pass";
  const fs::path config = write_config("nohw", null_sound_config());
  const cli_test::CliRun j = doctor(config, "--json");
  EXPECT_EQ(j.code, 1) << j.out;
  EXPECT_EQ(failed_list(j.out), R"("camera", "buzzer")") << j.out;
  const auto checks = parse_checks(j.out);
  std::vector<std::string> order;
  for (const auto& c : checks) order.push_back(c.name);
  EXPECT_EQ(order, (std::vector<std::string>{"config", "camera", "sound", "buzzer", "user", "sounds", "rig"}))
      << j.out;
  for (const auto& c : checks) {
    if (c.name == "camera" || c.name == "buzzer") {
      EXPECT_EQ(c.status, "fail") << c.name;
      EXPECT_FALSE(c.fix.empty()) << c.name << " has no fix";
    } else if (c.name == "rig") {
      EXPECT_EQ(c.status, "info") << c.message;
    } else {
      EXPECT_EQ(c.status, "ok") << c.name << ": " << c.message;
    }
  }
  ASSERT_NE(find(checks, "camera"), nullptr);
  EXPECT_NE(find(checks, "camera")->message.find("no camera found"), std::string::npos) << j.out;
  EXPECT_NE(find(checks, "buzzer")->message.find("GPIO chip 'gpiochip0' line 17"), std::string::npos)
      << j.out;
  EXPECT_NE(find(checks, "sound")->message.find("tone was played on ALSA device 'null'"), std::string::npos);
  EXPECT_NE(
      find(checks, "sounds")
          ->message.find("all " + std::to_string(stairguide::feedback::all_clip_names().size()) + " cues"),
      std::string::npos)
      << j.out;
  // ("no daemon running", unless a daemon of another test runs on this machine meanwhile.)

  // The plain form says the same to a person: a line per check, the fix under each failure.
  const cli_test::CliRun t = doctor(config, "");
  EXPECT_EQ(t.code, 1) << t.out;
  EXPECT_NE(t.out.find("[FAIL] camera"), std::string::npos) << t.out;
  EXPECT_NE(t.out.find("[FAIL] buzzer"), std::string::npos) << t.out;
  EXPECT_NE(t.out.find("[ ok ] config"), std::string::npos) << t.out;
  EXPECT_NE(t.out.find("[info] rig"), std::string::npos) << t.out;
  EXPECT_NE(t.out.find("fix: plug the camera into a USB port"), std::string::npos) << t.out;
  EXPECT_NE(t.out.find("2 problems to fix: camera, buzzer"), std::string::npos) << t.out;
}

// The virtual camera (an OpenNI2 driver serving a staircase) and a buzzer writing its edges to a
// file: everything the daemon needs is there, exit 0; the buzzer was pulsed once.
TEST(Doctor, WithTheVirtualCameraAndAFileBuzzerAllIsWell) {
  const fs::path dataset = kDir / "ascending_640";
  test::write_vcam_dataset(dataset, "ascending_static", 6, 3);
  const fs::path edges = kDir / ("buzzer." + std::to_string(getpid()) + ".edges");
  fs::remove(edges);
  PipelineConfig c = null_sound_config();
  c.feedback.gpio_chip = "file:" + edges.string();
  const fs::path config = write_config("vcam", c);
  const char* old = std::getenv("LD_LIBRARY_PATH");
  const std::string env = "LD_LIBRARY_PATH='" + test::vcam_dir() +
                          (old && *old ? std::string(":") + old : "") + "' SGVCAM_DATASET='" +
                          fs::absolute(dataset).string() + "'";
  const cli_test::CliRun j = doctor(config, "--json", env);
  EXPECT_EQ(j.code, 0) << j.out;
  EXPECT_EQ(failed_list(j.out), "") << j.out;
  EXPECT_NE(j.out.find("\"ok\": true"), std::string::npos) << j.out;
  const auto checks = parse_checks(j.out);
  ASSERT_EQ(checks.size(), 7u) << j.out;
  const JsonCheck* cam = find(checks, "camera");
  ASSERT_NE(cam, nullptr);
  EXPECT_EQ(cam->status, "ok") << cam->message;
  EXPECT_NE(cam->message.find("sgvcam://0"), std::string::npos) << cam->message;
  EXPECT_NE(cam->message.find("640x480 at 30 Hz"), std::string::npos) << cam->message;
  EXPECT_EQ(find(checks, "buzzer")->status, "ok") << j.out;
  // One pulse on the line: on, then off about 150 ms later.
  std::istringstream is(read_file(edges));
  double t_on = -1, t_off = -1;
  int on = -1, off = -1;
  is >> t_on >> on >> t_off >> off;
  EXPECT_EQ(on, 1) << read_file(edges);
  EXPECT_EQ(off, 0) << read_file(edges);
  EXPECT_NEAR(t_off - t_on, 150.0, 60.0);

  const cli_test::CliRun t = doctor(config, "", env);
  EXPECT_EQ(t.code, 0) << t.out;
  EXPECT_NE(t.out.find("all is well"), std::string::npos) << t.out;
  EXPECT_EQ(t.out.find("[FAIL]"), std::string::npos) << t.out;
}

// What goes wrong in the field, each named with its fix, and the checks after it still run.
TEST(Doctor, ABrokenConfigIsNamedWithItsLineAndTheOtherChecksStillRun) {
  fs::create_directories(kDir);
  const fs::path config = kDir / ("broken." + std::to_string(getpid()) + ".yaml");
  std::ofstream(config) << "feedback:\n  audio_device: \"null\"\n  volume_percnt: 80\n";
  const cli_test::CliRun j = doctor(config, "--json");
  EXPECT_EQ(j.code, 1) << j.out;
  const auto checks = parse_checks(j.out);
  ASSERT_EQ(checks.size(), 7u) << j.out;
  EXPECT_EQ(checks[0].name, "config");
  EXPECT_EQ(checks[0].status, "fail");
  EXPECT_NE(checks[0].message.find(config.string() + ":3"), std::string::npos) << checks[0].message;
  EXPECT_NE(checks[0].message.find("volume_percnt"), std::string::npos) << checks[0].message;
  EXPECT_NE(checks[0].fix.find("stairguide check-config"), std::string::npos) << checks[0].fix;
}

TEST(Doctor, ASoundDeviceThatCannotOpenIsNamed) {
  // An ALSA configuration that defines no device at all: "default" cannot open, as on a laptop
  // whose sound card is missing.
  fs::create_directories(kDir);
  const fs::path alsa = kDir / "empty-asound.conf";
  std::ofstream(alsa) << "# no devices\n";
  PipelineConfig c;
  c.feedback.audio_device = "default";
  const fs::path config = write_config("nosound", c);
  const cli_test::CliRun j = doctor(config, "--json", "ALSA_CONFIG_PATH='" + alsa.string() + "'");
  EXPECT_EQ(j.code, 1) << j.out;
  const auto checks = parse_checks(j.out);
  const JsonCheck* s = find(checks, "sound");
  ASSERT_NE(s, nullptr) << j.out;
  EXPECT_EQ(s->status, "fail");
  EXPECT_NE(s->message.find("cannot open ALSA device 'default'"), std::string::npos) << s->message;
  EXPECT_NE(s->fix.find("feedback.audio_device"), std::string::npos) << s->fix;
}

TEST(Doctor, AMissingCueAndAMissingUserAreNamed) {
  const fs::path sounds = kDir / ("sounds." + std::to_string(getpid()));
  fs::remove_all(sounds);
  fs::create_directories(sounds);
  for (const auto& e : fs::directory_iterator(fs::path(STAIRGUIDE_SOURCE_DIR) / "sounds"))
    if (e.is_regular_file() && e.path().filename() != "last_step.wav")  // the English set, not es/, de/, ...
      fs::copy_file(e.path(), sounds / e.path().filename());
  PipelineConfig c = null_sound_config();
  c.feedback.sounds_dir = sounds.string();
  const fs::path config = write_config("nocue", c);
  const cli_test::CliRun j =
      cli_test::run_shell(std::string(STAIRGUIDE_CLI) + " --config '" + config.string() +
                          "' doctor --json --user no-such-stairguide-user");
  EXPECT_EQ(j.code, 1) << j.out;
  const auto checks = parse_checks(j.out);
  const JsonCheck* s = find(checks, "sounds");
  ASSERT_NE(s, nullptr) << j.out;
  EXPECT_EQ(s->status, "fail");
  EXPECT_NE(
      s->message.find("1 of the " + std::to_string(stairguide::feedback::all_clip_names().size()) + " cues"),
      std::string::npos)
      << s->message;
  EXPECT_NE(s->message.find("last_step.wav"), std::string::npos) << s->message;
  const JsonCheck* u = find(checks, "user");
  ASSERT_NE(u, nullptr);
  EXPECT_EQ(u->status, "fail");
  EXPECT_NE(u->message.find("'no-such-stairguide-user' does not exist"), std::string::npos) << u->message;
  EXPECT_NE(u->fix.find("systemd-sysusers"), std::string::npos) << u->fix;
  fs::remove_all(sounds);
}

// A daemon running (here by hand, outside the service): the rig line names it, as information.
TEST(Doctor, ARunningDaemonIsNamedAndIsNoFailure) {
  const fs::path config = write_config("running", null_sound_config());
  sgtest::Daemon d({"--config", config.string(), "--replay", "synth:ascending_static:900", "--realtime",
                    "--no-haptic", "--no-frame-lines"});
  ASSERT_TRUE(d.wait_notify("READY=1", 30));
  const cli_test::CliRun j = doctor(config, "--json");
  const auto checks = parse_checks(j.out);
  const JsonCheck* rig = find(checks, "rig");
  ASSERT_NE(rig, nullptr) << j.out;
  EXPECT_EQ(rig->status, "info");
  // (Other tests' daemons may run on this machine too: the list holds this one.)
  EXPECT_TRUE(
      std::regex_search(rig->message, std::regex("stairguided runs outside the service \\(pid [0-9, ]*\\b" +
                                                 std::to_string(d.pid()) + "\\b")))
      << rig->message;
  EXPECT_EQ(failed_list(j.out).find("rig"), std::string::npos) << j.out;
}

// The button is checked only when the config enables it: a chip that is not there fails naming the
// chip and the line, with a fix; a file button (the tests' backend) passes; with the button off the
// check is not in the list at all (WithoutCameraAndGpio...), and the language's words are checked.
TEST(Doctor, TheButtonWhenEnabledAndTheLanguagesWords) {
  PipelineConfig c = null_sound_config();
  c.feedback.haptic_enabled = false;
  c.feedback.button_enabled = true;
  c.feedback.button_chip = "gpiochip_sg_absent";
  c.feedback.button_line = 5;
  c.feedback.language = "es";
  cli_test::CliRun j = doctor(write_config("button", c), "--json");
  auto checks = parse_checks(j.out);
  std::vector<std::string> order;
  for (const auto& k : checks) order.push_back(k.name);
  EXPECT_EQ(order, (std::vector<std::string>{"config", "camera", "sound", "buzzer", "button", "user",
                                             "sounds", "rig"}))
      << j.out;
  const JsonCheck* b = find(checks, "button");
  ASSERT_NE(b, nullptr) << j.out;
  EXPECT_EQ(b->status, "fail");
  EXPECT_NE(
      b->message.find("cannot use the button: GPIO chip 'gpiochip_sg_absent' line 5: cannot open the chip"),
      std::string::npos)
      << b->message;
  EXPECT_NE(b->fix.find("feedback.button_chip"), std::string::npos) << b->fix;
  const JsonCheck* s = find(checks, "sounds");
  ASSERT_NE(s, nullptr);
  EXPECT_EQ(s->status, "ok") << s->message;
  EXPECT_NE(s->message.find("(the words in " + std::string(STAIRGUIDE_SOURCE_DIR) + "/sounds/es)"),
            std::string::npos)
      << s->message;

  const fs::path presses = kDir / "doctor.presses";
  std::ofstream(presses) << "";
  c.feedback.button_chip = "file:" + presses.string();
  c.feedback.language = "xx";
  j = doctor(write_config("button_file", c), "--json");
  checks = parse_checks(j.out);
  b = find(checks, "button");
  ASSERT_NE(b, nullptr) << j.out;
  EXPECT_EQ(b->status, "ok") << b->message;
  s = find(checks, "sounds");
  ASSERT_NE(s, nullptr);
  EXPECT_EQ(s->status, "fail");
  EXPECT_NE(s->message.find("no sounds for language 'xx'"), std::string::npos) << s->message;
}
