// `cmake --install` under prefixes other than the package's /usr (issue 41, defect 8: installed
// under /usr/local the config still named /usr/share/stairguide/sounds and the daemon was mute).
// Each case installs this build tree into a scratch DESTDIR and checks that the installed files
// name each other where they were put: the config's sounds_dir holds every cue, the unit's
// ExecStart is the installed launcher, and that launcher runs its own installed daemon.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

#include "cli_test_util.hpp"
#include "stairguide/config/config_loader.hpp"
#include "stairguide/feedback/cue.hpp"
#include "stairguide/feedback/sound_bank.hpp"
#include "file_test_util.hpp"

namespace fs = std::filesystem;
using namespace stairguide;
using stairguide::test::read_file;

namespace {

/// A scratch DESTDIR under the build folder, removed at the end of the test.
struct Destdir {
  fs::path dir;
  explicit Destdir(const std::string& name)
      : dir(fs::path(STAIRGUIDE_BINARY_DIR) / ("install-test-" + name + "-" + std::to_string(getpid()))) {
    fs::remove_all(dir);
  }
  ~Destdir() {
    std::error_code ec;
    fs::remove_all(dir, ec);
  }
};

/// Installs the build tree under `prefix` into `destdir`; the install's output on failure.
cli_test::CliRun install(const fs::path& destdir, const std::string& prefix) {
  return cli_test::run_shell("DESTDIR='" + destdir.string() + "' cmake --install '" + STAIRGUIDE_BINARY_DIR +
                             "' --prefix '" + prefix + "'");
}

void expect_installed_paths_agree(const std::string& prefix) {
  SCOPED_TRACE("prefix " + prefix);
  Destdir d(fs::path(prefix).filename().string());
  const cli_test::CliRun r = install(d.dir, prefix);
  ASSERT_EQ(r.code, 0) << r.out;

  // The config names the sounds this install put under the prefix, and they are all there.
  const fs::path config = d.dir / "etc/stairguide/stairguide.yaml";
  ASSERT_TRUE(fs::exists(config)) << r.out;
  const PipelineConfig c = load_config(config.string());
  EXPECT_EQ(c.feedback.sounds_dir, prefix + "/share/stairguide/sounds");
  const fs::path sounds = d.dir / fs::path(c.feedback.sounds_dir).relative_path();
  ASSERT_TRUE(fs::is_directory(sounds)) << sounds;
  const feedback::SoundBank bank =
      feedback::load_sound_bank(sounds.string(), feedback::all_clip_names(), 1.0f);
  EXPECT_TRUE(bank.problems.empty()) << bank.problems.front();
  EXPECT_EQ(bank.clips.size(), feedback::all_clip_names().size());
  // Only that line differs from the source tree's config (its comment kept).
  std::string source = read_file(fs::path(STAIRGUIDE_SOURCE_DIR) / "config/stairguide.yaml");
  source = std::regex_replace(source, std::regex("sounds_dir: \"/usr/share/stairguide/sounds\""),
                              "sounds_dir: \"" + prefix + "/share/stairguide/sounds\"");
  EXPECT_EQ(read_file(config), source);

  // The unit starts the launcher this install put under the prefix.
  const std::string unit =
      read_file(d.dir / fs::path(prefix).relative_path() / "lib/systemd/system/stairguide.service");
  std::smatch m;
  ASSERT_TRUE(
      std::regex_search(unit, m, std::regex("\nExecStart=(\\S+) --config /etc/stairguide/stairguide.yaml\n")))
      << unit;
  EXPECT_EQ(m[1].str(), prefix + "/bin/stairguided");
  const fs::path launcher = d.dir / fs::path(m[1].str()).relative_path();
  ASSERT_TRUE(fs::exists(launcher));
  EXPECT_TRUE(fs::exists(d.dir / fs::path(prefix).relative_path() / "lib/sysusers.d/stairguide.conf"));
  EXPECT_TRUE(
      fs::exists(d.dir / fs::path(prefix).relative_path() / "lib/udev/rules.d/60-stairguide-gpio.rules"));

  // The launcher runs the daemon installed beside it (found relative to itself, so even staged
  // under DESTDIR), which accepts the installed config.
  const cli_test::CliRun check =
      cli_test::run_shell("'" + launcher.string() + "' --check-config '" + config.string() + "'");
  EXPECT_EQ(check.code, 0) << check.out;
  EXPECT_NE(check.out.find(": ok"), std::string::npos) << check.out;
}

}  // namespace

TEST(Install, UnderUsrLocalTheConfigNamesTheInstalledSounds) { expect_installed_paths_agree("/usr/local"); }

TEST(Install, UnderAnyPrefixTheConfigAndUnitNameWhatWasInstalled) {
  expect_installed_paths_agree("/opt/stairguide-test");
}
