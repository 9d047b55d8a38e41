// labels.yaml: per-frame ground truth of a dataset folder. Written by hand (so that floats are
// printed with enough digits to read back bit-exact), read with yaml-cpp with strict checks:
// every key present, no unknown key, so that a mislabelled file never passes silently.
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <set>
#include <sstream>
#include <type_traits>

#include "capture_util.hpp"
#include "stairguide/capture/dataset.hpp"
#include "stairguide/config/strict_yaml.hpp"

namespace stairguide {
namespace {

std::string f9(float v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.9g", static_cast<double>(v));
  return b;
}
std::string d17(double v) {
  char b[40];
  std::snprintf(b, sizeof b, "%.17g", v);
  return b;
}
std::string quoted(const std::string& s) {
  std::string o = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') o += '\\';
    o += c;
  }
  return o + "\"";
}
std::string matrix16(const Pose& p) {
  const Eigen::Matrix4f m = p.matrix();
  std::string o = "[";
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) o += (r || c ? ", " : "") + f9(m(r, c));
  return o + "]";
}
template <class T>
std::string list(const std::vector<T>& v) {
  std::string o = "[";
  for (std::size_t i = 0; i < v.size(); ++i) o += (i ? ", " : "") + std::to_string(v[i]);
  return o + "]";
}
const char* b(bool v) { return v ? "true" : "false"; }

// Strict reader of one mapping: every key must be read once, unknown keys are errors.
class MapReader {
 public:
  MapReader(const YAML::Node& n, const std::string& file, const std::string& what)
      : n_(n), file_(file), what_(what) {
    if (!n.IsMap()) throw err(n, what + " must be a mapping");
  }
  SourceError err(const YAML::Node& n, const std::string& why) const {
    return SourceError(file_ + ":" + std::to_string(n.Mark().line + 1) + ": " + why);
  }
  YAML::Node get(const char* key) {
    seen_.insert(key);
    YAML::Node v = n_[key];
    if (!v) throw err(n_, what_ + ": missing key '" + key + "'");
    return v;
  }
  template <class T>
  T scalar(const char* key) {
    YAML::Node v = get(key);
    T out{};
    try {
      if (!v.IsScalar()) throw YAML::Exception(v.Mark(), "not a scalar");
      out = v.as<T>();
    } catch (const YAML::Exception&) {
      throw err(v, what_ + ": key '" + key + "' has the wrong type ('" +
                       (v.IsScalar() ? v.Scalar() : "(not a scalar)") + "')");
    }
    if constexpr (std::is_floating_point_v<T>) {
      // .nan and .inf read as numbers; no label is either, and 1e30 m is no label either.
      if (!std::isfinite(out) || std::abs(out) > static_cast<T>(1e10))
        throw err(v, what_ + ": key '" + key + "' must be a finite number, got '" + v.Scalar() + "'");
    }
    return out;
  }
  Pose pose(const char* key) {
    YAML::Node v = get(key);
    if (!v.IsSequence() || v.size() != 16)
      throw err(v, what_ + ": key '" + key + "' needs 16 numbers (row-major 4x4)");
    Eigen::Matrix4f m;
    for (int i = 0; i < 16; ++i) {
      try {
        m(i / 4, i % 4) = v[static_cast<std::size_t>(i)].as<float>();
      } catch (const YAML::Exception&) {
        throw err(v, what_ + ": key '" + key + "' element " + std::to_string(i) + " is not a number");
      }
    }
    if (!m.allFinite())
      throw err(v, what_ + ": key '" + key + "' holds a number that is not finite (nan or inf)");
    if (std::abs(m(3, 0)) > 1e-6f || std::abs(m(3, 1)) > 1e-6f || std::abs(m(3, 2)) > 1e-6f ||
        std::abs(m(3, 3) - 1.f) > 1e-6f)
      throw err(v, what_ + ": key '" + key + "' last row must be 0 0 0 1");
    // A rigid transform: a rotation (orthonormal, det +1; written with 9 digits, off by 1e-6 at
    // most) and a translation no recording could span.
    const Eigen::Matrix3f r = m.topLeftCorner<3, 3>();
    if ((r.transpose() * r - Eigen::Matrix3f::Identity()).cwiseAbs().maxCoeff() > 1e-3f ||
        r.determinant() < 0.f)
      throw err(v, what_ + ": key '" + key + "' is not a rigid transform (its 3x3 part is not a rotation)");
    if (m.topRightCorner<3, 1>().cwiseAbs().maxCoeff() > 1e5f)
      throw err(v, what_ + ": key '" + key + "' translation is beyond 100 km");
    Pose p;
    p.matrix() = m;
    return p;
  }
  std::vector<int> ints(const char* key) {
    YAML::Node v = get(key);
    if (!v.IsSequence()) throw err(v, what_ + ": key '" + key + "' must be a list of whole numbers");
    std::vector<int> out;
    for (const auto& e : v) {
      try {
        out.push_back(e.as<int>());
      } catch (const YAML::Exception&) {
        throw err(e, what_ + ": key '" + key + "' holds a non-integer");
      }
    }
    return out;
  }
  void finish() {
    for (const auto& kv : n_) {
      const std::string k = kv.first.Scalar();
      if (!seen_.count(k)) throw err(kv.first, what_ + ": unknown key '" + k + "'");
    }
  }

