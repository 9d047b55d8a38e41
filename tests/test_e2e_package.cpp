// The Debian package, end to end, as a helper setting up the backpack laptop meets it (issue 41):
// tools/package builds it (lintian: no error), dpkg installs it (the service user and groups made,
// the unit neither enabled nor started), the installed unit verifies clean, the installed daemon
// replays the bundled demo scene as the service user and speaks its cues from the installed
// sounds, `stairguide doctor` finds the user, config and sounds in order, removing keeps the
// config and purging leaves nothing.
//
// It installs into this machine's system, so it runs only as root (CI), never over a stairguide
// package installed here, and never while dpkg is busy: each is a skip with the reason. It leaves
// the machine as it found it (the service user and group gpio it made are removed at the end).
#include <fcntl.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

#include "cli_test_util.hpp"
#include "file_test_util.hpp"

namespace fs = std::filesystem;
using stairguide::test::read_file;

namespace {

cli_test::CliRun sh(const std::string& command) { return cli_test::run_shell(command); }

/// Whether another process holds one of dpkg's locks (fcntl locks, as dpkg and apt take them).
bool dpkg_busy() {
  for (const char* lock : {"/var/lib/dpkg/lock-frontend", "/var/lib/dpkg/lock"}) {
    const int fd = open(lock, O_RDONLY);
    if (fd < 0) continue;
    struct flock fl {};
    fl.l_type = F_WRLCK;
    fl.l_whence = SEEK_SET;
    const bool held = fcntl(fd, F_GETLK, &fl) == 0 && fl.l_type != F_UNLCK;
    close(fd);
    if (held) return true;
  }
  return false;
}

bool installed() {
  return sh("dpkg-query -W -f='${Status}' stairguide").out.find("install ok installed") != std::string::npos;
}

/// A scratch folder the service user can read (the demo scene) and write (the cues it plays).
struct Scratch {
  fs::path dir;
  Scratch() {
    char tmpl[] = "/tmp/stairguide-package-test-XXXXXX";
    if (mkdtemp(tmpl)) dir = tmpl;
    fs::permissions(dir, fs::perms::all);
  }
  ~Scratch() {
    std::error_code ec;
    if (!dir.empty()) fs::remove_all(dir, ec);
  }
};

/// Leaves the machine as the test found it: purges the package when a failed assertion left it
/// installed, and removes the service user and group gpio when they were made by this test (the
/// package keeps them on purge, as Debian keeps system users).
struct RestoreAtEnd {
  bool purge = false;
  const bool had_user = sh("getent passwd stairguide").code == 0;
  const bool had_gpio = sh("getent group gpio").code == 0;
  ~RestoreAtEnd() {
    if (purge) sh("dpkg --purge stairguide");
    if (!had_user) sh("userdel stairguide; getent group stairguide >/dev/null && groupdel stairguide");
    if (!had_gpio) sh("groupdel gpio");
  }
};

}  // namespace

