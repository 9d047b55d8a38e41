// Dataset folders (TUM RGB-D layout): reader, writer, camera.yaml, groundtruth.txt.
// labels.yaml lives in labels_yaml.cpp, the single-frame readers in single_frame.cpp.
#include "stairguide/capture/dataset.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "capture_util.hpp"
#include "stairguide/core/nearest_in_time.hpp"
#include "stairguide/config/strict_yaml.hpp"

namespace fs = std::filesystem;

namespace stairguide {

// ---------------------------------------------------------------- camera.yaml

DatasetCamera read_camera_yaml(const std::string& path) {
  std::error_code ec;
  if (const std::string why = why_unreadable(path); !why.empty())
    throw SourceError(path + ": " + unreadable_words(why, "it"));
  if (!fs::is_regular_file(path, ec)) throw SourceError(path + ": not a regular file");
  YAML::Node root;
  try {
    // Seven numbers and comments: 64 KiB and 1000 nodes are far more than one holds.
    root = load_strict_yaml(read_small_file(path, 64 * 1024, "camera.yaml"), path, YamlLimits{1000, 4});
  } catch (const InputFileError& e) {
    throw SourceError(e.what());
  }
  if (!root.IsMap()) throw SourceError(path + ": expected a mapping of fx fy cx cy width height depth_scale");
  auto get = [&](const char* key, double lo, double hi) {
    const YAML::Node n = root[key];
    if (!n) throw SourceError(path + ": missing key '" + key + "'");
    double v = 0.0;
    try {
      v = n.as<double>();
    } catch (const YAML::Exception&) {
      throw SourceError(path + ":" + std::to_string(n.Mark().line + 1) + ": key '" + key +
                        "' expects a number, got '" +
                        (n.IsScalar() ? n.Scalar() : std::string("(not a scalar)")) + "'");
    }
    if (!std::isfinite(v) || v < lo || v > hi)
      throw SourceError(path + ":" + std::to_string(n.Mark().line + 1) + ": key '" + key +
                        "' = " + n.Scalar() + " is out of range [" + fmt_num(lo) + ", " + fmt_num(hi) + "]");
    return v;
  };
  DatasetCamera c;
  c.intrinsics.fx = static_cast<float>(get("fx", 1e-3, 1e5));
  c.intrinsics.fy = static_cast<float>(get("fy", 1e-3, 1e5));
  c.intrinsics.cx = static_cast<float>(get("cx", -1e5, 1e5));
  c.intrinsics.cy = static_cast<float>(get("cy", -1e5, 1e5));
  const double w = get("width", 1, 100000), h = get("height", 1, 100000);
  if (w != std::floor(w) || h != std::floor(h))
    throw SourceError(path + ": width and height must be whole numbers");
  c.intrinsics.width = static_cast<int>(w);
  c.intrinsics.height = static_cast<int>(h);
  c.depth_scale = get("depth_scale", 1e-6, 1e9);
  return c;
}

void write_camera_yaml(const std::string& path, const DatasetCamera& c, const std::string& comment) {
  std::ofstream o(path);
  if (!o) throw SourceError(path + ": cannot create (" + std::strerror(errno) + ")");
  if (!comment.empty()) o << "# " << comment << "\n";
  o << "# pinhole intrinsics of the depth image (px); depth_scale = depth PNG units per metre\n";
  o << "fx: " << fmt_num(c.intrinsics.fx) << "\nfy: " << fmt_num(c.intrinsics.fy) << "\n";
  o << "cx: " << fmt_num(c.intrinsics.cx) << "\ncy: " << fmt_num(c.intrinsics.cy) << "\n";
  o << "width: " << c.intrinsics.width << "\nheight: " << c.intrinsics.height << "\n";
  o << "depth_scale: " << fmt_num(c.depth_scale) << "\n";
  o.flush();
  if (!o) throw SourceError(path + ": write failed");
}

// ---------------------------------------------------------------- lists

namespace {

struct ListEntry {
  double t = 0.0;
  std::string path;
};

// depth.txt, rgb.txt and groundtruth.txt: a line per frame (about 40-80 bytes); 256 MiB is
// millions of frames, hours at 30 Hz. A FIFO or a device is refused, never read.
constexpr std::size_t kMaxListBytes = 256u << 20;

std::string read_text(const std::string& file) {
  try {
    return read_small_file(file, kMaxListBytes, "list file");
  } catch (const InputFileError& e) {
    throw SourceError(e.what());
  }
}

// "timestamp path" lines, '#' comments and blank lines skipped.
std::vector<ListEntry> read_list(const std::string& file) {
  std::istringstream in(read_text(file));
  std::vector<ListEntry> out;
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const std::string t = trim(line);
    if (t.empty() || t[0] == '#') continue;
    std::istringstream ss(t);
    std::string ts, p, extra;
    ss >> ts >> p;
    double v = 0.0;
    if (p.empty() || !parse_double(ts, v) || (ss >> extra))
      throw SourceError(file + ":" + std::to_string(n) + ": expected 'timestamp path', got '" + t + "'");
    out.push_back({v, p});
  }
  return out;
}

}  // namespace

