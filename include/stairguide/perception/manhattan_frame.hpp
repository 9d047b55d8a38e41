#pragma once
/// \file manhattan_frame.hpp
/// Floor-to-Manhattan transform (paper 3.2.2). j_M is the floor's up direction; i_M and k_M are
/// the two orthogonal horizontal directions that the vertical planes' normals agree with most
/// (vote modulo 90 degrees weighted by area * (width / yaw_full_width)^2, the precision of a plane's
/// yaw, refined by a circular mean of the votes near the peak). No frame unless an agreeing plane
/// is min_plane_width wide, or two agreeing parallel planes each pair_min_width wide (not at the
/// depth cut-off) and within pair_tolerance of each other are strips of one plane on one line
/// spanning that width, or distinct planes pair_min_separation apart (one of them half
/// min_plane_width wide) with the agreeing votes spread within max_spread: only people and posts
/// in view make none.
/// Planes with floor beyond them (furniture, risers, people: they stand inside the room) vote only
/// when the others (walls, which bound the floor) make no frame; a wall standing on the floor is
/// trusted from min_bounding_width. Such a plane hanging above the floor (hanging_min_height: a
/// seat's apron, a chair's back, a table's edge) makes no frame alone, nor in a pair with another
/// hanging one. Planes clipped by the depth cut-off cannot make that frame;
/// their yaw is their plane's held upright, fitted on their readings clear of the cut-off's noise
/// band when at least half of them are (fit_upright_normal_clear_of_cutoff).
/// A wall (no surface at all beyond it, standing on the floor or reaching the cut-off, at least
/// veto_min_width wide) seen beyond a plane that makes the frame (structure_beyond_area of it, or
/// half of a smaller one) and disagreeing with the frame modulo 90 degrees vetoes it: no frame
/// (`why` says so) rather than the frame of furniture turned against the room; a sliver at the
/// cut-off disagrees only beyond clipped_disagreement. When the widest vetoing wall is
/// min_plane_width wide, the walls agreeing with it give the frame instead; when it is narrower,
/// the image edges' direction agreeing with it (compass_veto_*) and not with the vetoed frame gives
/// the frame. A thin band along a sloping axis (a handrail beside a flight) votes but cannot make a
/// frame: its yaw turns with its plane about that axis.
/// When the planes alone make no trusted frame, the image edges' direction (edge_compass.hpp, an
/// independent witness) is asked: planes agreeing with it within compass_agreement, one of them
/// compass_min_width wide, make the frame (their own yaw), which the walls may still veto. Edges
/// too weak for that (below compass_min_support, down to compass_wall_min_support) confirm only
/// strips of wall (wall_strip()), planes that are walls by their own evidence. When the edges'
/// direction confirms nothing, a long straight edge lying on the floor (the foot of a wall, a
/// floor joint: EdgeCompassResult::lines) confirms a wall that agrees with it within
/// compass_agreement, and the frame takes the line's direction (confirm_by_lines()).
/// k_M is the one nearest the user's forward direction z_F; across frames the branch nearest the
/// previous k_M is kept when the choice is ambiguous (near +-45 degrees).

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "stairguide/core/config.hpp"
#include "stairguide/core/types.hpp"
#include "stairguide/perception/edge_compass.hpp"
#include "stairguide/perception/scene.hpp"

namespace stairguide {

struct ManhattanEstimate {
  bool found = false;
  std::string why;
  float yaw = 0.f;            ///< rad, k_M from z_F about y_F (positive towards x_F, the left)
  float fraction = 0.f;       ///< share of planar area on vertical planes agreeing with the frame
  float vertical_area = 0.f;  ///< m^2 of agreeing vertical planes
  Pose T_manhattan_floor = Pose::Identity();
};

/// Rotation about y_F by -yaw: maps floor coordinates into Manhattan coordinates.
Pose manhattan_pose_from_yaw(float yaw);

/// The representative of a direction modulo 90 degrees, in (-pi/4, pi/4].
float manhattan_wrap(float a);

/// The unit normal of the plane through `pts` (camera frame) held orthogonal to `up` (unit, camera
/// frame): a wall's, fitted as upright. On the side of `n0` (the plane's free fit, also returned
/// when the points fix no upright plane). See manhattan_frame.cpp for why and where it is used.
Eigen::Vector3f fit_upright_normal(const std::vector<Eigen::Vector3f>& pts, const Eigen::Vector3f& up,
                                   const Eigen::Vector3f& n0);

/// The same fit on the points of `pts` whose plane lies nearer than `clear_depth` along their ray
/// (the plane: `n_upright`, the upright fit of all of them, through their mean): the readings
/// clear of the depth cut-off's noise band, where the cut-off has dropped none. Chosen by ray, not
/// by reading, so that the choice does not depend on the noise; done twice. `n_upright` is returned
/// unchanged unless at least half of the points (and 30) are clear. See manhattan_frame.cpp.
Eigen::Vector3f fit_upright_normal_clear_of_cutoff(const std::vector<Eigen::Vector3f>& pts,
                                                   const Eigen::Vector3f& up,
                                                   const Eigen::Vector3f& n_upright, float clear_depth);

/// k_M is the dominant direction closest to forward; near +-45 degrees both branches are about as
/// close, so `yaw` is moved onto the branch of the `previous` k_M where that stays within 10
/// degrees of 45 (hysteresis).
float manhattan_keep_branch(float yaw, const std::optional<float>& previous);

/// Weighted directions modulo 90 degrees in 1 degree bins, each spread over its neighbours so
/// that a peak is not split by a bin edge.
class ManhattanHistogram {
 public:
  void add(float a, float w);
  /// rad, the centre of the fullest bin (the first of equals).
  float mode() const;

