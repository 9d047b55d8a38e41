#pragma once
/// \file dataset.hpp
/// Dataset folders in the TUM RGB-D layout, their writer, the labels file, and single-frame readers
/// (organized PCD, depth PNG + camera.yaml).
///
/// Layout of a dataset folder:
///   camera.yaml      fx fy cx cy width height depth_scale (flat keys; depth_scale = PNG units per metre)
///   depth.txt        "timestamp path" lines ('#' comments), path relative to the folder
///   rgb.txt          the same for colour (PNG or JPEG, 8-bit, BGR after decoding)
///   depth/           16-bit single-channel PNG, 0 = no reading
///   rgb/             colour images, same size as depth (colour registered to depth when it can be)
///   groundtruth.txt  optional, TUM "timestamp tx ty tz qx qy qz qw", camera-to-world (T_world_camera)
///   labels.yaml      optional, per-frame FrameTruth (see ground_truth.hpp), written by `stairguide synth`;
///                    or one label for the whole folder, written by hand (read_folder_label_yaml)

#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "stairguide/capture/frame_source.hpp"

namespace stairguide {

/// Contents of a camera.yaml.
struct DatasetCamera {
  CameraIntrinsics intrinsics;
  double depth_scale = 1000.0;  ///< depth PNG units per metre (1000 = millimetres)
};

/// Reads a camera.yaml; throws SourceError naming the file and the key on any problem.
DatasetCamera read_camera_yaml(const std::string& path);
/// Writes a camera.yaml; throws SourceError when the file cannot be written.
void write_camera_yaml(const std::string& path, const DatasetCamera& camera, const std::string& comment = {});

/// labels.yaml: every field of FrameTruth and StairTruth, transforms as 16 row-major numbers.
std::string labels_to_yaml(const std::vector<FrameTruth>& frames);
/// Parses labels.yaml; throws SourceError naming the file, the line and the key on any problem.
std::vector<FrameTruth> read_labels_yaml(const std::string& path);

/// A whole-folder label, written by hand for a folder of real frames: labels.yaml of the same
/// format ("format: stairguide-labels-1") with one `folder:` mapping instead of the `frames:` list.
/// It holds a frame's keys that a person can say of every frame without a pose:
///   folder:
///     scene: "7scenes-stairs-seq04"      required, a name for the tables
///     floor_visible: false               optional (false)
///     camera_height_m: 0                 optional, 0 = unknown
///     stairs:                            required ([] for a stair-free folder)
///       - kind: ascending                required: ascending, descending, single_step, curb
///         down: false                    required for a curb; must agree with the other kinds
///         steps: 9                       optional (0 = unknown)
///         riser_m: 0.152                 optional, 0 = unknown; when given, riser errors are scored
///         tread_m: 0.245                 optional, likewise
///         width_m: 1.27                  optional
///         open_risers: false             optional
///         visible_steps: [1, 2]          optional: treads in view in every frame ([1, 2]; [1] for one step)
///         first_edge_visible: true       optional (true)
///         both_ends_visible: false       optional (false)
/// Per-frame keys (index, timestamp, T_world_camera, camera_tilt_rad, camera_roll_rad,
/// T_camera_stair, visible_pixels, user_step) are refused by name: a folder has no one value of
/// them. Returns false (and leaves `out` alone) when the file holds a `frames:` list instead, so
/// read_labels_yaml reads it; throws SourceError naming the file, the line and the key on any
/// problem. The label comes back with pose_known = false and index/timestamp 0.
bool read_folder_label_yaml(const std::string& path, FrameTruth& out);

/// One line of groundtruth.txt.
struct TimedPose {
  double timestamp = 0.0;  ///< s
  Pose T_world_camera = Pose::Identity();
};
/// Parses a TUM groundtruth file; throws SourceError naming file:line on a bad line.
std::vector<TimedPose> read_groundtruth(const std::string& path);

struct DatasetOptions {
  /// Colour is paired with the depth image nearest in time; a depth image with no colour image
  /// within this many seconds is skipped (counted in skipped_frames()). 20 ms as in TUM's
  /// associate.py: less than one frame period at 30 Hz.
  double max_pair_dt = 0.02;
};

/// A dataset folder read frame by frame. Depth is the master stream: frame i is the i-th depth
/// image that found a colour partner (every depth image when the folder has no rgb.txt).
class DatasetSource : public FrameSource {
 public:
  /// Opens and checks the folder (camera.yaml, lists, groundtruth.txt and labels.yaml when
  /// present); throws SourceError naming the file (and line) on any problem. Images are read
  /// lazily by read(), which reports a missing or corrupt image as kError naming it.
  explicit DatasetSource(const std::string& dir, const DatasetOptions& options = {});