std::vector<TimedPose> read_groundtruth(const std::string& path) {
  std::istringstream in(read_text(path));
  std::vector<TimedPose> out;
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    const std::string t = trim(line);
    if (t.empty() || t[0] == '#') continue;
    std::istringstream ss(t);
    std::string tok[8], extra;
    double v[8];
    bool ok = true;
    for (int i = 0; i < 8 && ok; ++i) ok = static_cast<bool>(ss >> tok[i]) && parse_double(tok[i], v[i]);
    if (!ok || (ss >> extra))
      throw SourceError(path + ":" + std::to_string(n) +
                        ": expected 'timestamp tx ty tz qx qy qz qw', got '" + t + "'");
    // Finite is not enough: tx = 1e300 reads as a number, becomes inf in float and the ATE NaN.
    // No recording spans more than 100 km, and a TUM quaternion is written as a unit one.
    const std::string at = path + ":" + std::to_string(n) + ": ";
    if (std::abs(v[0]) > 1e10)
      throw SourceError(at + "timestamp " + tok[0] + " is out of range [-1e10, 1e10] s");
    for (int i = 1; i <= 3; ++i)
      if (std::abs(v[i]) > 1e5)
        throw SourceError(at + "translation " + tok[i] +
                          " m is out of range [-1e5, 1e5] (not a camera pose)");
    Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);
    for (int i = 4; i <= 7; ++i)
      if (std::abs(v[i]) > 2.0)
        throw SourceError(at + "quaternion component " + tok[i] + " is not that of a unit quaternion");
    if (!(q.norm() > 1e-6)) throw SourceError(at + "zero quaternion");
    if (std::abs(q.norm() - 1.0) > 0.01)
      throw SourceError(at + "quaternion of norm " + fmt_num(q.norm()) +
                        " (a rotation is a unit quaternion)");
    q.normalize();
    TimedPose p;
    p.timestamp = v[0];
    p.T_world_camera.setIdentity();
    p.T_world_camera.linear() = q.toRotationMatrix().cast<float>();
    p.T_world_camera.translation() = Eigen::Vector3d(v[1], v[2], v[3]).cast<float>();
    out.push_back(p);
  }
  std::stable_sort(out.begin(), out.end(),
                   [](const TimedPose& a, const TimedPose& b) { return a.timestamp < b.timestamp; });
  return out;
}

// ---------------------------------------------------------------- reader

