// Single-frame inputs: organized PCD files (the real frames in ../shared/data) and one depth PNG
// with its camera.yaml.
#include <pcl/PCLPointCloud2.h>
#include <pcl/conversions.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include <cmath>
#include <filesystem>
#include <fstream>
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

// Checks the PCD header ourselves before PCL reads the file: PCL 1.13's reader crashes on some
// malformed files (a header without points), and our messages name the file and the problem.
void check_pcd_header(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw SourceError(path + ": cannot open PCD file");
  std::map<std::string, std::vector<std::string>> h;
  std::string line;
  std::streamoff header_end = 0;
  for (int n = 0; n < 64 && std::getline(in, line); ++n) {
    std::istringstream ss(line);
    std::string key, v;
    ss >> key;
    if (key.empty() || key[0] == '#') continue;
    while (ss >> v) h[key].push_back(v);
    if (key == "DATA") {
      header_end = in.tellg();
      break;
    }
  }
  for (const char* key : {"FIELDS", "SIZE", "TYPE", "WIDTH", "HEIGHT", "POINTS", "DATA"})
    if (h[key].empty()) throw SourceError(path + ": not a PCD file (header has no " + key + " line)");
  const auto& fields = h["FIELDS"];
  if (h["SIZE"].size() != fields.size() || h["TYPE"].size() != fields.size())
    throw SourceError(path + ": corrupt PCD header (FIELDS, SIZE and TYPE disagree)");
  long width = 0, height = 0, points = 0, point_size = 0;
  try {
    width = std::stol(h["WIDTH"][0]);
    height = std::stol(h["HEIGHT"][0]);
    points = std::stol(h["POINTS"][0]);
    for (std::size_t i = 0; i < fields.size(); ++i) {
      const long count = h["COUNT"].size() == fields.size() ? std::stol(h["COUNT"][i]) : 1;
      point_size += std::stol(h["SIZE"][i]) * count;
    }
  } catch (const std::exception&) {
    throw SourceError(path + ": corrupt PCD header (WIDTH, HEIGHT, POINTS, SIZE or COUNT is not a number)");
  }
  if (width <= 0 || height <= 0 || points != width * height)
    throw SourceError(path + ": corrupt PCD header (WIDTH " + std::to_string(width) + " x HEIGHT " +
                      std::to_string(height) + " != POINTS " + std::to_string(points) + ")");
  if (height <= 1)
    throw SourceError(path + ": not an organized point cloud (height " + std::to_string(height) + ")");
  const std::string data = h["DATA"][0];
  std::error_code ec;
  const auto size = static_cast<std::streamoff>(fs::file_size(path, ec));
  if (data == "binary") {
    if (size - header_end < static_cast<std::streamoff>(points * point_size))
      throw SourceError(path + ": truncated PCD (binary data shorter than " + std::to_string(points) +
                        " points)");
  } else if (data == "binary_compressed") {
    if (size - header_end < 8) throw SourceError(path + ": truncated PCD (no compressed data)");
  } else if (data != "ascii") {
    throw SourceError(path + ": unknown PCD DATA kind '" + data + "'");
  }
}

}  // namespace

RgbdFrame read_pcd_frame(const std::string& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw SourceError(path + ": PCD file missing (no such file)");
  if (!fs::is_regular_file(path, ec)) throw SourceError(path + ": not a regular file");
  check_pcd_header(path);
  pcl::PCLPointCloud2 blob;
  pcl::PCDReader reader;
  if (reader.read(path, blob) < 0 || blob.data.empty())
    throw SourceError(path + ": cannot read PCD (corrupt, truncated or not a PCD file)");
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
  if (!fs::exists(path, ec)) throw SourceError(path + ": depth image missing (no such file)");
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