TEST(DebianPackage, BuildsInstallsVerifiesRunsAsTheServiceUserAndPurgesClean) {
  if (geteuid() != 0)
    GTEST_SKIP() << "needs root: it installs the package into this system with dpkg (CI runs as root)";
  if (sh("command -v dpkg && command -v systemd-analyze && command -v setpriv").code != 0)
    GTEST_SKIP() << "needs dpkg, systemd-analyze and setpriv (Debian's dpkg, systemd, util-linux)";
  if (dpkg_busy())
    GTEST_SKIP() << "dpkg is busy (another apt or dpkg holds its lock): try again when it is done";
  const cli_test::CliRun known = sh("dpkg-query -W -f='${Status}' stairguide");
  if (known.code == 0 && known.out.find("not-installed") == std::string::npos)
    GTEST_SKIP() << "a stairguide package is on this machine (" << known.out
                 << "): the test would replace and purge it";
  const auto t0 = std::chrono::steady_clock::now();
  Scratch s;
  ASSERT_FALSE(s.dir.empty());

  // Build: the .deb, lintian without error.
  const cli_test::CliRun pkg = sh("STAIRGUIDE_BUILD_DIR='" + std::string(STAIRGUIDE_BINARY_DIR) + "' '" +
                                  STAIRGUIDE_SOURCE_DIR + "/tools/package' --out '" + s.dir.string() + "'");
  ASSERT_EQ(pkg.code, 0) << pkg.out;
  const double built = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::smatch m;
  ASSERT_TRUE(std::regex_search(pkg.out, m, std::regex("(\\S+/stairguide_[0-9.]+_[a-z0-9]+\\.deb)\n?$")))
      << pkg.out;
  const std::string deb = m[1];
  EXPECT_NE(pkg.out.find("lintian: no errors"), std::string::npos) << pkg.out;
  const cli_test::CliRun fields = sh("dpkg-deb -f '" + deb + "' Depends");
  for (const char* lib : {"libopenni2-0", "libpcl-io", "libopencv-core", "libasound2", "libgpiod"})
    EXPECT_NE(fields.out.find(lib), std::string::npos) << "Depends lacks " << lib << ": " << fields.out;
  EXPECT_EQ(sh("dpkg-deb --info '" + deb + "' conffiles").out, "/etc/stairguide/stairguide.yaml\n");

  // Install.
  RestoreAtEnd restore;
  restore.purge = true;
  cli_test::CliRun in = sh("DEBIAN_FRONTEND=noninteractive dpkg -i '" + deb + "'");
  if (in.code != 0)  // dependencies missing on this machine: apt completes them
    in = sh("DEBIAN_FRONTEND=noninteractive apt-get install -f -y -q");
  ASSERT_EQ(in.code, 0) << in.out;
  ASSERT_TRUE(installed());
  const cli_test::CliRun groups = sh("id -nG stairguide");
  ASSERT_EQ(groups.code, 0) << "the service user was not made: " << groups.out;
  for (const char* g : {"audio", "video", "gpio"})
    EXPECT_NE((" " + groups.out).find(std::string(" ") + g), std::string::npos) << groups.out;
  EXPECT_FALSE(fs::exists("/etc/systemd/system/multi-user.target.wants/stairguide.service"))
      << "installing enabled the service";
  for (const char* f :
       {"/usr/bin/stairguide", "/usr/bin/stairguided", "/usr/libexec/stairguide/stairguided-core",
        "/usr/share/stairguide/sounds/last_step.wav", "/lib/systemd/system/stairguide.service",
        "/usr/lib/sysusers.d/stairguide.conf", "/lib/udev/rules.d/60-stairguide-gpio.rules"})
    EXPECT_TRUE(fs::exists(f)) << f;
  const std::string config = read_file("/etc/stairguide/stairguide.yaml");
  EXPECT_NE(config.find("sounds_dir: \"/usr/share/stairguide/sounds\""), std::string::npos);

  // The installed unit verifies without a word.
  const cli_test::CliRun verify = sh("systemd-analyze verify /lib/systemd/system/stairguide.service");
  EXPECT_EQ(verify.code, 0) << verify.out;
  EXPECT_EQ(verify.out, "") << "systemd-analyze verify must print nothing";

  // The bundled demo (tools/demo's scene and seed: a staircase approached and climbed), its first
  // 4 s rendered on the fly by the installed daemon, replayed as the service user with the
  // installed config; the cues go to an ALSA file PCM (this machine has no sound card) and must be
  // heard from the installed sounds: the daemon is not mute (defect 8).
  const fs::path wav = s.dir / "cues.wav";
  std::ofstream(s.dir / "asound.conf")
      << "pcm.cues { type file  slave.pcm { type null }  file \"" << wav.string() << "\"  format \"wav\" }\n";
  const cli_test::CliRun replay =
      sh("cd / && setpriv --reuid=stairguide --regid=stairguide --init-groups --reset-env env "
         "ALSA_CONFIG_PATH='" +
         (s.dir / "asound.conf").string() +
         "' /usr/bin/stairguided --replay synth:ascending_approach_climb:120:1 --sync --fast --no-haptic "
         "--audio cues");
  const std::string tail = replay.out.substr(replay.out.size() > 4000 ? replay.out.size() - 4000 : 0);
  EXPECT_EQ(replay.code, 0) << tail;
  ASSERT_TRUE(std::regex_search(
      replay.out, m,
      std::regex("summary frames=(\\d+) .* cues=(\\d+) cues_sounded=(\\d+) .* last_cue=(\\S+)")))
      << tail;
  EXPECT_EQ(m[1].str(), "120");
  EXPECT_GE(std::stoi(m[2]), 2) << "ready, then stairs ahead";
  EXPECT_EQ(m[3].str(), m[2].str()) << "every cue sounded";
  EXPECT_EQ(m[4].str().rfind("stairs_ahead_up", 0), 0u) << tail;
  EXPECT_EQ(replay.out.find("no usable sound"), std::string::npos) << tail;
  EXPECT_GT(fs::exists(wav) ? fs::file_size(wav) : 0, 44u + 2u * 22050u) << "at least a second of cues heard";
  const double replayed = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  // The doctor of the installed tool finds what the package provides: config, user, sounds.
  const cli_test::CliRun doc = sh("/usr/bin/stairguide doctor --json");
  for (const char* name : {"config", "user", "sounds"})
    EXPECT_TRUE(
        std::regex_search(doc.out, std::regex(std::string("\"name\": \"") + name + "\", \"status\": \"ok\"")))
        << name << ":\n"
        << doc.out;

  // Remove: the programs go, the config stays.
  const cli_test::CliRun rm = sh("dpkg -r stairguide");
  ASSERT_EQ(rm.code, 0) << rm.out;
  EXPECT_FALSE(fs::exists("/usr/bin/stairguided"));
  EXPECT_TRUE(fs::exists("/etc/stairguide/stairguide.yaml")) << "removing took the config";
  EXPECT_NE(sh("dpkg-query -W -f='${Status}' stairguide").out.find("config-files"), std::string::npos);

  // Purge: nothing is left.
  const cli_test::CliRun purged = sh("dpkg --purge stairguide");
  ASSERT_EQ(purged.code, 0) << purged.out;
  restore.purge = false;
  for (const char* f : {"/etc/stairguide", "/usr/bin/stairguide", "/usr/bin/stairguided",
                        "/usr/libexec/stairguide", "/usr/share/stairguide", "/usr/share/doc/stairguide",
                        "/lib/systemd/system/stairguide.service", "/usr/lib/sysusers.d/stairguide.conf",
                        "/lib/udev/rules.d/60-stairguide-gpio.rules", "/var/lib/stairguide"})
    EXPECT_FALSE(fs::exists(f)) << f << " is left after purge";
  EXPECT_EQ(sh("dpkg-query -W stairguide").code, 1) << "dpkg still knows the package";

  const double took = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("package test: %.0f s (package built in %.0f s, replay done at %.0f s)\n", took, built,
              replayed);
}
