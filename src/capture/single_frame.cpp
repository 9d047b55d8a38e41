// Single-frame inputs: organized PCD files (the real frames in ../shared/data) and one depth PNG
// with its camera.yaml.
#include <pcl/PCLPointCloud2.h>
#include <pcl/conversions.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "capture_util.hpp"
#include "stairguide/capture/dataset.hpp"

namespace fs = std::filesystem;

namespace stairguide {
namespace {

// Least-squares fit of u = c + f * a over the valid pixels (a = x/z or y/z). Returns false when
// the points do not constrain the fit.
bool fit_axis(const std::vector<double>& a, const std::vector<double>& u, double& f, double& c) {
  const double n = static_cast<double>(a.size());
  if (a.size() < 100) return false;
  double sa = 0, su = 0, saa = 0, sau = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    sa += a[i];
    su += u[i];
    saa += a[i] * a[i];
    sau += a[i] * u[i];
  }
  const double var = saa - sa * sa / n;
  if (!(var > 1e-9 * n)) return false;
  f = (sau - sa * su / n) / var;
  c = (su - f * sa) / n;
  return f > 0.0 && std::isfinite(f) && std::isfinite(c);
}

template <class PointT>
void fill_depth_and_intrinsics(const pcl::PointCloud<PointT>& cloud, RgbdFrame& out) {
  const int w = static_cast<int>(cloud.width), h = static_cast<int>(cloud.height);
  out.depth.create(h, w, CV_32FC1);
  std::vector<double> ax, au, ay, av;
  for (int v = 0; v < h; ++v) {
    float* d = out.depth.ptr<float>(v);
    for (int u = 0; u < w; ++u) {
      const auto& p = cloud.at(u, v);
      const bool ok = std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z) && p.z > 0.f;
      d[u] = ok ? p.z : 0.f;
      if (ok) {
        ax.push_back(static_cast<double>(p.x) / p.z);
        au.push_back(u);
        ay.push_back(static_cast<double>(p.y) / p.z);
        av.push_back(v);
      }
    }
  }
  CameraIntrinsics k;
  double fx = 0, cx = 0, fy = 0, cy = 0;
  if (fit_axis(ax, au, fx, cx) && fit_axis(ay, av, fy, cy)) {
    k.width = w;
    k.height = h;
    k.fx = static_cast<float>(fx);
    k.fy = static_cast<float>(fy);
    k.cx = static_cast<float>(cx);
    k.cy = static_cast<float>(cy);
  } else {
    // Too few points to estimate: Kinect defaults scaled to the cloud's width.
    k = CameraIntrinsics{}.scaled(static_cast<float>(w) / 640.f);
    k.width = w;
    k.height = h;
  }
  out.intrinsics = k;
}

// Bounds on a PCD frame. A depth camera's organized cloud is at most a few megapixels with a
// few fields; these are far above that and far below what exhausts memory.
constexpr long long kMaxPcdSide = 16384;               // WIDTH and HEIGHT
constexpr long long kMaxPcdPoints = 4096LL * 4096LL;   // WIDTH x HEIGHT
constexpr long long kMaxPcdCount = 1024;               // COUNT of one field (a descriptor's bins)
constexpr long long kMaxPcdPointBytes = 16384;         // one point's record
constexpr long long kMaxPcdDataBytes = 1LL << 30;      // the whole body, uncompressed
constexpr std::size_t kMaxPcdHeaderBytes = 64 * 1024;  // everything up to and including DATA