DatasetSource::DatasetSource(const std::string& dir, const DatasetOptions& options) : dir_(dir) {
  std::error_code ec;
  if (const std::string why = why_unreadable(dir, true); !why.empty()) {
    if (why == "no such file") throw SourceError("dataset " + dir + ": folder missing (no such directory)");
    if (!(fs::exists(dir, ec) && !fs::is_directory(dir, ec)))  // else: a file, said below
      throw SourceError("dataset " + dir + ": cannot read the folder (" + why + ")");
  }
  if (!fs::is_directory(dir, ec)) throw SourceError("dataset " + dir + ": not a directory");
  const fs::path d(dir);
  camera_ = read_camera_yaml((d / "camera.yaml").string());
  const std::string depth_txt = (d / "depth.txt").string();
  if (!fs::exists(depth_txt, ec))
    throw SourceError(depth_txt + ": missing (a dataset folder needs depth.txt)");
  const auto depth = read_list(depth_txt);
  if (depth.empty()) throw SourceError(depth_txt + ": lists no depth images");
  std::vector<ListEntry> rgb;
  const std::string rgb_txt = (d / "rgb.txt").string();
  const bool has_rgb = fs::exists(rgb_txt, ec);
  if (has_rgb) {
    rgb = read_list(rgb_txt);
    if (rgb.empty()) throw SourceError(rgb_txt + ": lists no colour images");
  }
  // A clock that jumps back (or any list whose times do not grow) makes a time ambiguous: after a
  // 5 s jump back, frame 300's time is frame 150's, and nearest-time pairing gave it frame 150's
  // colour (issue 41). Such lists are paired in file order: each depth image with the nearest of
  // the next few colour images after the previous pair's. Lists in time order pair as before.
  // Equal times count as out of order too: every depth image took the first colour image of the time.
  auto in_order = [](const std::vector<ListEntry>& l) {
    return std::adjacent_find(l.begin(), l.end(),
                              [](const ListEntry& a, const ListEntry& b) { return !(b.t > a.t); }) == l.end();
  };
  const bool file_order = has_rgb && !(in_order(depth) && in_order(rgb));
  std::size_t prev_rgb = 0;
  bool have_prev = false;
  if (has_rgb && !file_order)
    std::stable_sort(rgb.begin(), rgb.end(),
                     [](const ListEntry& a, const ListEntry& b) { return a.t < b.t; });
  for (const auto& e : depth) {
    Pair p;
    p.t_depth = e.t;
    p.depth_path = (d / e.path).string();
    if (has_rgb) {
      const ListEntry* best = nullptr;
      if (file_order) {
        // The next few after the previous pair's (the earliest of equally near ones), or that one
        // again when it is nearer still (a colour camera slower than the depth camera).
        constexpr std::size_t kWindow = 8;
        const std::size_t start = have_prev ? prev_rgb + 1 : 0;
        for (std::size_t j = start; j < rgb.size() && j < start + kWindow; ++j)
          if (!best || std::abs(rgb[j].t - e.t) < std::abs(best->t - e.t)) best = &rgb[j];
        if (have_prev && (!best || std::abs(rgb[prev_rgb].t - e.t) < std::abs(best->t - e.t)))
          best = &rgb[prev_rgb];
        if (best && std::abs(best->t - e.t) <= options.max_pair_dt) {
          prev_rgb = static_cast<std::size_t>(best - rgb.data());
          have_prev = true;
        }
      } else {
        // Nearest colour timestamp by binary search.
        auto it = std::lower_bound(rgb.begin(), rgb.end(), e.t,
                                   [](const ListEntry& a, double t) { return a.t < t; });
        if (it != rgb.end()) best = &*it;
        if (it != rgb.begin() && (!best || std::abs((it - 1)->t - e.t) <= std::abs(best->t - e.t)))
          best = &*(it - 1);
      }
      if (!best || std::abs(best->t - e.t) > options.max_pair_dt) {
        ++skipped_;
        continue;
      }
      p.color_path = (d / best->path).string();
    }
    pairs_.push_back(std::move(p));
  }
  if (pairs_.empty())
    throw SourceError("dataset " + dir + ": no depth image has a colour image within " +
                      fmt_num(options.max_pair_dt * 1000.0) +
                      " ms (check the timestamps of depth.txt and rgb.txt)");
  const std::string gt = (d / "groundtruth.txt").string();
  if (fs::exists(gt, ec)) groundtruth_ = read_groundtruth(gt);
  const std::string labels = (d / "labels.yaml").string();
  FrameTruth folder;
  if (fs::exists(labels, ec) && read_folder_label_yaml(labels, folder)) {
    folder_label_ = std::move(folder);
  } else if (fs::exists(labels, ec)) {
    labels_ = read_labels_yaml(labels);
    std::stable_sort(labels_.begin(), labels_.end(),
                     [](const FrameTruth& a, const FrameTruth& b) { return a.timestamp < b.timestamp; });
  }
}

std::string DatasetSource::describe() const {
  std::string s = "dataset " + dir_ + " (" + std::to_string(pairs_.size()) + " frames";
  if (skipped_ > 0) s += ", " + std::to_string(skipped_) + " depth images without colour skipped";
  if (!groundtruth_.empty()) s += ", ground-truth poses";
  if (!labels_.empty()) s += ", labels";
  if (folder_label_) s += ", one label for the folder";
  return s + ")";
}

