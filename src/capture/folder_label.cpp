// A whole-folder labels.yaml written by hand (dataset.hpp, read_folder_label_yaml): one label that
// holds for every frame of a folder of real frames, with no pose. Strict like the per-frame
// reader (labels_yaml.cpp): unknown keys and per-frame keys are errors naming the file and line.
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <set>
#include <string>

#include "capture_util.hpp"
#include "stairguide/capture/dataset.hpp"

namespace stairguide {
namespace {

class FolderReader {
 public:
  FolderReader(const YAML::Node& n, const std::string& file, const std::string& what)
      : n_(n), file_(file), what_(what) {
    if (!n.IsMap()) throw err(n, what + " must be a mapping");
  }
  SourceError err(const YAML::Node& n, const std::string& why) const {
    return SourceError(file_ + ":" + std::to_string(n.Mark().line + 1) + ": " + why);
  }
  /// err() with the mapping's name first ("folder stair 0: ...").
  SourceError here(const YAML::Node& n, const std::string& why) const { return err(n, what_ + ": " + why); }
  bool has(const char* key) {
    seen_.insert(key);
    return static_cast<bool>(n_[key]);
  }
  YAML::Node get(const char* key) {
    if (!has(key)) throw err(n_, what_ + ": missing key '" + key + "'");
    return n_[key];
  }
  template <class T>
  T scalar(const char* key) {
    const YAML::Node v = get(key);
    try {
      if (!v.IsScalar()) throw YAML::Exception(v.Mark(), "not a scalar");
      return v.as<T>();
    } catch (const YAML::Exception&) {
      throw err(v, what_ + ": key '" + key + "' has the wrong type ('" +
                       (v.IsScalar() ? v.Scalar() : "(not a scalar)") + "')");
    }
  }
  template <class T>
  T optional(const char* key, T fallback) {
    return has(key) ? scalar<T>(key) : fallback;
  }
  /// A length in metres, 0 (unknown) to `hi`.
  float length(const char* key, float hi) {
    if (!has(key)) return 0.f;
    const float v = scalar<float>(key);
    if (!std::isfinite(v) || v < 0.f || v > hi) {
      char range[80];
      std::snprintf(range, sizeof range, " is out of range [0, %g] m (0 = unknown)", static_cast<double>(hi));
      throw err(n_[key], what_ + ": key '" + key + "' = " + n_[key].Scalar() + range);
    }
    return v;
  }
  void finish(const std::set<std::string>& per_frame) {
    for (const auto& kv : n_) {
      const std::string k = kv.first.Scalar();
      if (seen_.count(k)) continue;
      if (per_frame.count(k))
        throw err(kv.first,
                  what_ + ": key '" + k + "' is a per-frame value, which a whole-folder label cannot give");
      throw err(kv.first, what_ + ": unknown key '" + k + "'");
    }
  }

 private:
  YAML::Node n_;
  std::string file_, what_;
  std::set<std::string> seen_;
};

}  // namespace

bool read_folder_label_yaml(const std::string& path, FrameTruth& out) {
  // The same strict reading and bounds as the per-frame labels: one document, no key twice.
  const YAML::Node root = load_labels_file(path);
  if (!root || !root.IsMap() || !root["folder"]) return false;  // a per-frame file, or not ours
  FolderReader top(root, path, "labels");
  const std::string format = top.scalar<std::string>("format");
  if (format != "stairguide-labels-1")
    throw SourceError(path + ": unknown format '" + format + "' (expected stairguide-labels-1)");
  const YAML::Node folder = top.get("folder");
  if (top.has("frames"))
    throw top.err(root["frames"], "labels: give either 'folder' (one label) or 'frames', not both");
  top.finish({});
  FolderReader r(folder, path, "folder");
  FrameTruth f;
  f.pose_known = false;
  f.scene = r.scalar<std::string>("scene");
  if (f.scene.empty()) throw r.err(folder["scene"], "folder: key 'scene' must not be empty");
  f.floor_visible = r.optional<bool>("floor_visible", false);
  f.camera_height_m = r.length("camera_height_m", 5.f);
  const YAML::Node stairs = r.get("stairs");
  r.finish({"index", "timestamp", "T_world_camera", "camera_tilt_rad", "camera_roll_rad"});
  if (!stairs.IsSequence())
    throw r.err(stairs, "folder: 'stairs' must be a list ([] for a folder without stairs)");
  for (const auto& sn : stairs) {
    FolderReader s(sn, path, "folder stair " + std::to_string(f.stairs.size()));
    StairTruth t;
    t.id = s.optional<int>("id", static_cast<int>(f.stairs.size()));
    const std::string kind = s.scalar<std::string>("kind");
    if (!parse_stair_kind(kind, t.kind) || t.kind == StairKind::kNone)
      throw s.here(sn["kind"],
                   "unknown stair kind '" + kind + "' (ascending, descending, single_step, curb)");
    if (s.has("down")) {
      t.down = s.scalar<bool>("down");
      if (const std::string why = down_contradiction(t.kind, t.down); !why.empty())
        throw s.here(sn["down"], why);
    } else if (t.kind == StairKind::kCurb) {
      throw s.here(sn, "a curb needs 'down: true' (the ground drops) or 'down: false' (it rises)");
    } else {
      t.down = t.kind == StairKind::kDescending;
    }
    t.steps = s.optional<int>("steps", 0);
    if (t.steps < 0 || t.steps > 1000) throw s.here(sn["steps"], "key 'steps' must be 0 (unknown) to 1000");
    t.riser_m = s.length("riser_m", 1.f);
    t.tread_m = s.length("tread_m", 5.f);
    t.width_m = s.length("width_m", 50.f);
    t.open_risers = s.optional<bool>("open_risers", false);
    const bool one_step = t.kind == StairKind::kSingleStep || t.kind == StairKind::kCurb;
    if (s.has("visible_steps")) {
      const YAML::Node v = sn["visible_steps"];
      if (!v.IsSequence())
        throw s.here(v, "key 'visible_steps' must be a list of tread numbers (1 = the first)");
      for (const auto& e : v) {
        int k = 0;
        try {
          k = e.as<int>();
        } catch (const YAML::Exception&) {
          throw s.here(e, "key 'visible_steps' holds a non-integer");
        }
        if (k < 1) throw s.here(e, "key 'visible_steps': treads are numbered from 1");
        t.visible_steps.push_back(k);
      }
    } else {
      t.visible_steps = one_step ? std::vector<int>{1} : std::vector<int>{1, 2};
    }
    t.visible_pixels.assign(t.visible_steps.size(), 0);
    t.first_edge_visible = s.optional<bool>("first_edge_visible", true);
    t.both_ends_visible = s.optional<bool>("both_ends_visible", false);
    s.finish({"T_camera_stair", "visible_pixels", "user_step"});
    f.stairs.push_back(std::move(t));
  }
  out = std::move(f);
  return true;
}

}  // namespace stairguide
