#include "capture_util.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>

#include "stairguide/capture/frame_source.hpp"

namespace stairguide {

std::string trim(const std::string& s) {
  std::size_t a = 0, b = s.size();
  while (a < b && std::isspace(static_cast<unsigned char>(s[a]))) ++a;
  while (b > a && std::isspace(static_cast<unsigned char>(s[b - 1]))) --b;
  return s.substr(a, b - a);
}

bool parse_double(const std::string& s, double& out) {
  if (s.empty()) return false;
  char* end = nullptr;
  const double v = std::strtod(s.c_str(), &end);
  if (end != s.c_str() + s.size() || !std::isfinite(v)) return false;
  out = v;
  return true;
}

std::string fmt_num(double v) {
  char buf[40];
  for (int prec = 6; prec <= 17; ++prec) {
    std::snprintf(buf, sizeof buf, "%.*g", prec, v);
    if (std::strtod(buf, nullptr) == v) break;
  }
  return buf;
}

std::string describe_mat_type(const cv::Mat& m) {
  if (m.empty()) return "empty";
  const char* depth = "?";
  switch (m.depth()) {
    case CV_8U: depth = "8-bit"; break;
    case CV_8S: depth = "8-bit signed"; break;
    case CV_16U: depth = "16-bit"; break;
    case CV_16S: depth = "16-bit signed"; break;
    case CV_32S: depth = "32-bit integer"; break;
    case CV_32F: depth = "32-bit float"; break;
    case CV_64F: depth = "64-bit float"; break;
    default: break;
  }
  return std::string(depth) + " " + std::to_string(m.channels()) + "-channel";
}

cv::Mat depth_to_u16(const cv::Mat& depth_m, double scale) {
  cv::Mat out(depth_m.size(), CV_16UC1);
  for (int r = 0; r < depth_m.rows; ++r) {
    const float* s = depth_m.ptr<float>(r);
    std::uint16_t* d = out.ptr<std::uint16_t>(r);
    for (int c = 0; c < depth_m.cols; ++c) {
      const double v = static_cast<double>(s[c]) * scale;
      // NaN fails the comparison and becomes 0 (no reading), like values that do not fit.
      d[c] = (v > 0.0 && v < 65535.5) ? static_cast<std::uint16_t>(std::lround(v)) : std::uint16_t{0};
    }
  }
  return out;
}

std::string errno_words(int err) {
  switch (err) {
    case ENOENT: return "no such file";
    case EACCES:
    case EPERM: return "permission denied";
    case ELOOP: return "a symbolic link loop (too many levels of symbolic links)";
    case ENOTDIR: return "not a directory (a component of the path)";
    case ENAMETOOLONG: return "file name too long";
    default: return std::strerror(err);
  }
}

std::string why_unreadable(const std::string& path, bool directory) {
  if (path.empty()) return "no file name given";
  // Opened, not stat'ed or access()'ed: what the reader will meet (an unreadable file can be
  // stat'ed; root passes access() where a mount refuses). O_NONBLOCK: a FIFO does not wait here.
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC | (directory ? O_DIRECTORY : 0));
  if (fd < 0) return errno_words(errno);
  ::close(fd);
  return "";
}

std::string unreadable_words(const std::string& why, const std::string& what) {
  return why == "no such file" ? "missing (no such file)" : "cannot read " + what + " (" + why + ")";
}

std::string lower_extension(const std::string& path) {
  std::string e = std::filesystem::path(path).extension().string();
  std::transform(e.begin(), e.end(), e.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return e;
}

}  // namespace stairguide
