#pragma once
/// \file types.hpp
/// Plain data types shared by every stage: camera intrinsics, the RGB-D frame, poses.
/// No I/O here. Frames: camera C (x right, y down, z forward), floor F (x left, y up, z forward),
/// Manhattan M, stair S, as in Perez-Yus et al. 2017. Transforms are named `T_target_source`.

#include <Eigen/Geometry>
#include <cstdint>
#include <opencv2/core.hpp>
#include <string>

namespace stairguide {

/// Pinhole intrinsics of the depth image (colour is registered to depth).
struct CameraIntrinsics {
  int width = 640;    ///< px
  int height = 480;   ///< px
  float fx = 525.f;   ///< px
  float fy = 525.f;   ///< px
  float cx = 319.5f;  ///< px
  float cy = 239.5f;  ///< px

  /// Intrinsics for an image scaled by `s` (e.g. 0.5 for the next pyramid level).
  CameraIntrinsics scaled(float s) const;
  bool valid() const { return width > 0 && height > 0 && fx > 0.f && fy > 0.f; }
};

/// One RGB-D frame as every stage sees it.
///
/// `depth` is CV_32FC1 in metres, 0 where the sensor gave no reading (never NaN).
/// `color` is CV_8UC3 BGR registered to depth, or empty when the source has no colour.
/// `gray` is CV_8UC1 (from colour, or from the source's grey/IR), or empty.
struct RgbdFrame {
  std::uint64_t index = 0;  ///< 0-based frame number in its source
  double timestamp = 0.0;   ///< s, sensor time
  CameraIntrinsics intrinsics;
  cv::Mat depth;
  cv::Mat color;
  cv::Mat gray;

  bool has_depth() const { return !depth.empty(); }
  /// Deep copy (cv::Mat copies share pixels by default).
  RgbdFrame clone() const;
};

using Pose = Eigen::Isometry3f;

/// Degrees <-> radians.
constexpr float deg2rad(float d) { return d * 0.017453292519943295f; }
constexpr float rad2deg(float r) { return r * 57.29577951308232f; }

}  // namespace stairguide
