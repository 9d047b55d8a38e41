// stairguided: the daemon. A thin main over stairguide::runtime: arguments, config, logging,
// signals (SIGTERM/SIGINT stop, SIGHUP reloads the config) and the exit code.
//
// Exit codes: 0 clean stop or end of replay, 1 a replay failed mid-way or a thread failed (out of
// memory: logged), 2 bad arguments, 3 config error, 4 the replay input cannot be opened, 5 the
// daemon could not start (out of threads or memory).
#include <signal.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <opencv2/core/utility.hpp>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <string>
#include <thread>

#include "stairguide/config/config_loader.hpp"
#include "stairguide/runtime/logging.hpp"
#include "stairguide/runtime/notifier.hpp"
#include "stairguide/runtime/runtime.hpp"

#include "stop_signals.hpp"

namespace {

using namespace stairguide;

constexpr const char* kUsage =
    "usage: stairguided [--config FILE] [--replay FILE.oni|DIR|synth:SCENE[:FRAMES[:SEED[:NOISE]]]]\n"
    "                   [--realtime|--fast] [--sync] [--frames N] [--no-frame-lines]\n"
    "                   [--audio DEVICE] [--no-haptic] [--perception-delay S]\n"
    "       stairguided --check-config FILE\n"
    "\n"
    "Runs the stair guidance pipeline on the live camera (default) or on a recording.\n"
    "  --config FILE       config (default: $STAIRGUIDE_CONFIG, /etc/stairguide/stairguide.yaml)\n"
    "  --replay INPUT      replay a recording instead of the camera; prints one line per frame\n"
    "  --realtime, --fast  replay paced by the frame timestamps, or as fast as possible\n"
    "                      (default: runtime.realtime_replay from the config)\n"
    "  --sync              one thread: every stage on every frame, in order\n"
    "  --frames N          stop after N frames\n"
    "  --no-frame-lines    no per-frame lines on stdout\n"
    "  --audio DEVICE      play the cues on ALSA PCM DEVICE (overrides feedback.audio_device)\n"
    "  --no-haptic         no buzzer (overrides feedback.haptic_enabled)\n"
    "  --perception-delay S  (tests) hold each frame S seconds before perception: a machine\n"
    "                      too slow for the camera, so that \"system slow\" is told\n"
    "  --check-config FILE validate FILE and exit (0 when valid)\n"
    "Signals: SIGTERM/SIGINT stop cleanly, SIGHUP reloads the config file.\n";

struct Args {
  std::string config_path;
  std::string check_path;
  std::string replay;
  int pacing = 0;  // 0 config, 1 realtime, 2 fast
  bool sync = false;
  bool frame_lines = true;
  long frames = -1;
  std::string audio;  // --audio DEVICE, empty: the config's
  bool no_haptic = false;
  double perception_delay = 0.0;  // s, --perception-delay
};

/// The command line's feedback overrides, applied to the config at start and to every reload.
void apply_overrides(const Args& a, PipelineConfig& c) {
  if (!a.audio.empty()) {
    c.feedback.audio_device = a.audio;
    c.feedback.audio_enabled = true;
  }
  if (a.no_haptic) c.feedback.haptic_enabled = false;
}

bool parse_args(int argc, char** argv, Args& a, std::string& err) {
  for (int i = 1; i < argc; ++i) {
    const std::string s = argv[i];
    auto value = [&](std::string& out) {
      if (i + 1 >= argc) {
        err = s + " needs a value";
        return false;
      }
      out = argv[++i];
      // An empty FILE would read as "not given" below: `--replay ""` started the live camera.
      if (out.empty()) {
        err = s + " needs a non-empty value";
        return false;
      }
      return true;
    };
    if (s == "--config") {
      if (!value(a.config_path)) return false;
    } else if (s == "--check-config") {
      if (!value(a.check_path)) return false;
    } else if (s == "--replay") {
      if (!value(a.replay)) return false;
    } else if (s == "--realtime") {
      a.pacing = 1;
    } else if (s == "--fast") {
      a.pacing = 2;
    } else if (s == "--sync") {
      a.sync = true;
    } else if (s == "--audio") {
      if (!value(a.audio)) return false;
    } else if (s == "--no-haptic") {
      a.no_haptic = true;
    } else if (s == "--no-frame-lines") {
      a.frame_lines = false;
    } else if (s == "--frames") {
      std::string v;
      if (!value(v)) return false;
      char* end = nullptr;
      a.frames = std::strtol(v.c_str(), &end, 10);
      if (v.empty() || *end || a.frames < 1) {
        err = "--frames expects a positive whole number, got '" + v + "'";
        return false;
      }
    } else if (s == "--perception-delay") {
      std::string v;
      if (!value(v)) return false;
      char* end = nullptr;
      a.perception_delay = std::strtod(v.c_str(), &end);
      if (*end || !(a.perception_delay >= 0.0 && a.perception_delay <= 10.0)) {
        err = "--perception-delay expects seconds in [0, 10], got '" + v + "'";
        return false;
      }
    } else if (s == "--help" || s == "-h") {
      std::fputs(kUsage, stdout);
      std::exit(0);
    } else {
      err = "unknown argument '" + s + "'";
      return false;
    }
  }
  return true;
}

// `stairguided` is a static launcher (stairguided_launcher.cpp) that blocks the stop and reload
// signals and execs this binary: the mask survives the exec, so a SIGTERM sent while the ~190
// shared libraries load waits for the signal thread instead of killing the process (exit 143).
// Run directly, this binary blocks them from its .preinit_array, before the libraries'
// constructors though after the dynamic loader's relocations (most of the start-up).
using stairguide_app::block_stop_signals;
__attribute__((section(".preinit_array"),
               used)) void (*const block_stop_signals_early)(int, char**, char**) = block_stop_signals;

/// The last word when memory ran out outside the runtime's threads (they log their own): a
/// message that needs no allocation when even logging cannot have any.
void say_out_of_memory(const char* where) noexcept {
  try {
    spdlog::critical(
        "out of memory (std::bad_alloc) {}: the memory limit (ulimit -v, the unit's MemoryMax=) "
        "is too small for the daemon; exiting",
        where);
    spdlog::default_logger()->flush();
  } catch (...) {
    static const char msg[] = "stairguided: out of memory (std::bad_alloc); exiting\n";
    [[maybe_unused]] const auto n = ::write(2, msg, sizeof msg - 1);
  }
}

int daemon_main(int argc, char** argv);

}  // namespace

