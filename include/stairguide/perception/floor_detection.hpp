#pragma once
/// \file floor_detection.hpp
/// Camera-to-floor transform (paper 3.2.1). The floor is chosen among the planar regions:
///  - its normal must fit a chest camera: tilt (optical axis below horizontal) within
///    [tilt_min, tilt_max] and |roll| <= roll_max;
///  - the camera must be height_min..height_max above it;
///  - it must be near the user: the search window on z_C starts at search_start and grows by
///    search_step up to search_max; the first window in which some candidate has min_area of
///    footprint wins, and among the candidates the one with the largest footprint in it.
/// Tracking: once a floor is known, a candidate within track_max_height_jump and
/// track_max_angle_jump of it is preferred, so that the first step (nearer than the floor when the
/// user stands in front of it) never replaces the floor. Candidates parallel to the floor and
/// higher (nearer the camera) are never taken while the tracked floor is still in view.
/// Hold: for track_hold_frames frames after the tracked floor was last seen, only planes within
/// the tracking tolerances of it can be the floor (a step is never taken for it meanwhile).
/// Verification (safety): the chosen plane is rejected when more than verify_min_pixels of the
/// frame lie verify_drop or more below it, nearer the user's feet than the plane's own near edge
/// (+ verify_margin): then it is a tread, a platform or a seat seen from in front (its front face
/// or the real floor lies below its near edge), not what the user stands on. Every candidate on
/// a rejected plane is dropped and the choice made again; when nothing is left the frame has no
/// floor ("no floor" is recoverable, a wrong floor hides a staircase). A plane whose near edge is
/// the bottom of the view, with another plane one riser above it a tread's depth further, may be
/// the first tread of a staircase filling the view: it is not taken either.
/// A cold candidate with another level a curb's height above it (curb_rise_min..max) that is
/// cut by the view's bottom edge and whose straight boundary with the candidate leaves the
/// user's nadir on its side is not taken either: the user may stand on that level.
/// Of parallel candidates, a lower one reaching as near the user's feet (angle from the nadir)
/// wins over a higher one (a seat or a platform beside the floor).

#include <optional>
#include <string>
#include <vector>

#include "stairguide/core/config.hpp"
#include "stairguide/core/types.hpp"
#include "stairguide/perception/scene.hpp"

namespace stairguide {

/// The floor found in one frame.
struct FloorEstimate {
  bool found = false;
  std::string why;                    ///< when !found
  int region = -1;                    ///< index of the floor region
  /// When !found: the plane the rules chose (a chest camera's orientation and height, the largest
  /// footprint near the user) and the checks then refused first for where it lies. It may be a
  /// tread or a seat, but its normal is still the vertical (perception measures the Manhattan
  /// frame about it); -1 when none was chosen (small planes' normals are not trusted for that: on
  /// the real kitchen, worktop and floor patches too small to be chosen gave frames up to 9 deg
  /// off). When found, the floor's region.
  int level_region = -1;
  bool tracked = false;               ///< chosen by agreement with the previous frame's floor
  Eigen::Vector3f normal = -Eigen::Vector3f::UnitY();  ///< floor up direction, camera frame
  float offset = 0.f;                 ///< n.p + offset = 0 for floor points; = camera height
  float height = 0.f;                 ///< m
  float tilt = 0.f;                   ///< rad
  float roll = 0.f;                   ///< rad
  Pose T_floor_camera = Pose::Identity();
};

/// Floor frame from a floor plane seen by the camera: y_F along `up` (unit, camera frame), z_F
/// the optical axis projected on the floor, x_F = y_F x z_F (left), origin under the camera.
Pose floor_pose_from_plane(const Eigen::Vector3f& up, float camera_height);
/// Tilt (optical axis below horizontal) and roll of a camera seeing floor `up` (camera frame), with
/// the synthetic world's convention: roll = atan2(-up_x, -up_y).
void tilt_roll_from_up(const Eigen::Vector3f& up, float& tilt, float& roll);

class FloorDetector {
 public:
  explicit FloorDetector(const FloorConfig& config = {});