 private:
  static constexpr int kBins = 90;
  float hist_[kBins] = {};
};

class ManhattanTracker {
 public:
  /// `max_range`: the depth (m) beyond which the sensor gives no reading (CaptureConfig::max_range);
  /// planes seen mostly within ManhattanConfig::range_clip_margin of it cannot make a frame of walls
  /// alone (they still vote). 0: no such test. `depth_noise_coeff` (SegmentationConfig's: sigma =
  /// coeff * z^2) sets the noise band at the cut-off that such a plane's yaw is fitted clear of.
  explicit ManhattanTracker(const ManhattanConfig& config = {}, float max_range = 0.f,
                            float depth_noise_coeff = SegmentationConfig{}.depth_noise_coeff);

  /// Estimates the Manhattan frame from the vertical planes among `regions`, given the floor
  /// (`T_floor_camera`; without a floor, the upright frame of a floor-like plane the floor's checks
  /// refused: SceneResult::T_upright_camera).
  /// `compass`, when given, is asked (once, only when the planes alone make no trusted frame) for
  /// the image edges' direction (edge_compass.hpp): agreeing planes too narrow or too small to be
  /// trusted alone then make the frame (ManhattanConfig::compass_*).
  ManhattanEstimate estimate(const std::vector<PlaneRegion>& regions, const Pose& T_floor_camera,
                             const std::function<EdgeCompassResult()>& compass = {});
  void reset() { prev_yaw_.reset(); }

 private:
  struct Vote {
    float a, w, area, width;
    float heading;  // the normal's direction in the floor plane, rad, (-pi, pi]
    bool inside;  // the floor goes on beyond the plane (or it reaches below the floor): furniture, a riser, a
                  // person
    bool grounded;  // its lowest point is at the floor's height
    bool clipped;   // most of its points lie at the depth cut-off
    int region;     // index in the regions
    bool
        sliver;  // clipped, and narrower than ManhattanConfig::sliver_width: its yaw may be off by 10 degrees
    // Its plane seen from above, normal towards the camera: a point (x, z) of the floor frame lies
    // beyond it by more than floor_beyond_margin when nx * x + nz * z < limit.
    bool has_side = false;
    float nx = 0.f, nz = 0.f, limit = 0.f;
    float cx = 0.f, cz = 0.f;  // its centroid in the floor frame (set with has_side)
    // A thin band along a sloping axis (a handrail, a stringer): its plane is fixed only up to a
    // turn about that axis, which turns its yaw. It votes but makes no frame, alone or in a pair.
    bool sloped_band = false;
    // A band along a level axis tilted beyond vertical_tolerance: its heading is its axis's; it
    // only joins planes that the image edges confirm (confirm()).
    bool tilted = false;
    // At least ManhattanConfig::far_wall_range away and narrower than far_wall_width: its yaw is
    // good to a few degrees only on the real sensor.
    bool far = false;
    float range = 0.f;  // m, its centroid's distance from the camera
    float base = 0.f;   // m, its lowest point's height above the floor
    float top = 0.f;    // m, its highest point's height above the floor
    // A riser of a flight, a single step or a curb, or a drop's face (mark_risers): the staircase's own
    // direction, which a far wall's cannot overrule.
    bool riser = false;
    float tread_depth = 0.f;  // m, how far the tread on its top edge is seen to go on beyond it
    // Grounded and narrower than min_plane_width, with structure_beyond_area of other surfaces
    // beyond its extension: no wall strip, so it makes no walls' frame alone (min_width()).
    bool structure_beyond = false;
  };
  struct StructureSample {
    float x, z, area;  // floor frame, m; m^2 it stands for
    int region;        // index in the regions
  };
  struct FloorSample {
    float x, z, area;  // floor frame, m; m^2 it stands for
  };
  /// Angle modulo 90 degrees by which a plane must differ from another direction to contradict it.
  float disagree_tolerance(const Vote& v) const;
  /// Width from which an agreeing plane makes the frame trusted on its own.
  float min_width(const Vote& v, bool bounding_only) const;
  /// A strip of wall: on the floor, nothing seen beyond it (neither floor nor other surfaces),
  /// narrower than min_plane_width, clear of the depth cut-off and near (not `far`), upright and
  /// no band along a slope. Too narrow or too small to make a frame alone, it still is a wall.
  bool wall_strip(const Vote& v) const;
  /// Inside the room and hanging above the floor (hanging_min_height): furniture or a person, never
  /// the plane that makes a frame alone, nor one of a pair with another such plane.
  bool hangs(const Vote& v) const;
  /// Which votes solve() counts: the planes that bound the room, all of them, or the risers.
  enum class Voters { kBounding, kAll, kRisers };
  ManhattanEstimate solve(const std::vector<Vote>& votes, float total_area, Voters voters);
  /// Sets Vote::riser and tread_depth (see manhattan_frame.cpp).
  void mark_risers(const std::vector<PlaneRegion>& regions, const Pose& T_floor_camera);
  /// The frame of the planes agreeing with the image edges' direction (see estimate()).
  ManhattanEstimate confirm(const std::vector<Vote>& votes, float total_area,
                            const EdgeCompassResult& compass) const;
  /// The frame of a long straight edge on the floor that a wall agrees with (see estimate()).
  ManhattanEstimate confirm_by_lines(const std::vector<Vote>& votes, float total_area,
                                     const EdgeCompassResult& compass) const;