int main(int argc, char** argv) {
  // An exception escaping main (out of memory under a tight limit) ended the process through
  // std::terminate with no log line (issue 41): it is named here and the exit is 5.
  try {
    return daemon_main(argc, argv);
  } catch (const std::bad_alloc&) {
    say_out_of_memory("while starting or stopping");
  } catch (const std::exception& e) {
    try {
      spdlog::critical("stopping on an unexpected error: {}", e.what());
      spdlog::default_logger()->flush();
    } catch (...) {
    }
  }
  return 5;
}

namespace {

int daemon_main(int argc, char** argv) {
  // Signals are taken synchronously by one thread (sigtimedwait), never by a handler. Blocked
  // first thing, so a SIGHUP or SIGTERM during start-up waits instead of killing the process;
  // every thread started later inherits the mask.
  const sigset_t sigs = stairguide_app::stop_and_reload_signals();
  pthread_sigmask(SIG_BLOCK, &sigs, nullptr);
  signal(SIGPIPE, SIG_IGN);

  Args args;
  std::string err;
  if (!parse_args(argc, argv, args, err)) {
    std::fprintf(stderr, "stairguided: %s\n%s", err.c_str(), kUsage);
    return 2;
  }

  if (!args.check_path.empty()) {
    try {
      load_config(args.check_path);
      std::printf("%s: ok\n", args.check_path.c_str());
      return 0;
    } catch (const std::exception& e) {
      std::fprintf(stderr, "stairguided: config error: %s\n", e.what());
      return 3;
    }
  }

  // OpenCV's own worker pool (cvtColor, convertTo in capture) would run beside the daemon's
  // capture, odometry and perception threads on a 2-core unit; each call runs on its caller.
  cv::setNumThreads(1);

  runtime::setup_logging("info");
  PipelineConfig config;
  if (args.config_path.empty()) args.config_path = default_config_path();
  try {
    if (!args.config_path.empty()) config = load_config(args.config_path);
  } catch (const std::exception& e) {
    spdlog::critical("config error: {}", e.what());
    return 3;
  }
  apply_overrides(args, config);
  runtime::set_log_level(config.runtime.log_level);
  spdlog::info("stairguided starting: config {}",
               args.config_path.empty() ? "(built-in defaults)" : args.config_path);

  runtime::RuntimeOptions opt;
  const bool replay = !args.replay.empty();
  opt.input = replay ? args.replay : "device";
  opt.realtime = args.pacing == 0 ? config.runtime.realtime : args.pacing == 1;
  opt.synchronous = args.sync;
  opt.frame_lines = replay && args.frame_lines;
  opt.max_frames = args.frames;
  opt.perception_delay_s = args.perception_delay;
  if (opt.perception_delay_s > 0.0)
    spdlog::warn(
        "--perception-delay {:.3f} s: each frame is held that long before perception (a test of a slow "
        "machine)",
        opt.perception_delay_s);

  runtime::SystemdNotifier notifier;
  runtime::Runtime rt(config, opt, &notifier);
  try {
    rt.start();
  } catch (const SourceError& e) {
    spdlog::critical("cannot open input: {}", e.what());
    notifier.notify(std::string("STATUS=cannot open input: ") + e.what());
    return 4;
  } catch (const std::bad_alloc&) {
    say_out_of_memory("while starting the pipeline");
    notifier.notify("STATUS=cannot start: out of memory");
    return 5;
  } catch (const std::exception& e) {
    // A thread that cannot be had (StartError) or any other failure to start: not the input's.
    spdlog::critical("cannot start: {}", e.what());
    notifier.notify(std::string("STATUS=cannot start: ") + e.what());
    return 5;
  }

  std::atomic<bool> stop_requested{false};
  std::atomic<bool> signal_thread_quit{false};
  std::thread signal_thread([&] {
    while (!signal_thread_quit.load()) {
      timespec ts{0, 100 * 1000 * 1000};
      siginfo_t info{};
      const int sig = sigtimedwait(&sigs, &info, &ts);
      if (sig == SIGTERM || sig == SIGINT) {
        spdlog::info("{}: stopping", sig == SIGTERM ? "SIGTERM" : "SIGINT");
        notifier.notify("STOPPING=1");
        stop_requested.store(true);
        rt.request_stop();
      } else if (sig == SIGHUP) {
        if (args.config_path.empty()) {
          spdlog::warn("SIGHUP: no config file to reload (running on built-in defaults)");
          continue;
        }
        try {
          PipelineConfig fresh = load_config(args.config_path);
          apply_overrides(args, fresh);
          if (rt.reconfigure(fresh)) {
            spdlog::info("SIGHUP: config reloaded from {} (generation {})", args.config_path,
                         rt.stats().config_generation);
            notifier.notify("STATUS=config reloaded");
          } else {
            spdlog::info("SIGHUP: {} unchanged; the running config and its state are kept", args.config_path);
          }
        } catch (const std::exception& e) {
          spdlog::error("SIGHUP: config reload rejected, keeping the running config: {}", e.what());
          notifier.notify(std::string("STATUS=config reload rejected: ") + e.what());
        }
      }
    }
  });

  int code = 0;
  if (opt.synchronous) {
    code = rt.run();
  } else {
    while (!rt.wait_finished(std::chrono::milliseconds(200))) {
    }
  }
  // Threads have finished or are finishing: a stop request gives them 800 ms in all (the unit's
  // TimeoutStopSec is far longer, the promise is 1 s).
  const bool joined = rt.join(std::chrono::milliseconds(stop_requested.load() ? 800 : 60000));
  signal_thread_quit.store(true);
  signal_thread.join();
  code = rt.exit_code();
  const runtime::RuntimeStats st = rt.stats();
  spdlog::info("{}", st.summary());
  notifier.notify("STATUS=" + st.summary());
  // The summary line comes with or without the frame lines (--no-frame-lines leaves those out).
  if (replay) {
    std::printf(
        "summary frames=%llu odometry_frames=%llu odometry_lost=%llu perception_frames=%llu "
        "perception_skipped=%llu fps=%.2f latency_p50_ms=%.2f latency_p99_ms=%.2f state=%s traversal=%s "
        "traversal_step=%d traversal_left=%d traversal_known=%d cues=%llu cues_sounded=%llu "
        "cue_latency_p50_ms=%.2f cue_latency_p99_ms=%.2f last_cue=%s cues_lost=%llu odometry_lag_p99_ms=%.2f "
        "timestamps_replaced=%llu\n",
        static_cast<unsigned long long>(st.frames_captured),
        static_cast<unsigned long long>(st.odometry_frames),
        static_cast<unsigned long long>(st.odometry_frames_lost),
        static_cast<unsigned long long>(st.perception_frames),
        static_cast<unsigned long long>(st.perception_skipped), st.fps, st.latency_p50_ms, st.latency_p99_ms,
        st.state.c_str(), st.traversal_state.c_str(), st.traversal_step, st.traversal_left,
        st.traversal_known, static_cast<unsigned long long>(st.cues),
        static_cast<unsigned long long>(st.cues_sounded), st.cue_latency_p50_ms, st.cue_latency_p99_ms,
        st.last_cue.empty() ? "-" : st.last_cue.c_str(), static_cast<unsigned long long>(st.cues_lost),
        st.odometry_lag_p99_ms, static_cast<unsigned long long>(st.timestamps_replaced));
  }
  std::fflush(stdout);
  spdlog::default_logger()->flush();
  if (!joined) {
    // A thread is stuck in a device read: leave without waiting for it (its device is closed
    // by the kernel with the process).
    spdlog::error("exiting with a thread still blocked");
    spdlog::default_logger()->flush();
    _exit(code);
  }
  return code;
}
}  // namespace
