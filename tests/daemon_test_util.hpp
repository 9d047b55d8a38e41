#pragma once
// stairguided as a child process of an end-to-end test, started as systemd starts it: NOTIFY_SOCKET
// on an abstract datagram socket of the test, default signal dispositions, the test's arguments and
// environment; stdout through a pipe (the frame lines), to a file or to /dev/null; stderr (the log)
// to a file or to /dev/null. Header-only: each test binary includes it once.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstddef>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "file_test_util.hpp"

namespace sgtest {

/// Where the child's stdout goes.
enum class Stdout { null, pipe, file };

struct DaemonOptions {
  /// Set in the child's environment, over this process's and over what Daemon sets or clears.
  std::vector<std::pair<std::string, std::string>> env;
  Stdout out = Stdout::null;
  std::string out_path;  ///< stdout's file, for Stdout::file
  std::string err_path;  ///< stderr's file; "" for /dev/null
};

/// The child's environment: this process's without what a service manager or shell running the
/// test may have set for itself (its watchdog, its journal stream, a default config), then
/// NOTIFY_SOCKET=@`notify`, then `extra`.
inline std::vector<std::string> daemon_env(const std::string& notify,
                                           const std::vector<std::pair<std::string, std::string>>& extra) {
  std::map<std::string, std::string> env;
  for (char** e = environ; *e; ++e) {
    const std::string kv = *e;
    const std::size_t eq = kv.find('=');
    if (eq != std::string::npos) env[kv.substr(0, eq)] = kv.substr(eq + 1);
  }
  for (const char* key : {"WATCHDOG_USEC", "WATCHDOG_PID", "JOURNAL_STREAM", "STAIRGUIDE_CONFIG"})
    env.erase(key);
  env["NOTIFY_SOCKET"] = "@" + notify;
  for (const auto& [key, value] : extra) env[key] = value;
  std::vector<std::string> out;
  for (const auto& [key, value] : env) out.push_back(key + "=" + value);
  return out;
}

/// stairguided (the binary under test) run with `args`. The constructor returns once the child has
/// exec'd it: a signal sent then reaches stairguided, not the test's fork, and the output files
/// are already truncated (an old log cannot answer for this run). The destructor kills and reaps a
/// child still running.
class Daemon {
 public:
  explicit Daemon(const std::vector<std::string>& args, const DaemonOptions& o = {}) : err_path_(o.err_path) {
    static int counter = 0;
    const std::string name = "stairguide-test-" + std::to_string(getpid()) + "-" + std::to_string(counter++);
    notify_fd_ = socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    std::memcpy(addr.sun_path + 1, name.data(), name.size());  // sun_path[0] = 0: abstract namespace
    const auto len = static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + 1 + name.size());
    if (bind(notify_fd_, reinterpret_cast<sockaddr*>(&addr), len) != 0) ADD_FAILURE() << "bind notify socket";

    // All built before the fork, so that the child makes only async-signal-safe calls.
    std::vector<std::string> argv_s{STAIRGUIDED}, env_s = daemon_env(name, o.env);
    argv_s.insert(argv_s.end(), args.begin(), args.end());
    std::vector<char*> argv, envp;
    for (auto& a : argv_s) argv.push_back(a.data());
    for (auto& e : env_s) envp.push_back(e.data());
    argv.push_back(nullptr);
    envp.push_back(nullptr);
    int out_pipe[2] = {-1, -1};
    if (o.out == Stdout::pipe && pipe2(out_pipe, O_CLOEXEC) != 0) ADD_FAILURE() << "stdout pipe";
    const int out = o.out == Stdout::pipe   ? out_pipe[1]
                    : o.out == Stdout::file ? open_for_child(o.out_path)
                                            : open_for_child("");
    const int err = open_for_child(err_path_);
    int sync[2];
    if (pipe2(sync, O_CLOEXEC) != 0) ADD_FAILURE() << "sync pipe";

    pid_ = fork();
    if (pid_ == 0) {
      dup2(out, 1);
      dup2(err, 2);
      // Default dispositions and an empty mask, as systemd starts a service.
      sigset_t none;
      sigemptyset(&none);
      sigprocmask(SIG_SETMASK, &none, nullptr);
      for (int s : {SIGTERM, SIGINT, SIGHUP}) ::signal(s, SIG_DFL);
      execve(argv[0], argv.data(), envp.data());
      _exit(127);
    }
    if (pid_ < 0) ADD_FAILURE() << "fork";
    close(out);
    close(err);
    close(sync[1]);
    char c;
    while (read(sync[0], &c, 1) < 0 && errno == EINTR) {
    }  // EOF: the exec happened (the write end was close-on-exec)
    close(sync[0]);
    out_fd_ = out_pipe[0];
    eof_ = out_fd_ < 0;
  }
  ~Daemon() {
    if (pid_ > 0 && !reaped_) {
      kill(pid_, SIGKILL);
      int st = 0;
      waitpid(pid_, &st, 0);
    }
    if (out_fd_ >= 0) close(out_fd_);
    if (notify_fd_ >= 0) close(notify_fd_);
  }
  Daemon(const Daemon&) = delete;
  Daemon& operator=(const Daemon&) = delete;