 private:
  YAML::Node n_;
  std::string file_, what_;
  std::set<std::string> seen_;
};

}  // namespace

std::string labels_to_yaml(const std::vector<FrameTruth>& frames) {
  std::ostringstream o;
  o << "# stairguide per-frame ground truth (include/stairguide/core/ground_truth.hpp).\n"
       "# Transforms are 4x4 row-major; T_world_camera maps camera to world (z up), T_camera_stair maps\n"
       "# the stair frame (paper Fig. 8) to the camera frame. Lengths in metres, angles in radians.\n";
  o << "format: stairguide-labels-1\n";
  if (frames.empty()) {
    o << "frames: []\n";
    return o.str();
  }
  o << "frames:\n";
  for (const auto& f : frames) {
    o << "  - index: " << f.index << "\n";
    o << "    timestamp: " << d17(f.timestamp) << "\n";
    o << "    scene: " << quoted(f.scene) << "\n";
    o << "    T_world_camera: " << matrix16(f.T_world_camera) << "\n";
    o << "    camera_height_m: " << f9(f.camera_height_m) << "\n";
    o << "    camera_tilt_rad: " << f9(f.camera_tilt_rad) << "\n";
    o << "    camera_roll_rad: " << f9(f.camera_roll_rad) << "\n";
    o << "    floor_visible: " << b(f.floor_visible) << "\n";
    if (f.stairs.empty()) {
      o << "    stairs: []\n";
      continue;
    }
    o << "    stairs:\n";
    for (const auto& s : f.stairs) {
      o << "      - id: " << s.id << "\n";
      o << "        kind: " << to_string(s.kind) << "\n";
      o << "        steps: " << s.steps << "\n";
      o << "        riser_m: " << f9(s.riser_m) << "\n";
      o << "        tread_m: " << f9(s.tread_m) << "\n";
      o << "        width_m: " << f9(s.width_m) << "\n";
      o << "        open_risers: " << b(s.open_risers) << "\n";
      o << "        down: " << b(s.goes_down()) << "\n";
      o << "        T_camera_stair: " << matrix16(s.T_camera_stair) << "\n";
      o << "        visible_steps: " << list(s.visible_steps) << "\n";
      o << "        visible_pixels: " << list(s.visible_pixels) << "\n";
      o << "        first_edge_visible: " << b(s.first_edge_visible) << "\n";
      o << "        both_ends_visible: " << b(s.both_ends_visible) << "\n";
      o << "        user_step: " << s.user_step << "\n";
    }
  }
  return o.str();
}