ReadResult DatasetSource::read(RgbdFrame& out) {
  if (next_ >= static_cast<long>(pairs_.size())) return {ReadStatus::kEnd, {}};
  const Pair& p = pairs_[static_cast<std::size_t>(next_)];
  const long index = next_++;
  std::error_code ec;
  auto fail = [&](const std::string& file, const std::string& why) {
    return ReadResult{ReadStatus::kError, file + ": " + why};
  };
  // Existence first: imread cannot tell a missing file from a corrupt one.
  // And readable: an unreadable image read as "corrupt" (issue 41).
  if (const std::string why = why_unreadable(p.depth_path); !why.empty())
    return fail(p.depth_path,
                why == "no such file" ? "depth image missing" : "cannot read depth image (" + why + ")");
  cv::Mat raw = cv::imread(p.depth_path, cv::IMREAD_UNCHANGED);
  if (raw.empty()) return fail(p.depth_path, "cannot decode depth image (corrupt or not an image)");
  if (raw.type() != CV_16UC1)
    return fail(p.depth_path, "depth image must be 16-bit single-channel, got " + describe_mat_type(raw));
  const CameraIntrinsics& k = camera_.intrinsics;
  if (raw.cols != k.width || raw.rows != k.height)
    return fail(p.depth_path, "depth image is " + std::to_string(raw.cols) + "x" + std::to_string(raw.rows) +
                                  ", camera.yaml says " + std::to_string(k.width) + "x" +
                                  std::to_string(k.height));
  raw.convertTo(out.depth, CV_32F, 1.0 / camera_.depth_scale);
  if (!p.color_path.empty()) {
    if (const std::string why = why_unreadable(p.color_path); !why.empty())
      return fail(p.color_path,
                  why == "no such file" ? "colour image missing" : "cannot read colour image (" + why + ")");
    cv::Mat c = cv::imread(p.color_path, cv::IMREAD_COLOR);
    if (c.empty()) return fail(p.color_path, "cannot decode colour image (corrupt or not an image)");
    if (c.cols != k.width || c.rows != k.height)
      return fail(p.color_path, "colour image is " + std::to_string(c.cols) + "x" + std::to_string(c.rows) +
                                    ", depth is " + std::to_string(k.width) + "x" + std::to_string(k.height));
    out.color = c;
    cv::cvtColor(out.color, out.gray, cv::COLOR_BGR2GRAY);
  } else {
    out.color.release();
    out.gray.release();
  }
  out.index = static_cast<std::uint64_t>(index);
  out.timestamp = p.t_depth;
  out.intrinsics = k;
  have_last_ = true;
  last_t_ = p.t_depth;
  last_index_ = out.index;
  return {};
}

std::optional<FrameTruth> DatasetSource::truth() const {
  if (have_last_ && folder_label_) {
    FrameTruth t = *folder_label_;
    t.index = last_index_;
    t.timestamp = last_t_;
    return t;
  }
  if (!have_last_ || labels_.empty()) return std::nullopt;
  // Labels are matched by timestamp (1 ms: lists carry 6 decimals), else by frame index.
  if (const FrameTruth* best = nearest_in_time(labels_, last_t_, 1e-3)) return *best;
  for (const auto& l : labels_)
    if (l.index == last_index_) return l;
  return std::nullopt;
}

std::optional<Pose> DatasetSource::pose() const {
  if (!have_last_ || groundtruth_.empty()) return std::nullopt;
  if (const TimedPose* best = nearest_in_time(groundtruth_, last_t_, 5e-3)) return best->T_world_camera;
  return std::nullopt;
}

// ---------------------------------------------------------------- writer

DatasetWriter::DatasetWriter(const std::string& dir, const CameraIntrinsics& intrinsics, double depth_scale)
    : dir_(dir) {
  if (!intrinsics.valid()) throw SourceError("dataset " + dir + ": invalid intrinsics");
  if (!(depth_scale > 0.0)) throw SourceError("dataset " + dir + ": depth_scale must be positive");
  camera_.intrinsics = intrinsics;
  camera_.depth_scale = depth_scale;
  const fs::path d(dir);
  std::error_code ec;
  if (fs::exists(d / "depth.txt", ec))
    throw SourceError("dataset " + dir +
                      ": already holds a dataset (depth.txt exists); refusing to overwrite it");
  fs::create_directories(d / "depth", ec);
  if (!ec) fs::create_directories(d / "rgb", ec);
  if (ec) throw SourceError("dataset " + dir + ": cannot create folder (" + ec.message() + ")");
  write_camera_yaml((d / "camera.yaml").string(), camera_, "written by stairguide");
  auto open = [&](const char* name) {
    const std::string p = (d / name).string();
    std::FILE* f = std::fopen(p.c_str(), "w");
    if (!f) throw SourceError(p + ": cannot create (" + std::strerror(errno) + ")");
    return f;
  };
  depth_list_ = open("depth.txt");
  rgb_list_ = open("rgb.txt");
  std::fprintf(
      depth_list_,
      "# depth images: 16-bit PNG, depth_scale units per metre (camera.yaml)\n# timestamp filename\n");
  std::fprintf(rgb_list_, "# colour images: 8-bit PNG, registered to depth\n# timestamp filename\n");
}