  pid_t pid() const { return pid_; }
  /// Never to a pid of -1 (a failed fork): kill(-1, ...) signals every process of the user.
  void signal(int sig) const {
    if (pid_ > 0 && !reaped_) kill(pid_, sig);
  }

  /// Waits up to `ms` for stdout (when piped) or a notification, then takes what has come.
  void drain(int ms) {
    pollfd fds[2] = {{notify_fd_, POLLIN, 0}, {out_fd_, POLLIN, 0}};
    poll(fds, eof_ ? 1u : 2u, std::max(ms, 0));
    if (!eof_ && (fds[1].revents & (POLLIN | POLLHUP | POLLERR))) {
      char b[4096];
      const ssize_t k = ::read(out_fd_, b, sizeof b);
      if (k > 0)
        out_.append(b, static_cast<std::size_t>(k));
      else if (k == 0 || errno != EINTR)
        eof_ = true;
    }
    char b[4096];
    for (ssize_t k; (k = recv(notify_fd_, b, sizeof b, MSG_DONTWAIT)) > 0;)
      notes_.emplace_back(b, static_cast<std::size_t>(k));
  }

  /// The notifications so far, a datagram each (one may hold several lines, as READY=1 + STATUS=).
  const std::vector<std::string>& notes() const { return notes_; }
  /// The first notification line that starts with `prefix`, or "".
  std::string notify_line(const std::string& prefix) const {
    std::string line;
    return find_line(prefix, line) ? line : "";
  }
  /// Waits for a notification line that starts with `prefix` (or one already received); false on
  /// timeout.
  bool wait_notify(const std::string& prefix, double timeout_s = 20.0) {
    const auto until = deadline(timeout_s);
    for (std::string line;;) {
      if (find_line(prefix, line)) return true;
      const int ms = ms_until(until);
      if (ms <= 0) return false;
      drain(std::min(ms, 50));
    }
  }
  /// Notifications holding `text` anywhere: a count of 0 rules it out in any line.
  int count_notify(const std::string& text) const {
    int n = 0;
    for (const auto& m : notes_) n += m.find(text) != std::string::npos;
    return n;
  }

  /// Next stdout line (Stdout::pipe), or false at EOF / timeout. Notifications meanwhile are kept.
  bool read_line(std::string& line, double timeout_s = 20.0) {
    const auto until = deadline(timeout_s);
    for (;;) {
      const auto nl = out_.find('\n');
      if (nl != std::string::npos) {
        line = out_.substr(0, nl);
        out_.erase(0, nl + 1);
        return true;
      }
      if (eof_) return false;
      const int ms = ms_until(until);
      if (ms <= 0) return false;
      drain(ms);
    }
  }

  /// Waits for the exit, reading stdout meanwhile (a full pipe would stall the child) into `lines`
  /// when given; after the exit, what is left on stdout and the last notifications are taken too.
  /// Returns the exit code, 128 + N when killed by signal N, -1 on timeout.
  int wait_exit(double timeout_s, std::vector<std::string>* lines = nullptr) {
    if (reaped_) return code_;
    const auto until = deadline(timeout_s);
    for (std::string l;;) {
      while (read_line(l, 0.0))
        if (lines) lines->push_back(l);
      int st = 0;
      if (pid_ > 0 && waitpid(pid_, &st, WNOHANG) == pid_) {
        reaped_ = true;
        code_ = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
        while (read_line(l, 1.0))
          if (lines) lines->push_back(l);
        drain(10);
        return code_;
      }
      if (std::chrono::steady_clock::now() > until) return -1;
      drain(10);
    }
  }
  /// SIGTERM, then wait_exit.
  int stop(double timeout_s) {
    signal(SIGTERM);
    return wait_exit(timeout_s);
  }

  /// What the child wrote to stderr so far ("" with stderr to /dev/null).
  std::string stderr_text() const { return err_path_.empty() ? "" : stairguide::test::read_file(err_path_); }

 private:
  static std::chrono::steady_clock::time_point deadline(double s) {
    return std::chrono::steady_clock::now() +
           std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(s));
  }
  static int ms_until(std::chrono::steady_clock::time_point t) {
    return static_cast<int>(
        std::chrono::duration<double, std::milli>(t - std::chrono::steady_clock::now()).count());
  }
  /// `path` truncated, or /dev/null for ""; close-on-exec here, as dup2 clears that for the child.
  static int open_for_child(const std::string& path) {
    const int fd = path.empty() ? open("/dev/null", O_WRONLY | O_CLOEXEC)
                                : open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd < 0) ADD_FAILURE() << "open " << (path.empty() ? "/dev/null" : path);
    return fd;
  }
  bool find_line(const std::string& prefix, std::string& line) const {
    for (const auto& n : notes_)
      for (std::size_t at = 0; at != std::string::npos;) {
        const std::size_t end = n.find('\n', at);
        line = n.substr(at, end == std::string::npos ? end : end - at);
        if (line.rfind(prefix, 0) == 0) return true;
        at = end == std::string::npos ? end : end + 1;
      }
    return false;
  }

  pid_t pid_ = -1;
  int notify_fd_ = -1, out_fd_ = -1;
  bool eof_ = true, reaped_ = false;
  int code_ = -1;
  std::string err_path_, out_;
  std::vector<std::string> notes_;
};

}  // namespace sgtest