YAML::Node load_labels_file(const std::string& path) {
  std::error_code ec;
  if (const std::string why = why_unreadable(path); !why.empty())
    throw SourceError(path + ": " + unreadable_words(why, "it"));
  if (!std::filesystem::is_regular_file(path, ec)) throw SourceError(path + ": not a regular file");
  try {
    // A labelled frame is about 1.2 kB and 130 nodes: these bounds are some 15000 frames with a
    // staircase each, and keep yaml-cpp's tree (a few hundred bytes a node) under a gigabyte.
    return load_strict_yaml(read_small_file(path, 64u << 20, "labels.yaml"), path, YamlLimits{2000000, 8});
  } catch (const InputFileError& e) {
    throw SourceError(e.what());
  }
}

std::vector<FrameTruth> read_labels_yaml(const std::string& path) {
  const YAML::Node root = load_labels_file(path);
  if (!root || root.IsNull()) throw SourceError(path + ": empty file");
  MapReader top(root, path, "labels");
  const std::string format = top.scalar<std::string>("format");
  if (format != "stairguide-labels-1")
    throw SourceError(path + ": unknown format '" + format + "' (expected stairguide-labels-1)");
  YAML::Node frames = top.get("frames");
  top.finish();
  if (!frames.IsSequence()) throw top.err(frames, "'frames' must be a list");
  std::vector<FrameTruth> out;
  out.reserve(frames.size());
  for (const auto& fn : frames) {
    MapReader r(fn, path, "frame " + std::to_string(out.size()));
    FrameTruth f;
    f.index = r.scalar<std::uint64_t>("index");
    f.timestamp = r.scalar<double>("timestamp");
    f.scene = r.scalar<std::string>("scene");
    f.T_world_camera = r.pose("T_world_camera");
    f.camera_height_m = r.scalar<float>("camera_height_m");
    f.camera_tilt_rad = r.scalar<float>("camera_tilt_rad");
    f.camera_roll_rad = r.scalar<float>("camera_roll_rad");
    f.floor_visible = r.scalar<bool>("floor_visible");
    YAML::Node stairs = r.get("stairs");
    r.finish();
    if (!stairs.IsSequence())
      throw r.err(stairs, "frame " + std::to_string(out.size()) + ": 'stairs' must be a list");
    for (const auto& sn : stairs) {
      MapReader s(sn, path,
                  "frame " + std::to_string(out.size()) + " stair " + std::to_string(f.stairs.size()));
      StairTruth t;
      t.id = s.scalar<int>("id");
      const std::string kind = s.scalar<std::string>("kind");
      if (!parse_stair_kind(kind, t.kind))
        throw s.err(sn["kind"],
                    "unknown stair kind '" + kind + "' (none, ascending, descending, single_step, curb)");
      t.steps = s.scalar<int>("steps");
      t.riser_m = s.scalar<float>("riser_m");
      t.tread_m = s.scalar<float>("tread_m");
      t.width_m = s.scalar<float>("width_m");
      t.open_risers = s.scalar<bool>("open_risers");
      // `down` came after the first labels: a staircase's kind implies it (and must agree), a curb's
      // does not, so a curb without it is refused rather than guessed.
      if (sn["down"]) {
        t.down = s.scalar<bool>("down");
        if (const std::string why = down_contradiction(t.kind, t.down); !why.empty())
          throw s.err(sn["down"], why);
      } else if (t.kind == StairKind::kCurb) {
        throw s.err(sn, "a curb needs 'down: true' (the ground drops) or 'down: false' (it rises)");
      } else {
        t.down = t.kind == StairKind::kDescending;
      }
      t.T_camera_stair = s.pose("T_camera_stair");
      t.visible_steps = s.ints("visible_steps");
      t.visible_pixels = s.ints("visible_pixels");
      if (t.visible_steps.size() != t.visible_pixels.size())
        throw s.err(sn, "visible_steps and visible_pixels must have the same length");
      t.first_edge_visible = s.scalar<bool>("first_edge_visible");
      t.both_ends_visible = s.scalar<bool>("both_ends_visible");
      t.user_step = s.scalar<int>("user_step");
      s.finish();
      f.stairs.push_back(std::move(t));
    }
    out.push_back(std::move(f));
  }
  return out;
}

}  // namespace stairguide