  // estimate()'s phases (src/perception/manhattan/estimate.cpp).
  /// Fills floor_pts_: samples of every horizontal plane at the floor's height.
  void sample_floor(const std::vector<PlaneRegion>& regions, const Pose& T_floor_camera);
  /// Fills struct_pts_ and region_samples_: samples of every other region.
  void sample_structure(const std::vector<PlaneRegion>& regions, const Pose& T_floor_camera);
  /// What vote_of needs of the floor's pose, computed once a frame.
  struct VoteView {
    Eigen::Matrix3f R;     // T_floor_camera's rotation
    Eigen::Vector3f up_c;  // up in camera coordinates
    float sin_tol = 0.f;   // sin(vertical_tolerance)
    float camera_height = 0.f, full_w = 0.f, clip_depth = 0.f;
  };
  /// Fills votes_ (one per vertical plane, or level band); returns the regions' total area.
  float collect_votes(const std::vector<PlaneRegion>& regions, const Pose& T_floor_camera);
  /// The vote of region `k`; false when it casts none (not vertical, nor a level band).
  bool vote_of(const PlaneRegion& r, int k, const VoteView& view, Vote& vote) const;
  /// Sets each vote's side (has_side, nx, nz, limit, cx, cz) and `inside` (floor beyond it).
  void mark_sides(const std::vector<PlaneRegion>& regions, const Pose& T_floor_camera);
  /// m^2 of the other regions' samples [from, to) beyond a vote's plane.
  float area_beyond(const Vote& v, std::size_t from, std::size_t to) const;
  /// Sets Vote::structure_beyond.
  void mark_structure_beyond();
  /// Whether a wall that is not far (by range, or Vote::far) and wide enough agrees with `yaw`.
  bool near_wall_agrees(float yaw, bool far_by_range) const;
  /// The frame the planes make: the walls', the risers' or all planes'.
  ManhattanEstimate frame_of_planes(float total_area, bool& bounding_only, bool& riser_frame);
  /// Fills vetoes_: the walls seen beyond the planes that make `frame` that disagree with them.
  void find_vetoes(const ManhattanEstimate& frame, bool riser_frame, bool bounding_only);
  /// The frame the vetoing walls (or the image edges agreeing with them) give; false: none.
  bool apply_vetoes(ManhattanEstimate& frame, float total_area,
                    const std::function<EdgeCompassResult()>& compass,
                    std::optional<EdgeCompassResult>& compass_cache) const;

  ManhattanConfig cfg_;
  float max_range_ = 0.f;
  float clear_depth_ = 0.f;  // m: 3 sigma of noise nearer than max_range_ (0: max_range_ unset)
  std::optional<float> prev_yaw_;
  std::vector<const Vote*> pair_candidates_;  // scratch: agreeing planes wide enough to make a pair
  std::vector<const Vote*> vetoes_;           // scratch: the walls that veto the frame
  std::vector<Vote> votes_;                   // scratch
  std::vector<FloorSample> floor_pts_;        // scratch
  std::vector<StructureSample> struct_pts_;   // scratch: samples of the regions other than the floor
  std::vector<std::size_t> region_samples_;   // scratch: region k's samples start at [k], end at [k + 1]
  std::vector<char> stacked_;                 // scratch: mark_risers' candidates on or under another
};

}  // namespace stairguide