DatasetWriter::~DatasetWriter() {
  try {
    close();
  } catch (...) {
  }
}

void DatasetWriter::write(const RgbdFrame& frame, const FrameTruth* truth) {
  if (closed_) throw SourceError("dataset " + dir_ + ": write after close");
  const CameraIntrinsics& k = camera_.intrinsics;
  if (frame.depth.type() != CV_32FC1 || frame.depth.cols != k.width || frame.depth.rows != k.height)
    throw SourceError("dataset " + dir_ + ": frame " + std::to_string(frame.index) + " depth is " +
                      describe_mat_type(frame.depth) + " " + std::to_string(frame.depth.cols) + "x" +
                      std::to_string(frame.depth.rows) + ", expected 32-bit float " +
                      std::to_string(k.width) + "x" + std::to_string(k.height));
  if (!frame.color.empty() && (frame.color.type() != CV_8UC3 || frame.color.size() != frame.depth.size()))
    throw SourceError("dataset " + dir_ + ": frame " + std::to_string(frame.index) +
                      " colour must be 8-bit BGR of the depth's size");
  const fs::path d(dir_);
  char name[64];
  std::snprintf(name, sizeof name, "%06ld.png", count_);
  const std::string depth_rel = std::string("depth/") + name, rgb_rel = std::string("rgb/") + name;
  const std::vector<int> png = {cv::IMWRITE_PNG_COMPRESSION, 1};
  const cv::Mat mm = depth_to_u16(frame.depth, camera_.depth_scale);
  const std::string dp = (d / depth_rel).string();
  if (!cv::imwrite(dp, mm, png)) throw SourceError(dp + ": cannot write");
  if (!frame.color.empty()) {
    const std::string cp = (d / rgb_rel).string();
    if (!cv::imwrite(cp, frame.color, png)) throw SourceError(cp + ": cannot write");
    std::fprintf(rgb_list_, "%.6f %s\n", frame.timestamp, rgb_rel.c_str());
  }
  std::fprintf(depth_list_, "%.6f %s\n", frame.timestamp, depth_rel.c_str());
  if (truth) {
    if (!gt_) {
      const std::string p = (d / "groundtruth.txt").string();
      gt_ = std::fopen(p.c_str(), "w");
      if (!gt_) throw SourceError(p + ": cannot create (" + std::strerror(errno) + ")");
      std::fprintf(gt_,
                   "# ground-truth camera poses, camera-to-world (T_world_camera), metres\n"
                   "# timestamp tx ty tz qx qy qz qw\n");
    }
    const Eigen::Quaternionf q(truth->T_world_camera.linear());
    const Eigen::Vector3f t = truth->T_world_camera.translation();
    std::fprintf(gt_, "%.6f %.9g %.9g %.9g %.9g %.9g %.9g %.9g\n", frame.timestamp, t.x(), t.y(), t.z(),
                 q.x(), q.y(), q.z(), q.w());
    labels_.push_back(*truth);
    any_truth_ = true;
  }
  if (std::ferror(depth_list_) || std::ferror(rgb_list_) || (gt_ && std::ferror(gt_)))
    throw SourceError("dataset " + dir_ + ": write failed (disk full?)");
  ++count_;
}

void DatasetWriter::close() {
  if (closed_) return;
  closed_ = true;
  bool ok = true;
  for (std::FILE** f : {&depth_list_, &rgb_list_, &gt_}) {
    if (*f) ok = (std::fclose(*f) == 0) && ok;
    *f = nullptr;
  }
  if (!ok) throw SourceError("dataset " + dir_ + ": closing the lists failed (disk full?)");
  if (any_truth_) {
    const std::string p = (fs::path(dir_) / "labels.yaml").string();
    std::ofstream o(p);
    o << labels_to_yaml(labels_);
    o.flush();
    if (!o) throw SourceError(p + ": write failed");
  }
}

}  // namespace stairguide
