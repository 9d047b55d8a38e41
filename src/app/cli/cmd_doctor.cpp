// doctor: checks what the daemon needs, in the order a helper setting up the backpack would, and
// says in plain words what is wrong and how to fix it. Each check is one line: its name, ok / FAIL
// / info, what was found, and for a failure the fix. The exit code is 0 only when nothing failed
// (an "info" line is never a failure: a daemon that is not running has learned nothing, and that
// is fine).
//
// The hardware checks use the daemon's own code paths: the camera is opened as the daemon opens
// it (DeviceSource, then one frame read), the tone is played through the daemon's ALSA sink and
// the buzzer line is requested as the daemon requests it. So a pass here means the daemon will
// get the same devices, as long as it runs with the same permissions (the user check).
#include <grp.h>
#include <pwd.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <mutex>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "cli/command.hpp"
#include "stairguide/capture/device.hpp"
#include "stairguide/config/config_loader.hpp"
#include "stairguide/core/json.hpp"
#include "stairguide/feedback/audio_sink.hpp"
#include "stairguide/feedback/button.hpp"
#include "stairguide/feedback/cue.hpp"
#include "stairguide/feedback/haptic.hpp"
#include "stairguide/feedback/sound_bank.hpp"
#include "stairguide/runtime/devices/alsa_audio_sink.hpp"
#include "stairguide/runtime/devices/button_reader.hpp"
#include "stairguide/runtime/devices/haptic_player.hpp"