// Checks the PCD header ourselves before PCL reads the file: PCL 1.13's reader crashes on some
// malformed files (a header without points, a compressed body whose uncompressed size word is
// 0), allocates whatever size the header claims, and its messages do not name the file. Every
// size is bounded and checked against the file's own size here.
void check_pcd_header(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw SourceError(path + ": cannot open PCD file");
  std::string head(kMaxPcdHeaderBytes, '\0');
  in.read(&head[0], static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<std::size_t>(in.gcount()));
  std::map<std::string, std::vector<std::string>> h;
  std::size_t pos = 0;
  long long header_end = -1;
  for (int n = 0; n < 64 && pos < head.size(); ++n) {
    std::size_t eol = head.find('\n', pos);
    if (eol == std::string::npos) break;  // a header line longer than what is left of 64 KiB
    std::istringstream ss(head.substr(pos, eol - pos));
    pos = eol + 1;
    std::string key, v;
    ss >> key;
    if (key.empty() || key[0] == '#') continue;
    // PCL matches header keys by their first letters: a line "VIrmat" (found by fuzzing) left
    // its parse half done and crashed it. Only the keys of the format pass.
    static const char* const kKeys[] = {"VERSION", "FIELDS", "SIZE",      "TYPE",   "COUNT",
                                        "WIDTH",   "HEIGHT", "VIEWPOINT", "POINTS", "DATA"};
    if (std::none_of(std::begin(kKeys), std::end(kKeys), [&](const char* k) { return key == k; }))
      throw SourceError(path + ": corrupt PCD header (unknown line '" + key.substr(0, 40) + "')");
    auto& values = h[key];
    if (!values.empty()) throw SourceError(path + ": corrupt PCD header (" + key + " given twice)");
    while (ss >> v) values.push_back(v);
    if (key == "DATA") {
      header_end = static_cast<long long>(pos);
      break;
    }
  }
  for (const char* key : {"FIELDS", "SIZE", "TYPE", "WIDTH", "HEIGHT", "POINTS", "DATA"})
    if (h[key].empty()) throw SourceError(path + ": not a PCD file (header has no " + key + " line)");
  if (h.count("VIEWPOINT") && h["VIEWPOINT"].size() != 7)
    throw SourceError(path + ": corrupt PCD header (VIEWPOINT needs 7 numbers)");
  if (header_end < 0) throw SourceError(path + ": not a PCD file (no DATA line in the first 64 lines)");
  const auto& fields = h["FIELDS"];
  if (h["SIZE"].size() != fields.size() || h["TYPE"].size() != fields.size())
    throw SourceError(path + ": corrupt PCD header (FIELDS, SIZE and TYPE disagree)");
  if (!h["COUNT"].empty() && h["COUNT"].size() != fields.size())
    throw SourceError(path + ": corrupt PCD header (FIELDS and COUNT disagree)");
  auto number = [&](const std::string& text, const char* what) {
    try {
      std::size_t used = 0;
      const long long v = std::stoll(text, &used);
      if (used == text.size()) return v;
    } catch (const std::exception&) {
    }
    throw SourceError(path + ": corrupt PCD header (" + what + " '" + text + "' is not a whole number)");
  };
  const long long width = number(h["WIDTH"][0], "WIDTH"), height = number(h["HEIGHT"][0], "HEIGHT");
  const long long points = number(h["POINTS"][0], "POINTS");
  long long point_size = 0, values = 0;
  for (std::size_t i = 0; i < fields.size(); ++i) {
    const long long size = number(h["SIZE"][i], "SIZE");
    const long long count = h["COUNT"].empty() ? 1 : number(h["COUNT"][i], "COUNT");
    const std::string& type = h["TYPE"][i];
    if (size != 1 && size != 2 && size != 4 && size != 8)
      throw SourceError(path + ": corrupt PCD header (field '" + fields[i] + "' SIZE " +
                        std::to_string(size) + "; 1, 2, 4 or 8 expected)");
    if (type != "I" && type != "U" && type != "F")
      throw SourceError(path + ": corrupt PCD header (field '" + fields[i] + "' TYPE '" + type +
                        "'; I, U or F expected)");
    if (count < 1 || count > kMaxPcdCount)
      throw SourceError(path + ": PCD field '" + fields[i] + "' COUNT " + std::to_string(count) +
                        " is out of range [1, " + std::to_string(kMaxPcdCount) + "]");
    point_size += size * count;
    values += count;
  }
  if (width <= 0 || height <= 0 || width > kMaxPcdSide || height > kMaxPcdSide)
    throw SourceError(path + ": PCD WIDTH " + std::to_string(width) + " x HEIGHT " + std::to_string(height) +
                      " is out of range [1, " + std::to_string(kMaxPcdSide) + "] each");
  if (points != width * height)
    throw SourceError(path + ": corrupt PCD header (WIDTH " + std::to_string(width) + " x HEIGHT " +
                      std::to_string(height) + " != POINTS " + std::to_string(points) + ")");
  if (height <= 1)
    throw SourceError(path + ": not an organized point cloud (height " + std::to_string(height) + ")");
  if (points > kMaxPcdPoints)
    throw SourceError(path + ": PCD of " + std::to_string(points) + " points is more than " +
                      std::to_string(kMaxPcdPoints) + " (no depth camera gives that)");
  if (point_size > kMaxPcdPointBytes)
    throw SourceError(path + ": PCD point record of " + std::to_string(point_size) + " bytes is more than " +
                      std::to_string(kMaxPcdPointBytes));
  const long long data_bytes = points * point_size;
  if (data_bytes > kMaxPcdDataBytes)
    throw SourceError(path + ": PCD body of " + std::to_string(data_bytes) + " bytes is more than " +
                      std::to_string(kMaxPcdDataBytes));
  const std::string data = h["DATA"][0];
  std::error_code ec;
  const auto file_size = static_cast<long long>(fs::file_size(path, ec));
  if (ec) throw SourceError(path + ": cannot read the file's size (" + ec.message() + ")");
  const long long body = file_size - header_end;
  if (data == "binary") {
    if (body < data_bytes)
      throw SourceError(path + ": truncated PCD (binary data of " + std::to_string(body) + " bytes, " +
                        std::to_string(points) + " points of " + std::to_string(point_size) + " bytes need " +
                        std::to_string(data_bytes) + ")");
  } else if (data == "binary_compressed") {
    if (body < 8) throw SourceError(path + ": truncated PCD (no compressed data)");
    unsigned char w[8];
    in.clear();
    in.seekg(static_cast<std::streamoff>(header_end));
    in.read(reinterpret_cast<char*>(w), 8);
    if (in.gcount() != 8) throw SourceError(path + ": truncated PCD (no compressed data)");
    auto le32 = [&](int o) {
      return static_cast<long long>(w[o]) | static_cast<long long>(w[o + 1]) << 8 |
             static_cast<long long>(w[o + 2]) << 16 | static_cast<long long>(w[o + 3]) << 24;
    };
    const long long compressed = le32(0), uncompressed = le32(4);
    if (uncompressed != data_bytes)
      throw SourceError(path + ": corrupt PCD (compressed body says " + std::to_string(uncompressed) +
                        " bytes uncompressed, the header's " + std::to_string(points) + " points of " +
                        std::to_string(point_size) + " bytes are " + std::to_string(data_bytes) + ")");
    if (compressed <= 0 || compressed > body - 8)
      throw SourceError(path + ": truncated or corrupt PCD (compressed body of " +
                        std::to_string(compressed) + " bytes, the file holds " + std::to_string(body - 8) +
                        " after the header)");
  } else if (data == "ascii") {
    // Every value is at least one character and a separator.
    if (body < 2 * points * values - 1)
      throw SourceError(path + ": truncated PCD (ascii data of " + std::to_string(body) +
                        " bytes cannot hold " + std::to_string(points) + " points of " +
                        std::to_string(values) + " values)");
  } else {
    throw SourceError(path + ": unknown PCD DATA kind '" + data + "'");
  }
}

}  // namespace