  ReadResult read(RgbdFrame& out) override;
  CameraIntrinsics intrinsics() const override { return camera_.intrinsics; }
  long frame_count() const override { return static_cast<long>(pairs_.size()); }
  std::string describe() const override;
  std::optional<FrameTruth> truth() const override;

  double depth_scale() const { return camera_.depth_scale; }
  /// Depth images dropped because no colour image was within max_pair_dt.
  long skipped_frames() const { return skipped_; }
  /// Ground-truth pose of the frame last read, when groundtruth.txt has one within 5 ms.
  std::optional<Pose> pose() const;
  /// All poses of groundtruth.txt (empty without the file).
  const std::vector<TimedPose>& groundtruth() const { return groundtruth_; }
  bool has_labels() const { return !labels_.empty() || folder_label_.has_value(); }

 private:
  struct Pair {
    double t_depth = 0.0;
    std::string depth_path;
    std::string color_path;  ///< empty when the folder has no colour
  };
  std::string dir_;
  DatasetCamera camera_;
  std::vector<Pair> pairs_;
  std::vector<TimedPose> groundtruth_;
  std::vector<FrameTruth> labels_;          ///< sorted by timestamp
  std::optional<FrameTruth> folder_label_;  ///< a whole-folder labels.yaml (read_folder_label_yaml)
  long skipped_ = 0;
  long next_ = 0;
  double last_t_ = -1.0;
  bool have_last_ = false;
  std::uint64_t last_index_ = 0;
};

/// Writes a dataset folder frame by frame. Creates the folder (and rgb/, depth/) when missing.
/// Depth is stored as round(depth_m * depth_scale) in a 16-bit PNG (readings that do not fit in
/// 16 bits become 0 = no reading). Colour (when the frame has it) as PNG. With a FrameTruth per
/// frame it also writes groundtruth.txt and labels.yaml. Files are complete after close() (also
/// called by the destructor, which swallows errors: call close() to see them).
class DatasetWriter {
 public:
  DatasetWriter(const std::string& dir, const CameraIntrinsics& intrinsics, double depth_scale = 1000.0);
  ~DatasetWriter();
  DatasetWriter(const DatasetWriter&) = delete;
  DatasetWriter& operator=(const DatasetWriter&) = delete;

  /// Throws SourceError naming the file on a write failure or a frame of the wrong size/type.
  void write(const RgbdFrame& frame, const FrameTruth* truth = nullptr);
  void close();
  long frames_written() const { return count_; }

 private:
  std::string dir_;
  DatasetCamera camera_;
  std::FILE* depth_list_ = nullptr;
  std::FILE* rgb_list_ = nullptr;
  std::FILE* gt_ = nullptr;
  std::vector<FrameTruth> labels_;
  bool any_truth_ = false;
  long count_ = 0;
  bool closed_ = false;
};

/// Reads an organized PCD file (x y z [rgb|rgba], metres, camera optical frame, NaN = no
/// reading) into a frame: depth = z, colour from rgb when present. The intrinsics are estimated
/// from the points themselves (u = cx + fx x/z by least squares over the valid pixels); with too
/// few valid points the Kinect defaults (f 525 at 640 px, scaled) are used. Throws SourceError
/// naming the file when it is missing, unreadable, or not organized.
RgbdFrame read_pcd_frame(const std::string& path);

/// Reads one 16-bit depth PNG with the camera.yaml found beside it or in its parent folder.
RgbdFrame read_depth_png_frame(const std::string& path);

/// A source that gives one frame once (PCD files, single depth PNGs).
class SingleFrameSource : public FrameSource {
 public:
  SingleFrameSource(RgbdFrame frame, std::string description);
  ReadResult read(RgbdFrame& out) override;
  CameraIntrinsics intrinsics() const override { return frame_.intrinsics; }
  long frame_count() const override { return 1; }
  std::string describe() const override { return description_; }

 private:
  RgbdFrame frame_;
  std::string description_;
  bool done_ = false;
};

}  // namespace stairguide
