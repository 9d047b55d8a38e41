#pragma once
// Helpers the tests share for reading what a run wrote: a whole file, and the key=value tokens of
// the daemon's frame and summary lines. Header-only.
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

namespace stairguide::test {

/// The whole content of `p` ("" when it cannot be read).
inline std::string read_file(const std::filesystem::path& p) {
  std::ifstream f(p);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

/// The key=value tokens of one line ("frame=3 odom=ok ..."); words without '=' are skipped.
inline std::map<std::string, std::string> parse_kv(const std::string& line) {
  std::istringstream is(line);
  std::map<std::string, std::string> kv;
  std::string tok;
  while (is >> tok) {
    const auto eq = tok.find('=');
    if (eq != std::string::npos) kv[tok.substr(0, eq)] = tok.substr(eq + 1);
  }
  return kv;
}

}  // namespace stairguide::test
