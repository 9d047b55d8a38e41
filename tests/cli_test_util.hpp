#pragma once
// Runs the stairguide binary (or a shell command) for CLI tests: exit code and stdout + stderr together.
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <string>

namespace cli_test {

struct CliRun {
  int code = -1;
  std::string out;  // stdout and stderr together
};

/// A shell command line: its exit code and its stdout + stderr together.
inline CliRun run_shell(const std::string& command) {
  CliRun r;
  const std::string cmd = command + " 2>&1";
  FILE* p = popen(cmd.c_str(), "r");
  if (!p) return r;
  std::array<char, 4096> buf{};
  std::size_t n;
  while ((n = fread(buf.data(), 1, buf.size(), p)) > 0) r.out.append(buf.data(), n);
  const int status = pclose(p);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

inline CliRun run(const std::string& args) { return run_shell(std::string(STAIRGUIDE_CLI) + " " + args); }

/// A scratch path in the build folder, unique to the test binary's `prefix`.
inline std::string tmp(const std::string& prefix, const std::string& name) {
  return std::string(STAIRGUIDE_BINARY_DIR) + "/" + prefix + name;
}

}  // namespace cli_test