  /// Chooses the floor among `regions` (from Segmentation on `frame`).
  FloorEstimate detect(const std::vector<PlaneRegion>& regions, const RgbdFrame& frame);
  /// Forgets the tracked floor (a new sequence).
  void reset() {
    prev_.reset();
    anchor_.reset();
    lost_frames_ = 0;
  }
  const FloorConfig& config() const { return cfg_; }
  /// Camera height above the floor last verified on a clear view, while remembered; 0 when unknown.
  float remembered_height() const { return anchor_ ? *anchor_ : 0.f; }
  /// Frames since the floor was last found; -1 when no floor is remembered.
  int frames_since_floor() const { return prev_ ? lost_frames_ : -1; }

 private:
  int choose(const std::vector<PlaneRegion>& regions, const std::vector<int>& cand, float area_k, bool& tracked);
  struct Reach {
    float distance = 1e9f;  // m from the camera's foot to the plane's near edge
    float angle = 1.6f;     // rad from the nadir to the plane's near edge
  };
  Reach reach(const PlaneRegion& r);
  FloorEstimate& lost(FloorEstimate& est);
  int lost_frames_ = 0;
  void sample_frame(const RgbdFrame& frame);
  bool nothing_below(const PlaneRegion& r, const Reach& near) const;
  bool drop_under_edge(const PlaneRegion& r, const RgbdFrame& frame) const;
  bool stair_from_view_edge(const std::vector<PlaneRegion>& regions, int c, const Reach& near, int width);
  std::vector<int> col_top_;
  struct Span {
    float lo = 0.f, hi = 0.f;  // m, robust extent of points along an axis
  };
  Span span(const std::vector<Eigen::Vector3f>& pts, const Eigen::Vector3f& axis);
  // C (at the view's edge) cannot be a tread of the flight whose next tread is A, one riser above
  // it: C's level goes on beyond A's riser line beside the flight, or C is deeper than the treads.
  bool not_a_tread_of(const std::vector<PlaneRegion>& regions, const PlaneRegion& C, const PlaneRegion& A);
  // C's level lies within the width of the flight whose tread A is (one riser from C) and C is
  // no deeper than A: C may be a tread of that flight, whatever the image columns say.
  bool tread_shaped(const std::vector<PlaneRegion>& regions, const PlaneRegion& C, const PlaneRegion& A);
  // A bigger level one riser above candidate c and another one riser below it ahead, within its
  // width: c is a tread of a descent (its top seen cold), not the floor.
  bool middle_of_stack(const std::vector<PlaneRegion>& regions, int c, const Reach& near);
  // Cold view: a level a curb's height above candidate c, cut by the view's bottom edge, whose
  // straight boundary with c (measured in c's floor frame), extended, leaves the user's nadir on
  // its side: the user may stand on that level, seen only at the view's edge.
  bool level_above_underfoot(const std::vector<PlaneRegion>& regions, int c, int width, int height);
  // The point of `edge` (floor frame x, z; `rise` above the frame's plane) nearest position t
  // along `along` lies at the view's border or beyond it.
  bool edge_end_at_border(const std::vector<Eigen::Vector2f>& edge, const Eigen::Vector2f& along, float t,
                          const Pose& T_floor_camera, float rise, int width, int height) const;
  std::vector<unsigned char> grid_;
  std::vector<unsigned char> curb_grid_;                 // level_above_underfoot scratch: the grid grown along x
  std::vector<Eigen::Vector2f> curb_u_, curb_edge_;      // ... the upper level's points and its edge with F (floor frame x, z)
  std::vector<float> lateral_;
  bool stack_below_ = false;  // middle_of_stack said so: every lower plane is a tread too
  CameraIntrinsics K_;

  FloorConfig cfg_;
  std::vector<Eigen::Vector3f> samples_;  // sparse grid of the frame's points, camera frame
  float sample_weight_ = 1.f;             // pixels per sample
  std::vector<float> near_buf_;
  struct Prev {
    Eigen::Vector3f normal;
    float offset;
  };
  std::optional<Prev> prev_;
  // Camera height above the floor, last measured on a floor that passed every check (nothing lower
  // nearer the user, not a possible tread). Forgotten with prev_.
  std::optional<float> anchor_;
  std::vector<float> window_area_;
};

}  // namespace stairguide