RgbdFrame read_pcd_frame(const std::string& path) {
  std::error_code ec;
  if (const std::string why = why_unreadable(path); !why.empty() && !fs::is_directory(path, ec))
    throw SourceError(path + ": " +
                      (why == "no such file" ? "PCD file missing (no such file)"
                                             : "cannot read the PCD file (" + why + ")"));
  if (!fs::is_regular_file(path, ec)) throw SourceError(path + ": not a regular file");
  check_pcd_header(path);
  pcl::PCLPointCloud2 blob;
  pcl::PCDReader reader;
  int rc = -1;
  try {
    rc = reader.read(path, blob);
  } catch (const std::exception& e) {  // std::bad_alloc, pcl::IOException: named with the file
    throw SourceError(path + ": cannot read PCD (" + e.what() + ")");
  }
  if (rc < 0 || blob.data.empty())
    throw SourceError(path + ": cannot read PCD (corrupt, truncated or not a PCD file)");
  if (blob.data.size() < static_cast<std::size_t>(blob.width) * blob.height * blob.point_step)
    throw SourceError(path + ": cannot read PCD (fewer bytes than its points need)");
  if (blob.height <= 1)
    throw SourceError(path + ": not an organized point cloud (height " + std::to_string(blob.height) + ")");
  bool has_x = false, has_y = false, has_z = false, has_rgb = false;
  for (const auto& f : blob.fields) {
    has_x |= f.name == "x";
    has_y |= f.name == "y";
    has_z |= f.name == "z";
    has_rgb |= f.name == "rgb" || f.name == "rgba";
  }
  if (!has_x || !has_y || !has_z) throw SourceError(path + ": PCD has no x y z fields");
  RgbdFrame out;
  if (has_rgb) {
    pcl::PointCloud<pcl::PointXYZRGB> cloud;
    pcl::fromPCLPointCloud2(blob, cloud);
    fill_depth_and_intrinsics(cloud, out);
    out.color.create(out.depth.size(), CV_8UC3);
    for (int v = 0; v < out.color.rows; ++v) {
      cv::Vec3b* c = out.color.ptr<cv::Vec3b>(v);
      for (int u = 0; u < out.color.cols; ++u) {
        const auto& p = cloud.at(u, v);
        c[u] = cv::Vec3b(p.b, p.g, p.r);
      }
    }
    cv::cvtColor(out.color, out.gray, cv::COLOR_BGR2GRAY);
  } else {
    pcl::PointCloud<pcl::PointXYZ> cloud;
    pcl::fromPCLPointCloud2(blob, cloud);
    fill_depth_and_intrinsics(cloud, out);
  }
  return out;
}

