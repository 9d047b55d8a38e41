#pragma once
/// \file edge_compass.hpp
/// The room's horizontal directions from the image's edges, given the vertical (the paper's
/// reference for the Manhattan world, Coughlan & Yuille 1999: "compass direction from a single
/// image"). Man-made edges run along the Manhattan directions: tile joints, skirting boards,
/// door frames, the nosings and risers of a staircase, the edges of walls and cupboards. An edge
/// pixel's image direction and its viewing ray span a plane (its interpretation plane) that holds
/// the 3D edge; with the vertical known from the floor, that plane meets the horizontal in a
/// single direction, which the pixel votes for modulo 90 degrees. Vertical edges (their plane
/// holds the vertical) say nothing and are left out. No depth is used: the edges may lie on any
/// surface, near or beyond the depth cut-off.
///
/// This is a second, independent witness of the yaw: the planes' normals (manhattan_frame.hpp)
/// stay the measurement; ManhattanTracker asks the compass only to confirm a wall or riser too
/// small to be trusted on its own. A floor laid diagonally or textured at random gives a wrong or
/// no compass direction, and a table turned against the room gives its own: the compass never
/// makes a frame alone. `gray` needs no depth registration to within a few pixels (a colour
/// camera apart from the depth camera, as in 7-Scenes, agrees with the walls to 1-2 degrees).
///
/// Given the depth as well, it also gives the long straight edges that lie on the floor
/// (EdgeCompassResult::lines): the foot of a wall, even beyond the depth cut-off, the joints of a
/// floor's boards or tiles, the edge of a rug. Where the floor's texture drowns the edges'
/// dominant direction, such a line still gives the room's (ManhattanTracker::confirm_by_lines).

#include <vector>

#include <opencv2/core.hpp>

#include "stairguide/core/types.hpp"

namespace stairguide {

struct EdgeCompassConfig {
  int stride = 2;  ///< px of the half-resolution image: every stride-th pixel in each direction votes
  int window = 5;  ///< px of the half-resolution image: the structure tensor's window
  float min_gradient = 6.f;      ///< grey levels per pixel (RMS over the window), weaker edges are noise
  float min_coherence = 0.7f;    ///< of the structure tensor: 1 on a straight edge, 0 on isotropic texture
  float min_horizontal = 0.26f;  ///< sin of the angle between the interpretation plane and the vertical (15
                                 ///< deg): closer, the edge may be vertical
  float peak_halfwidth =
      0.0349f;  ///< rad, votes within this of the peak refine it and count as its support (2 deg)
  float line_min_length = 150.f;  ///< px of the full image: collinear segments adding up to this make a long
                                  ///< edge (EdgeCompassResult::lines); 0: none
};

/// A long straight edge: collinear line segments of the image chained along one line.
struct EdgeLine {
  float heading = 0.f;  ///< rad, modulo 90 degrees in (-45, 45]: its horizontal direction in the floor frame
  float length = 0.f;   ///< px of the full image: the segments' summed length along it
  float span = 0.f;     ///< px of the full image: from its first segment's end to its last's
  Eigen::Vector2f a = Eigen::Vector2f::Zero(),
                  b = Eigen::Vector2f::Zero();  ///< px of the full image: its two ends
};

struct EdgeCompassResult {
  bool valid = false;
  float yaw = 0.f;  ///< rad, modulo 90 degrees in (-45, 45]: the dominant horizontal direction in the floor
                    ///< frame (heading from z_F towards x_F)
  float support = 0.f;  ///< share of the voting weight within peak_halfwidth of `yaw` (a uniform spread gives
                        ///< 2 * halfwidth / 90 deg)
  float weight = 0.f;   ///< total voting weight (edge strength x straightness x horizontal share, summed)
  int edgels = 0;       ///< pixels that voted
  std::vector<EdgeLine> lines;  ///< long straight edges (EdgeCompassConfig::line_min_length), longest first
};

/// The compass. `gray`: CV_8UC1 registered to depth (the intrinsics `K` apply); `R_floor_camera`:
/// rotation of the camera into the floor frame (y_F up). Buffers are kept between calls.
class EdgeCompass {
 public:
  explicit EdgeCompass(const EdgeCompassConfig& config = {}) : cfg_(config) {}
  EdgeCompassResult estimate(const cv::Mat& gray, const CameraIntrinsics& K,
                             const Eigen::Matrix3f& R_floor_camera);
  /// As above, and the long straight edges that lie on the floor (EdgeCompassResult::lines), told
  /// by `depth` (CV_32FC1, metres, 0: no reading, registered to `gray`), the floor's pose and the
  /// depth cut-off `max_range` (m).
  EdgeCompassResult estimate(const cv::Mat& gray, const CameraIntrinsics& K, const Pose& T_floor_camera,
                             const cv::Mat& depth, float max_range);

 private:
  struct Vote {
    float a, w;  // heading modulo 90 degrees (rad), weight
  };
  EdgeCompassConfig cfg_;
  std::vector<float> hist_;      // scratch
  std::vector<Vote> votes_;      // scratch
  cv::Mat half_, gx_, gy_;       // scratch: half-resolution image and gradients
  std::vector<float> rows_;      // scratch: per row, horizontal window sums of the structure tensor
  std::vector<float> acc_;       // scratch: their vertical running sum
  std::vector<cv::Vec4f> segs_;  // scratch: line segments of the half-resolution image
  void find_lines(const CameraIntrinsics& K, const Pose& T_floor_camera, const cv::Mat& depth,
                  float max_range, EdgeCompassResult& out);
  bool on_floor(const Eigen::Vector2f& p1, const Eigen::Vector2f& p2, const CameraIntrinsics& K,
                const Pose& T_floor_camera, const cv::Mat& depth, float max_range) const;
};

}  // namespace stairguide