namespace stairguide::cli {
namespace {

namespace fs = std::filesystem;

enum class Status { kOk, kFail, kInfo };

struct Check {
  explicit Check(std::string n, Status s = Status::kOk) : name(std::move(n)), status(s) {}
  std::string name;
  Status status = Status::kOk;
  std::string message;  ///< what was found, in plain words
  std::string fix;      ///< how to fix it (failures; empty otherwise)
};

const char* status_word(Status s) { return s == Status::kOk ? "ok" : s == Status::kFail ? "fail" : "info"; }

std::string fmt_double(double v, int decimals) {
  char b[32];
  std::snprintf(b, sizeof b, "%.*f", decimals, v);
  return b;
}

/// stdout of a shell command (stderr dropped), trailing white space removed.
std::string shell(const std::string& command) {
  std::string out;
  FILE* p = popen((command + " 2>/dev/null").c_str(), "r");
  if (!p) return out;
  std::array<char, 4096> buf{};
  std::size_t n;
  while ((n = fread(buf.data(), 1, buf.size(), p)) > 0) out.append(buf.data(), n);
  pclose(p);
  while (!out.empty() && std::isspace(static_cast<unsigned char>(out.back()))) out.pop_back();
  return out;
}

std::vector<int> daemon_pids();

/// A running daemon holds the camera, and may hold the sound device and the buzzer line: a device
/// that is there but busy is then no fault of the setup. Such a failure becomes information,
/// naming the daemon; a device that is missing altogether stays a failure.
void judge_held_by_daemon(Check& c, const std::vector<int>& pids) {
  if (c.status != Status::kFail || pids.empty()) return;
  const std::string& m = c.message;
  const bool busy = m.find("busy") != std::string::npos || m.find("Busy") != std::string::npos;
  const bool held = c.name == "camera" ? m.find("cannot open") != std::string::npos || busy : busy;
  if (!held) return;
  c.status = Status::kInfo;
  c.message = "in use by the running daemon (pid " + std::to_string(pids.front()) +
              "), so not tried here: " + c.message +
              "; stop the daemon ('sudo systemctl stop stairguide') and "
              "run the doctor again to try it";
  c.fix.clear();
}

// ---- 1. config -------------------------------------------------------------------------------

Check check_config(const std::string& path, PipelineConfig& config) {
  Check c{"config"};
  if (path.empty()) {
    c.status = Status::kFail;
    c.message = "no config file found ($STAIRGUIDE_CONFIG unset, no /etc/stairguide/stairguide.yaml)";
    c.fix =
        "install the package (it puts the config in /etc/stairguide/stairguide.yaml), or name one with "
        "--config FILE; the checks below use the built-in defaults";
    return c;
  }
  ConfigLoadReport report;
  try {
    config = load_config(path, &report);
  } catch (const ConfigError& e) {
    c.status = Status::kFail;
    c.message = std::string("the config does not load: ") + e.what();
    c.fix = "edit " + path +
            " at the line and key named (every key, its unit and range are listed by "
            "'stairguide dump-config --defaults'), then run 'stairguide check-config " +
            path + "'; the checks below use the built-in defaults";
    return c;
  }
  c.message = path + " loads and every value is valid";
  if (!report.missing_keys.empty())
    c.message +=
        " (" + std::to_string(report.missing_keys.size()) + " keys not given: their defaults are used)";
  return c;
}

// ---- 2. camera -------------------------------------------------------------------------------

Check check_camera(const CaptureConfig& cfg) {
  Check c{"camera"};
  const std::string fix_plug =
      "plug the camera into a USB port of the laptop itself (a Kinect also needs its power supply), "
      "check that 'lsusb' lists it, and that the service user is in group 'video' (the 'user' line)";
  try {
    DeviceSource cam(cfg);
    RgbdFrame f;
    // A camera may take a moment to send its first frame after its streams start.
    ReadResult r;
    for (int attempt = 0; attempt < 3; ++attempt) {
      r = cam.read(f);
      if (r.ok() && f.has_depth()) break;
    }
    if (!r.ok() || !f.has_depth()) {
      c.status = Status::kFail;
      c.message =
          cam.describe() + " opened but sent no depth frame" + (r.message.empty() ? "" : ": " + r.message);
      c.fix = "unplug the camera and plug it in again (a USB 3 port can starve it: try a USB 2 port); " +
              fix_plug;
      return c;
    }
    int valid = cv::countNonZero(f.depth > 0);
    const double share = 100.0 * valid / std::max(1, f.depth.rows * f.depth.cols);
    c.message = cam.describe() + ": a frame read, " + std::to_string(f.depth.cols) + "x" +
                std::to_string(f.depth.rows) + " at " + std::to_string(cfg.fps) + " Hz, depth" +
                (f.color.empty() ? " only (no colour stream)" : " and colour") +
                (cam.registered() ? ", depth registered to colour" : "") + ", " + fmt_double(share, 0) +
                "% of the depth pixels valid";
    if (valid == 0) {
      c.status = Status::kFail;
      c.message += ": the depth image is empty";
      c.fix = "take the cap off the camera's projector and point it at the floor 0.5-4 m away";
    }
  } catch (const std::exception& e) {
    c.status = Status::kFail;
    c.message = e.what();
    c.fix = cfg.device_uri.empty() ? fix_plug
                                   : "capture.device_uri names '" + cfg.device_uri +
                                         "': leave it empty to take the first camera found, or " + fix_plug;
  }
  return c;
}

// ---- 3. sound --------------------------------------------------------------------------------

/// True when the kernel lists no sound card at all.
bool no_sound_card() {
  std::ifstream f("/proc/asound/cards");
  if (!f) return true;
  std::string all((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  return all.find("no soundcards") != std::string::npos ||
         all.find_first_not_of(" \n\t") == std::string::npos;
}

Check check_sound(const FeedbackConfig& cfg) {
  Check c{"sound"};
  if (!cfg.audio_enabled) {
    c.status = Status::kInfo;
    c.message = "audio cues are off in the config (feedback.audio_enabled: false): the wearer hears nothing";
    return c;
  }
  // A 0.3 s tone at 880 Hz, faded in and out, through the daemon's own sink.
  const int n = feedback::kSoundRate * 3 / 10;
  std::vector<std::int16_t> tone(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    const double fade = std::min(1.0, std::min(i, n - 1 - i) / (0.02 * feedback::kSoundRate));
    tone[static_cast<std::size_t>(i)] = static_cast<std::int16_t>(std::lround(
        12000.0 * cfg.volume * fade * std::sin(2 * 3.14159265358979 * 880.0 * i / feedback::kSoundRate)));
  }
  feedback::SoundBank bank;
  bank.clips["doctor_tone"] = tone;
  std::mutex m;
  std::string warning;
  runtime::devices::AudioEvents ev;
  ev.warn = [&](const std::string& w) {
    std::lock_guard<std::mutex> lk(m);
    if (warning.empty()) warning = w;
  };
  runtime::devices::AlsaSinkOptions opt;
  opt.device = cfg.audio_device;
  opt.retry_s = 60.0;  // one attempt
  opt.max_age_s = 2.0;
  runtime::devices::AlsaAudioSink sink(opt, bank, ev);
  feedback::Utterance u;
  u.id = 1;
  u.clips = {"doctor_tone"};
  u.label = "doctor";
  u.queued = feedback::SteadyClock::now();
  sink.play(u);
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(3);
  runtime::devices::AlsaAudioSink::Counters k;
  for (;;) {
    k = sink.counters();
    if (k.played > 0 || k.open_failures > 0 || std::chrono::steady_clock::now() > until) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  if (k.played > 0) {
    c.message = "a 0.3 s tone was played on ALSA device '" + cfg.audio_device +
                "' (the wearer should have heard a short beep)";
    return c;
  }
  c.status = Status::kFail;
  {
    std::lock_guard<std::mutex> lk(m);
    c.message = warning.empty() ? "ALSA device '" + cfg.audio_device + "' took no sound within 3 s" : warning;
  }
  // The sink's warning goes on about retrying: what matters here is what failed.
  if (c.message.rfind("audio: ", 0) == 0) c.message.erase(0, 7);
  if (const auto at = c.message.find("; going on without sound"); at != std::string::npos)
    c.message.resize(at);
  if (no_sound_card()) c.message += " (this machine has no sound card: /proc/asound/cards lists none)";
  c.fix =
      "plug in the headphones or USB sound card the wearer uses; 'aplay -L' lists the ALSA devices: "
      "set feedback.audio_device to the one to use (e.g. \"plughw:CARD=Device\") and run the doctor again";
  return c;
}

// ---- 4. buzzer and 4b. button: GPIO lines, requested as the daemon requests them ---------------

/// What names a GPIO device in the config and in its messages.
struct GpioDevice {
  const char* name;       ///< "buzzer"
  const char* file_what;  ///< what its test backend's file holds ("edge file")
  const char* room;       ///< the prefix of its errors ("haptic: ")
  const char* key;        ///< its line is feedback.KEY_chip / KEY_line ...
  const char* enabled;    ///< ... and feedback.ENABLED turns it off
  const char* also;       ///< the last words of the fix
};

/// Checks the line of `dev` that `chip` and `line` name: `use` opens it as the daemon does and
/// says what it did; the line's file when `chip` is "file:PATH" (a test device).
template <class Use>
Check check_gpio(const GpioDevice& dev, const std::string& chip, int line, Use use) {
  Check c{dev.name};
  const bool file = chip.rfind("file:", 0) == 0;
  const std::string where = file ? std::string("the ") + dev.name + "'s " + dev.file_what + " " +
                                       chip.substr(5) + " (a test " + dev.name + ")"
                                 : "GPIO line " + std::to_string(line) + " of '" + chip + "'";
  try {
    c.message = where + use(file);
  } catch (const std::exception& e) {
    c.status = Status::kFail;
    std::string why = e.what();
    if (why.rfind(dev.room, 0) == 0) why.erase(0, std::string(dev.room).size());
    c.message = std::string("cannot use the ") + dev.name + ": " + why;
    c.fix = std::string("'gpiodetect' lists the GPIO chips and 'gpioinfo CHIP' their lines: set feedback.") +
            dev.key + "_chip and feedback." + dev.key + "_line to the " + dev.name + "'s (or feedback." +
            dev.enabled + ": false for none); " + dev.also;
  }
  return c;
}

Check check_buzzer(const FeedbackConfig& cfg) {
  if (!cfg.haptic_enabled) {
    Check c{"buzzer", Status::kInfo};
    c.message = "the buzzer is off in the config (feedback.haptic_enabled: false): no vibration cues";
    return c;
  }
  const GpioDevice dev{"buzzer", "edge file",      "haptic: ",
                       "gpio",   "haptic_enabled", "a line 'used' by another program must be freed first"};
  return check_gpio(dev, cfg.gpio_chip, cfg.gpio_line, [&](bool file) {
    auto line = runtime::devices::make_haptic_line(cfg.gpio_chip, cfg.gpio_line);
    line->set(true);  // one 150 ms pulse: the helper can feel that this is the right line
    std::this_thread::sleep_for(std::chrono::milliseconds(150));
    line->set(false);
    return std::string(file ? " written" : " requested") +
           " and pulsed once for 150 ms: the wearer should have felt one buzz";
  });
}

// ---- 4b. the wearer's button (only when the config asks for one) ------------------------------

Check check_button(const FeedbackConfig& cfg) {
  const GpioDevice dev{
      "button", "presses file", "button: ", "button", "button_enabled", "the user must be in group gpio"};
  return check_gpio(dev, cfg.button_chip, cfg.button_line, [&](bool file) {
    const auto line =
        runtime::devices::make_button_line(cfg.button_chip, cfg.button_line, cfg.button_active_low, nullptr);
    return std::string(file ? " opened" : " requested for its edges") +
           ": the wearer's presses will be read (short: where are the stairs; long: mute; double: verbosity)";
  });
}

// ---- 5. the service user ---------------------------------------------------------------------

struct Identity {
  std::string name;
  uid_t uid = 0;
  gid_t gid = 0;
  std::vector<gid_t> groups;
  bool has(gid_t g) const { return g == gid || std::find(groups.begin(), groups.end(), g) != groups.end(); }
};

bool find_user(const std::string& name, Identity& id) {
  const passwd* pw = getpwnam(name.c_str());
  if (!pw) return false;
  id.name = name;
  id.uid = pw->pw_uid;
  id.gid = pw->pw_gid;
  int n = 64;
  std::vector<gid_t> g(static_cast<std::size_t>(n));
  if (getgrouplist(name.c_str(), pw->pw_gid, g.data(), &n) < 0) {
    g.resize(static_cast<std::size_t>(n));
    getgrouplist(name.c_str(), pw->pw_gid, g.data(), &n);
  }
  g.resize(static_cast<std::size_t>(std::max(n, 0)));
  id.groups = g;
  return true;
}

/// Whether `id` may access `st` for `want` (4 read, 2 write, 1 execute/search, or-ed).
bool may(const Identity& id, const struct stat& st, int want) {
  if (id.uid == 0) return true;
  int bits = static_cast<int>(st.st_mode) & 7;
  if (st.st_uid == id.uid)
    bits = (static_cast<int>(st.st_mode) >> 6) & 7;
  else if (id.has(st.st_gid))
    bits = (static_cast<int>(st.st_mode) >> 3) & 7;
  return (bits & want) == want;
}

std::string owner_text(const struct stat& st) {
  const passwd* pw = getpwuid(st.st_uid);
  const group* gr = getgrgid(st.st_gid);
  char mode[8];
  std::snprintf(mode, sizeof mode, "%04o", static_cast<unsigned>(st.st_mode & 07777));
  return std::string(pw ? pw->pw_name : std::to_string(st.st_uid)) + ":" +
         (gr ? gr->gr_name : std::to_string(st.st_gid)) + " " + mode;
}

/// The USB device nodes of the depth cameras OpenNI2 drives (PrimeSense/Asus, Microsoft, Orbbec).
std::vector<std::string> camera_usb_nodes() {
  std::vector<std::string> out;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator("/sys/bus/usb/devices", ec)) {
    auto read = [&](const char* name) {
      std::ifstream f(e.path() / name);
      std::string s;
      f >> s;
      return s;
    };
    const std::string vendor = read("idVendor");
    if (vendor != "1d27" && vendor != "045e" && vendor != "2bc5") continue;
    const std::string bus = read("busnum"), dev = read("devnum");
    if (bus.empty() || dev.empty()) continue;
    char path[64];
    std::snprintf(path, sizeof path, "/dev/bus/usb/%03d/%03d", std::atoi(bus.c_str()),
                  std::atoi(dev.c_str()));
    out.push_back(path);
  }
  return out;
}

std::vector<std::string> glob_dev(const std::string& dir, const std::regex& name) {
  std::vector<std::string> out;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec))
    if (std::regex_match(e.path().filename().string(), name)) out.push_back(e.path().string());
  std::sort(out.begin(), out.end());
  return out;
}

Check check_user(const std::string& name, const std::string& config_path, bool is_service_user) {
  Check c{"user"};
  Identity id;
  if (!find_user(name, id)) {
    c.status = Status::kFail;
    c.message = "the service user '" + name + "' does not exist: the service cannot start";
    c.fix =
        "install the stairguide package (it creates the user), or run 'sudo systemd-sysusers' with "
        "systemd/stairguide.sysusers installed as /usr/lib/sysusers.d/stairguide.conf";
    return c;
  }
  std::vector<std::string> problems, fixes;
  if (id.uid != 0) {
    // The unit adds these groups to the service (SupplementaryGroups=); each must exist, and the
    // user is a member of each (sysusers puts it there) so that it can also run the daemon by hand.
    const std::vector<std::pair<const char*, const char*>> needed{
        {"audio", "the sound card"}, {"video", "the camera"}, {"gpio", "the buzzer's GPIO chip"}};
    for (const auto& [group_name, what] : needed) {
      const group* g = getgrnam(group_name);
      if (!g) {
        problems.push_back(std::string("group '") + group_name + "' does not exist (it gives " + what +
                           " to the service; the unit cannot start without it)");
        fixes.push_back("'sudo systemd-sysusers' creates it from /usr/lib/sysusers.d/stairguide.conf");
      } else if (!id.has(g->gr_gid)) {
        problems.push_back("'" + name + "' is not in group '" + group_name + "' (" + what + ")");
        fixes.push_back("sudo usermod -aG " + std::string(group_name) + " " + name);
      }
    }
  }
  // The device nodes: what udev made of them decides whether the groups help.
  struct Node {
    std::string path, what, fix;
  };
  std::vector<Node> nodes;
  for (const auto& p : glob_dev("/dev/snd", std::regex("pcmC\\d+D\\d+p|controlC\\d+")))
    nodes.push_back({p, "the sound card",
                     "Debian gives /dev/snd to group audio: 'sudo udevadm trigger --subsystem-match=sound'"});
  for (const auto& p : glob_dev("/dev", std::regex("gpiochip\\d+")))
    nodes.push_back(
        {p, "the GPIO chip",
         "the package's udev rule gives it to group gpio: 'sudo udevadm control --reload && sudo udevadm "
         "trigger --subsystem-match=gpio'"});
  for (const auto& p : camera_usb_nodes())
    nodes.push_back(
        {p, "the camera",
         "OpenNI2's udev rule (package libopenni2-0) gives it to group video: replug the camera"});
  for (const auto& n : nodes) {
    struct stat st {};
    if (stat(n.path.c_str(), &st) != 0) continue;
    if (!may(id, st, 6)) {
      problems.push_back("'" + name + "' cannot open " + n.path + " (" + n.what + ", " + owner_text(st) +
                         ")");
      fixes.push_back(n.fix);
    }
  }
  // The config must be readable by the service (the unit's ProtectSystem keeps /etc read-only).
  struct stat st {};
  if (!config_path.empty() && stat(config_path.c_str(), &st) == 0 && !may(id, st, 4)) {
    problems.push_back("'" + name + "' cannot read " + config_path + " (" + owner_text(st) + ")");
    fixes.push_back("sudo chmod 0644 " + config_path);
  }
  if (!problems.empty()) {
    c.status = Status::kFail;
    c.message = problems.front();
    for (std::size_t i = 1; i < problems.size(); ++i) c.message += "; " + problems[i];
    c.fix = fixes.front();
    for (std::size_t i = 1; i < fixes.size(); ++i)
      if (c.fix.find(fixes[i]) == std::string::npos) c.fix += "; " + fixes[i];
    return c;
  }
  c.message = std::string(is_service_user ? "the service user '" : "user '") + name + "' (uid " +
              std::to_string(id.uid) + ") exists";
  if (id.uid == 0) {
    c.message += " and may open every device (root)";
  } else {
    c.message += ", is in groups audio, video and gpio";
    c.message += nodes.empty() ? " (no sound card, GPIO chip or camera device node here to try)"
                               : " and may open the " + std::to_string(nodes.size()) +
                                     " sound, GPIO and camera device nodes found";
  }
  return c;
}

// ---- 6. sounds -------------------------------------------------------------------------------

Check check_sounds(const FeedbackConfig& cfg, const std::string& user) {
  Check c{"sounds"};
  const std::string dir = cfg.sounds_dir;
  if (!fs::is_directory(dir)) {
    c.status = Status::kFail;
    c.message = "the sounds folder " + dir +
                " (feedback.sounds_dir) does not exist: every spoken cue would be silent";
    c.fix =
        "set feedback.sounds_dir to the folder of the cues: the package puts them in "
        "/usr/share/stairguide/sounds ('cmake --install' in PREFIX/share/stairguide/sounds)";
    return c;
  }
  // The words of the configured language (feedback.language), the earcons from the folder itself.
  const feedback::SoundSet set = feedback::sound_set_for(dir, cfg.language);
  if (!set.problem.empty()) {
    c.status = Status::kFail;
    c.message = set.problem + ": the daemon speaks English instead";
    c.fix = "set feedback.language to one of the folders under " + dir +
            " (en: the folder itself), or make the set with tools/make-sounds --lang " + cfg.language;
    return c;
  }
  const auto& names = feedback::all_clip_names();
  std::vector<std::pair<std::string, std::vector<std::string>>> folders;  // each folder, the clips it holds
  if (set.speech_dir == set.earcon_dir) {
    folders.push_back({dir, names});
  } else {
    folders.push_back({set.speech_dir, {}});
    folders.push_back({set.earcon_dir, {}});
    for (const auto& n : names) folders[feedback::is_earcon_clip(n) ? 1 : 0].second.push_back(n);
  }
  std::vector<std::string> problems;
  Identity id;
  const bool have_user = find_user(user, id);
  for (const auto& [folder, these] : folders) {
    const feedback::SoundBank bank = feedback::load_sound_bank(folder, these, 1.0f);
    problems.insert(problems.end(), bank.problems.begin(), bank.problems.end());
    if (!have_user) continue;
    struct stat st {};
    if (stat(folder.c_str(), &st) == 0 && !may(id, st, 5))
      problems.push_back("'" + user + "' cannot open the folder " + folder + " (" + owner_text(st) + ")");
    for (const auto& n : these) {
      const std::string p = folder + "/" + n + ".wav";
      if (stat(p.c_str(), &st) == 0 && !may(id, st, 4))
        problems.push_back("'" + user + "' cannot read " + p + " (" + owner_text(st) + ")");
    }
  }
  if (!problems.empty()) {
    c.status = Status::kFail;
    c.message = std::to_string(problems.size()) + " of the " + std::to_string(names.size()) +
                " cues the daemon speaks cannot be used: " + problems.front();
    for (std::size_t i = 1; i < std::min<std::size_t>(problems.size(), 4); ++i)
      c.message += "; " + problems[i];
    if (problems.size() > 4) c.message += "; ...";
    c.fix =
        "reinstall the package (sudo apt-get install --reinstall stairguide) or copy the WAVs of the "
        "source tree's sounds/ into " +
        dir + " (16-bit mono, readable by everyone)";
    return c;
  }
  c.message = "all " + std::to_string(names.size()) + " cues are in " + dir +
              (set.speech_dir != dir ? " (the words in " + set.speech_dir + ")" : std::string()) +
              " and readable";
  return c;
}

// ---- 7. the rig the running daemon learned -----------------------------------------------------

/// Pids of processes named stairguided-core (a comm is cut to 15 characters).
std::vector<int> daemon_pids() {
  std::vector<int> out;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator("/proc", ec)) {
    const std::string pid = e.path().filename().string();
    if (pid.find_first_not_of("0123456789") != std::string::npos) continue;
    std::ifstream f(e.path() / "comm");
    std::string comm;
    std::getline(f, comm);
    if (comm == "stairguided-cor" || comm == "stairguided-core") out.push_back(std::atoi(pid.c_str()));
  }
  return out;
}

Check check_rig() {
  Check c{"rig", Status::kInfo};
  const bool systemd = fs::is_directory("/run/systemd/system");
  const std::string state = systemd ? shell("systemctl is-active stairguide.service") : "";
  if (state == "active" || state == "reloading") {
    const std::string status = shell("systemctl show -p StatusText --value stairguide.service");
    const std::string invocation = shell("systemctl show -p InvocationID --value stairguide.service");
    std::string rig;
    if (!invocation.empty() && invocation.find_first_not_of("0123456789abcdef") == std::string::npos)
      rig = shell("journalctl -q --no-pager -o cat _SYSTEMD_INVOCATION_ID=" + invocation +
                  " | grep -E 'rig (learned|relearned):' | tail -n 1");
    c.message = "the service runs";
    if (!status.empty()) c.message += " (status: " + status + ")";
    std::smatch m;
    if (std::regex_search(rig, m, std::regex("frame (\\d+): rig (learned|relearned): (.*)$")))
      c.message += "; rig " + m[2].str() + " at frame " + m[1].str() + ": " + m[3].str();
    else if (geteuid() != 0 && rig.empty())
      c.message +=
          "; the rig it learned is in the journal, which this user may not read: run 'sudo "
          "stairguide doctor' to see it";
    else
      c.message +=
          "; no rig learned yet: the daemon learns the camera's height and tilt from its first "
          "clear views of the floor";
    return c;
  }
  const std::vector<int> pids = daemon_pids();
  if (!pids.empty()) {
    std::string list;
    for (std::size_t i = 0; i < pids.size(); ++i) list += (i ? ", " : "") + std::to_string(pids[i]);
    c.message = "stairguided runs outside the service (pid " + list +
                "): the rig it learned is in its own log ('rig learned' lines)";
    return c;
  }
  c.message = "no daemon running";
  if (systemd) {
    if (state == "failed")
      c.message += ": the service failed (see 'journalctl -u stairguide' for why)";
    else
      c.message += " (the service is " + (state.empty() ? std::string("not installed") : state) +
                   "; 'sudo systemctl start stairguide' starts it)";
  }
  c.message += ": no rig learned to show";
  return c;
}

// ---- the command -----------------------------------------------------------------------------

int doctor(Context& ctx) {
  const bool json = ctx.flag("--json");
  const std::string user = ctx.option("--user").value_or("stairguide");
  ctx.positionals(0, 0);
  if (user.empty()) throw UsageError("--user needs a user name");

  PipelineConfig config;  // the built-in defaults until the file loads
  std::vector<Check> checks;
  auto run = [&](Check c) {
    if (!json) {
      const char* tag = c.status == Status::kOk ? "[ ok ]" : c.status == Status::kFail ? "[FAIL]" : "[info]";
      std::printf("%s %-7s %s\n", tag, c.name.c_str(), c.message.c_str());
      if (c.status == Status::kFail && !c.fix.empty())
        std::printf("       %-7s fix: %s\n", "", c.fix.c_str());
      std::fflush(stdout);
    }
    checks.push_back(std::move(c));
  };
  const std::vector<int> daemons = daemon_pids();
  auto held = [&](Check c) {
    judge_held_by_daemon(c, daemons);
    return c;
  };
  run(check_config(ctx.config_path, config));
  run(held(check_camera(config.capture)));
  run(held(check_sound(config.feedback)));
  run(held(check_buzzer(config.feedback)));
  if (config.feedback.button_enabled) run(held(check_button(config.feedback)));
  run(check_user(user, ctx.config_path, user == "stairguide"));
  run(check_sounds(config.feedback, user));
  run(check_rig());

  std::vector<std::string> failed;
  for (const auto& c : checks)
    if (c.status == Status::kFail) failed.push_back(c.name);
  if (json) {
    std::string o = "{\"ok\": " + std::string(failed.empty() ? "true" : "false") + ", \"failed\": [";
    for (std::size_t i = 0; i < failed.size(); ++i) o += (i ? ", " : "") + json_quote(failed[i]);
    o += "], \"checks\": [";
    for (std::size_t i = 0; i < checks.size(); ++i) {
      const Check& c = checks[i];
      o += std::string(i ? ",\n  " : "\n  ") + "{\"name\": " + json_quote(c.name) +
           ", \"status\": " + json_quote(status_word(c.status)) + ", \"message\": " + json_quote(c.message) +
           ", \"fix\": " + json_quote(c.fix) + "}";
    }
    o += "\n]}\n";
    std::fputs(o.c_str(), stdout);
  } else if (failed.empty()) {
    std::printf("all is well: the daemon has what it needs\n");
  } else {
    std::string names;
    for (std::size_t i = 0; i < failed.size(); ++i) names += (i ? ", " : "") + failed[i];
    std::printf("%zu problem%s to fix: %s\n", failed.size(), failed.size() == 1 ? "" : "s", names.c_str());
  }
  return failed.empty() ? 0 : 1;
}

}  // namespace

SG_COMMAND("doctor", "doctor [--json] [--user NAME]",
           "check config, camera, sound, buzzer, button (when enabled), service user, sounds and the running "
           "daemon; say how to fix "
           "what is wrong (exit 0 when all is well)",
           doctor);

}  // namespace stairguide::cli
