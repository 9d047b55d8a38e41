#pragma once
/// \file floor_detection.hpp
/// Camera-to-floor transform (paper 3.2.1). The floor is chosen among the planar regions:
///  - its normal must fit a chest or waist rig: tilt (optical axis below horizontal) within
///    [tilt_min, tilt_max] and |roll| <= roll_max;
///  - the camera must be height_min..height_max above it (the rig range, issue 34);
/// The rig model (issue 34): the user's camera height is a property of the wearer and the rig, not
/// of the place. A cold start looks in the usual chest band (usual_height_*, usual_tilt_*: the
/// paper's 1.0-1.6 m, 20-70 deg) first, where one clear view is a floor; outside it (a waist rig,
/// a steep or level one) only once rig_learn_frames clear views agree within
/// rig_height_tolerance (one view of a worktop or a bed filling the view looks like a waist rig's
/// floor). Once established the height is held: outside the usual band a floor is taken only
/// within rig_height_tolerance of it, so a table, bed, seat or landing below the camera is never
/// the floor; a height held within the band leaves the band's choice as it was (the traversal's
/// drift correction depends on it) and keeps what lies outside the band from being the floor. When a fresh
/// start would take a clear floor at one other height for rig_relearn_frames frames with none at the held
/// height in between (the wearer sat down, the rig was remounted), that height is relearned; a floor lower
/// than held only when no level lies in view between it and the camera (on a stair the treads nearer the
/// camera are in view).
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
/// A strip smaller than min_area in every window (0.5-0.7 m from a platform's edge, a hole, or a
/// flight filling the view) is offered as the floor when no bigger plane is, if it is cut by the
/// view's bottom edge at the rig's height and tilt (learned, or the usual chest rig's while none
/// is) with its normal within 2 deg of a bigger level's in view; every check above then applies to
/// it as to any candidate. Once the rig is learned, such a piece of the tracked floor is tracked.

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
  std::string why;  ///< when !found
  int region = -1;  ///< index of the floor region
  /// When !found: the plane the rules chose (a chest camera's orientation and height, the largest
  /// footprint near the user) and the checks then refused first for where it lies. It may be a
  /// tread or a seat, but its normal is still the vertical (perception measures the Manhattan
  /// frame about it); -1 when none was chosen (small planes' normals are not trusted for that: on
  /// the real kitchen, worktop and floor patches too small to be chosen gave frames up to 9 deg
  /// off). When found, the floor's region.
  int level_region = -1;
  bool tracked = false;  ///< chosen by agreement with the previous frame's floor
  Eigen::Vector3f normal = -Eigen::Vector3f::UnitY();  ///< floor up direction, camera frame
  float offset = 0.f;                                  ///< n.p + offset = 0 for floor points; = camera height
  float height = 0.f;                                  ///< m
  float tilt = 0.f;                                    ///< rad
  float roll = 0.f;                                    ///< rad
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
    rig_height_.reset();
    rig_tilt_.reset();
    learn_.clear();
    relearn_.clear();
    relearn_misses_ = 0;
  }
  const FloorConfig& config() const { return cfg_; }
  /// Camera height above the floor last verified on a clear view, while remembered; else the
  /// user's camera height the rig model holds; 0 when unknown.
  float remembered_height() const { return anchor_ ? *anchor_ : 0.f; }
  /// The user's camera height above what they stand on, learned from the first clear views and
  /// held (relearned when clearly wrong for long); 0 while not yet established.
  float rig_height() const { return rig_height_ ? *rig_height_ : 0.f; }
  /// The rig's tilt (rad), learned with its height; 0 while not yet established.
  float rig_tilt() const { return rig_tilt_ ? *rig_tilt_ : 0.f; }
  /// The learned rig alone (no tracked floor), to carry over a rebuild of the detector (a config
  /// reload must not make a waist rig's wearer wait rig_learn_frames views for the floor again).
  struct Rig {
    std::optional<float> height, tilt;
    int learned = 0;
  };
  Rig rig() const { return Rig{rig_height_, rig_tilt_, rig_learned_}; }
  void restore_rig(const Rig& r) {
    rig_height_ = r.height;
    rig_tilt_ = r.tilt;
    rig_learned_ = r.learned;
  }
  /// How many times the rig has been established or relearned since construction (a reset too
  /// counts nothing): tells a listener that rig_height()/rig_tilt() were learned anew.
  int rig_learned() const { return rig_learned_; }
  /// Frames since the floor was last found; -1 when no floor is remembered.
  int frames_since_floor() const { return prev_ ? lost_frames_ : -1; }

 private:
  int choose(const std::vector<PlaneRegion>& regions, const std::vector<int>& cand, float area_k,
             bool& tracked);
  // Cold or not, a candidate smaller than min_area in every window cut by the view's bottom edge at
  // the rig's height and tilt (the usual chest rig while none is learned): the strip of floor at the
  // user's feet before an edge or a flight filling the view; -1 when none.
  int strip_at_feet(const std::vector<PlaneRegion>& regions, const std::vector<int>& cand) const;
  // Candidate c's normal agrees closely with that of a level of min_area or more in view (a small
  // strip's own normal is poorly fixed; a big level's says where "up" is).
  bool level_confirmed(const std::vector<PlaneRegion>& regions, int c) const;
  // The plane's height and tilt are those of the rig (learned; while not, the usual chest rig).
  bool agrees_with_rig(const PlaneRegion& r) const;
  // A level `below` m under the camera could be what the user stands on (the rig's height, learned
  // or the usual chest rig's).
  bool could_be_floor(float below) const;
  struct Reach {
    float distance = 1e9f;  // m from the camera's foot to the plane's near edge
    float angle = 1.6f;     // rad from the nadir to the plane's near edge
  };
  Reach reach(const PlaneRegion& r);
  void lost();  // a frame with no floor: the tracked floor is forgotten after track_forget_frames
  // One choice of the floor among the planes height_lo..height_hi below the camera; no state
  // changes but clear_height_ (the height of a floor found on a clear view). probe_: as on a
  // fresh start, nothing tracked.
  FloorEstimate select(const std::vector<PlaneRegion>& regions, const RgbdFrame& frame, float height_lo,
                       float height_hi, float tilt_lo, float tilt_hi);
  bool refused_as_tread_ = false;  // select() refused a plane as a possible tread (or the user above it)
  void learn(float height, float tilt);
  struct TiltBand {
    float lo, hi;  // rad
  };
  // The tilts a floor may be seen at: the whole rig range until the rig's tilt is learned, then
  // the usual band widened to the rig's tilt +- rig_tilt_tolerance.
  TiltBand rig_tilt_band() const;
  bool probe_ = false;
  std::optional<float> clear_height_;
  // The rig model: the user's camera height (held), the clear views that establish it, and the
  // clear views at another height that relearn it (with the frames since the last of them).
  std::optional<float> rig_height_;
  int rig_learned_ = 0;
  std::optional<float> rig_tilt_;  // rad, the median tilt of the views that established the height
  struct RigView {
    float height, tilt;
  };
  std::vector<RigView> learn_, relearn_;
  int relearn_misses_ = 0;
  int lost_frames_ = 0;
  void sample_frame(const RgbdFrame& frame);
  // `descent`: the relative heights (m, negative: below r) of the levels of a descent found to start
  // at r's level (a refused first tread and what lies below it); points on them are not "below".
  bool nothing_below(const PlaneRegion& r, const Reach& near, const std::vector<float>& descent) const;
  bool drop_under_edge(const PlaneRegion& r, const RgbdFrame& frame) const;
  // Lower than any floor of the rig range: a drop (a hole, a dock, a stairwell), never the front of
  // a seat or a step standing on the user's floor, nor that floor.
  bool below_any_floor(const Eigen::Vector3f& up, const Eigen::Vector3f& q) const {
    return -up.dot(q) > cfg_.height_max + cfg_.verify_drop;
  }
  // Candidate c's level is seen under the camera: the nadir is in view and, behind it (towards
  // the user's heels), c's level is what the camera sees, no other level.
  bool under_the_camera(const std::vector<PlaneRegion>& regions, int c) const;
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
  std::vector<unsigned char> curb_grid_;  // level_above_underfoot scratch: the grid grown along x
  std::vector<Eigen::Vector2f> curb_u_,
      curb_edge_;  // ... the upper level's points and its edge with F (floor frame x, z)
  std::vector<float> lateral_;
  bool stack_below_ = false;  // middle_of_stack said so: every lower plane is a tread too
  // The descent middle_of_stack found last (its first tread's plane offset), while choosing.
  struct DescentTread {
    float offset;  // m, its plane's offset
    float angle;   // rad, its near edge from the nadir
  };
  std::optional<DescentTread> descent_tread_;
  std::vector<float> descent_levels_;  // scratch: nothing_below's `descent`
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