RgbdFrame read_depth_png_frame(const std::string& path) {
  std::error_code ec;
  if (const std::string why = why_unreadable(path); !why.empty() && !fs::is_directory(path, ec))
    throw SourceError(path + ": " +
                      (why == "no such file" ? "depth image missing (no such file)"
                                             : "cannot read the depth image (" + why + ")"));
  const fs::path p(path);
  fs::path cam = p.parent_path() / "camera.yaml";
  if (!fs::exists(cam, ec)) cam = p.parent_path().parent_path() / "camera.yaml";
  if (!fs::exists(cam, ec))
    throw SourceError(
        path + ": no camera.yaml beside the image or in its parent folder (needed for the intrinsics)");
  const DatasetCamera c = read_camera_yaml(cam.string());
  cv::Mat raw = cv::imread(path, cv::IMREAD_UNCHANGED);
  if (raw.empty()) throw SourceError(path + ": cannot decode depth image (corrupt or not an image)");
  if (raw.type() != CV_16UC1)
    throw SourceError(path + ": depth image must be 16-bit single-channel, got " + describe_mat_type(raw));
  if (raw.cols != c.intrinsics.width || raw.rows != c.intrinsics.height)
    throw SourceError(path + ": depth image is " + std::to_string(raw.cols) + "x" + std::to_string(raw.rows) +
                      ", " + cam.string() + " says " + std::to_string(c.intrinsics.width) + "x" +
                      std::to_string(c.intrinsics.height));
  RgbdFrame out;
  raw.convertTo(out.depth, CV_32F, 1.0 / c.depth_scale);
  out.intrinsics = c.intrinsics;
  return out;
}

SingleFrameSource::SingleFrameSource(RgbdFrame frame, std::string description)
    : frame_(std::move(frame)), description_(std::move(description)) {}

ReadResult SingleFrameSource::read(RgbdFrame& out) {
  if (done_) return {ReadStatus::kEnd, {}};
  done_ = true;
  out = frame_.clone();
  return {};
}

}  // namespace stairguide
