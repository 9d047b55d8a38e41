#pragma once
/// \file config.hpp
/// Every tunable of the pipeline, one struct per stage, with defaults written here.
///
/// Values inside are SI (metres, seconds, radians, fractions). The YAML file uses the units named
/// in each key's suffix (`_cm`, `_deg`, `_percent`, ...); the loader converts. Each struct lists its
/// fields once in `visit()`: the loader, the YAML writer and the equality test all walk that list,
/// so a field cannot be known to one and forgotten by another.
///
/// Only what a technician may need to set is a key (a physical quantity of the rig, the sensor,
/// the stairs or the feedback). A field that `visit()` does not list is one of the method's own
/// thresholds (which plane is a tread, which wall makes the Manhattan frame...): named here with its
/// unit, fixed, and refused in a file like any unknown key (issue 39: 231 keys became 137).
///
/// A visitor `V` provides:
///   v.num(field, "key", Unit, min, max, "comment")  - float/double/int, range in file units
///   v.flag(field, "key", "comment")                 - bool
///   v.text(field, "key", {"a","b"} or {}, "comment") - string, optional list of allowed values
///   v.section("name", "comment", sub_struct)

#include <string>
#include <vector>

namespace stairguide {

/// Unit of a value in the YAML file; the loader converts it to SI.
enum class Unit {
  kNone,
  kMetre,
  kCentimetre,
  kMillimetre,
  kDegree,
  kPercent,
  kSecond,
  kMillisecond,
  kHertz,
  kPerMetre,
  kPixel,
  kCount
};

/// Factor from file unit to SI (cm -> m is 0.01, deg -> rad is pi/180, percent -> fraction 0.01).
double unit_to_si(Unit u);
/// Short unit name for comments and messages ("cm", "deg", ...); empty for kNone.
const char* unit_name(Unit u);

struct CaptureConfig {
  std::string device_uri = "";     ///< OpenNI2 device URI; empty = first device found
  int width = 640;                 ///< px, requested depth/colour mode
  int height = 480;                ///< px
  int fps = 30;                    ///< Hz
  bool depth_registration = true;  ///< register depth to colour in the device
  bool mirroring = false;          ///< image mirroring in the device
  float read_timeout = 2.0f;       ///< s without a frame before the camera counts as lost
  float retry_min = 0.5f;          ///< s, first reconnect delay
  float retry_max = 8.0f;          ///< s, longest reconnect delay (exponential back-off)
  float max_range = 5.0f;          ///< m, depth beyond this is discarded as unreliable
  float min_range = 0.4f;          ///< m, depth below this is discarded

  template <class V>
  void visit(V& v) {
    v.text(device_uri, "device_uri", {}, "OpenNI2 device URI; empty picks the first camera");
    v.num(width, "width_px", Unit::kPixel, 80, 1920, "depth and colour width");
    v.num(height, "height_px", Unit::kPixel, 60, 1080, "depth and colour height");
    v.num(fps, "fps_hz", Unit::kHertz, 1, 120, "frame rate requested from the camera");
    v.flag(depth_registration, "depth_registration", "register depth to colour in the device");
    v.flag(mirroring, "mirroring", "mirror the images in the device (off for a body camera)");
    v.num(read_timeout, "read_timeout_s", Unit::kSecond, 0.1, 60, "no frame for this long = camera lost");
    v.num(retry_min, "retry_min_s", Unit::kSecond, 0.05, 60, "first reconnect delay");
    v.num(retry_max, "retry_max_s", Unit::kSecond, 0.05, 600,
          "longest reconnect delay (back-off doubles up to it)");
    v.num(min_range, "min_range_m", Unit::kMetre, 0.0, 2.0, "depth nearer than this is dropped");
    v.num(max_range, "max_range_m", Unit::kMetre, 0.5, 20.0, "depth farther than this is dropped");
  }
};

struct SegmentationConfig {
  float voxel_size = 0.04f;            ///< m, voxel grid edge (paper: 3-4 cm)
  float normal_radius = 0.05f;         ///< m, neighbourhood for PCA normals
  float region_angle = 0.10471976f;    ///< rad, region growing normal deviation (6 deg)
  float region_curvature = 0.5f;       ///< region growing curvature threshold
  int region_min_points = 50;          ///< points (voxels) in a region
  float planarity_min_inliers = 0.8f;  ///< fraction of a region's points on its RANSAC plane
  float cluster_tolerance = 0.08f;     ///< m, Euclidean clustering distance for non-planar points
  int cluster_min_points = 30;         ///< points in an obstacle cluster
  // Organized (image-structure) segmentation, the route the pipeline runs; the fields above are
  // the paper's PCL route, used by the reference pipeline of `stairguide bench perception`.
  int cell_size_px = 8;                 ///< px, edge of the cells whose planes seed region growing
  int fine_cell_size_px = 4;            ///< px, second seeding pass on what the first left (thin treads)
  float depth_noise_coeff = 1.425e-3f;  ///< 1/m, depth sigma = coeff * z^2 (Kinect)
  float inlier_sigmas = 3.0f;           ///< a pixel joins a plane within this many sigmas (perpendicular)
  float inlier_min_distance = 0.003f;   ///< m, added to the metric tests (region merging)
  int region_min_pixels = 100;          ///< px, smallest planar region kept
  int cluster_min_pixels = 200;         ///< px, smallest obstacle cluster kept
  int points_stride_px = 2;             ///< px, PlaneRegion::points keeps every Nth pixel in u and v
  float dominant_min_fraction =
      0.01f;  ///< share of the valid pixels a region needs for its normal to be a dominant direction
  int strip_length_px =
      8;  ///< px, columns of the 2-row windows seeding thin strips on dominant directions (0: off)
  float curved_tile_max_area = 0.15f;        ///< m^2, regions smaller than this, bent smoothly into their
                                             ///< neighbours, are tiles of a curved surface (0: off)
  float curved_bend_max_angle = 0.6981317f;  ///< rad, a smooth (depth-continuous) seam between two regions at
                                             ///< most this angle apart is a bend (40 deg)
  float curved_facet_size_ratio =
      8.f;  ///< a region bends like a facet only into neighbours at least 1/ratio its area (0: any neighbour)

  template <class V>
  void visit(V& v) {
    v.num(voxel_size, "voxel_size_cm", Unit::kCentimetre, 0.5, 20, "voxel grid edge (paper: 3-4 cm)");
    v.num(normal_radius, "normal_radius_cm", Unit::kCentimetre, 1, 50,
          "radius of the PCA normal neighbourhood");
    v.num(region_angle, "region_angle_deg", Unit::kDegree, 0.5, 45, "region growing: max normal deviation");
    v.num(region_curvature, "region_curvature", Unit::kNone, 0.0, 10, "region growing: curvature threshold");
    v.num(region_min_points, "region_min_points", Unit::kCount, 3, 100000, "smallest planar region");
    v.num(planarity_min_inliers, "planarity_min_inliers_percent", Unit::kPercent, 10, 100,
          "a region is planar when this share of it lies on its RANSAC plane");
    v.num(cluster_tolerance, "cluster_tolerance_cm", Unit::kCentimetre, 0.5, 100,
          "Euclidean clustering distance");
    v.num(cluster_min_points, "cluster_min_points", Unit::kCount, 1, 100000, "smallest obstacle cluster");
    v.num(depth_noise_coeff, "depth_noise_coeff_per_m", Unit::kPerMetre, 1e-5, 0.1,
          "depth noise sigma = coeff * z^2 (Kinect: 1.425e-3)");
  }
};

struct FloorConfig {
  // The rig range: any chest or waist rig (issue 34), a camera mounted 0.5-1.8 m high and tilted
  // 15-80 deg, with a margin for the wobble of a walk (the chest pitches by +-5 deg, the camera
  // bobs by cm). The paper's 1.0-1.6 m and 20-70 deg gate is the profile config/profiles/paper.yaml.
  float tilt_min = 0.17453293f;  ///< rad, camera pitch below horizontal (10 deg)
  float tilt_max = 1.48352986f;  ///< rad (85 deg)
  float roll_max = 0.34906585f;  ///< rad, |roll| allowed (20 deg)
  float height_min = 0.4f;       ///< m, camera above the floor
  float height_max = 1.9f;       ///< m
  // The usual chest rig (the paper's gate): a cold start looks for the floor here first, and only
  // when none is found here in the whole rig range; floorless stairs place the user's floor here
  // while no camera height is learned.
  float usual_tilt_min = 0.34906585f;  ///< rad (20 deg)
  float usual_tilt_max = 1.22173048f;  ///< rad (70 deg)
  float usual_height_min = 1.0f;       ///< m
  float usual_height_max = 1.6f;       ///< m
  // The rig model: the user's camera height, learned from the first clear views and held.
  int rig_learn_frames = 5;            ///< clear views agreeing within rig_height_tolerance that establish it
  float rig_height_tolerance = 0.10f;  ///< m, once established the floor lies within this of it
  float rig_tilt_tolerance = 0.17453293f;  ///< rad (10 deg), a walk's wobble about the rig's learned tilt
  int rig_relearn_frames =
      150;  ///< frames of a clear floor at another height (none at the held one) that relearn it
  float search_start = 1.0f;                 ///< m, first z_C window for floor points
  float search_step = 0.5f;                  ///< m, window growth per attempt
  float search_max = 4.0f;                   ///< m, largest window
  float inlier_distance = 0.04f;             ///< m, plane inlier distance (paper: the voxel edge)
  float min_area = 0.25f;                    ///< m^2, smallest floor patch
  float track_max_height_jump = 0.08f;       ///< m, change of camera height accepted between frames
  float track_max_angle_jump = 0.17453293f;  ///< rad, change of floor normal accepted between frames
  float horizontal_tolerance = 0.17453293f;  ///< rad, floor candidates vs the tracked floor normal (10 deg)
  int track_hold_frames = 15;                ///< frames the tracked floor is held after it was last seen
  int track_forget_frames =
      300;  ///< frames the user's camera height is remembered after the floor was last seen
  float track_anchor_tolerance =
      0.04f;  ///< m, a tracked floor this near the last verified camera height needs no re-verification
  float verify_drop = 0.06f;  ///< m, a point this far below a floor candidate counts as "below"
  float verify_margin_angle = 0.0087266463f;  ///< rad, "nearer the user": this much nearer the nadir than the
                                              ///< candidate's near edge (0.5 deg)
  float view_edge_angle =
      0.034906585f;  ///< rad, a plane within this of the view's bottom edge "starts at the edge" (2 deg)
  float ambiguous_rise_min =
      0.10f;  ///< m, a plane this much above a candidate starting at the view's edge ...
  float ambiguous_rise_max = 0.22f;  ///< m, ... and at most this ...
  float ambiguous_depth_max =
      0.45f;  ///< m, ... and starting within this of its near edge: the candidate may be a tread
  float ambiguous_covered =
      0.9f;  ///< share of such a candidate's pixels with the upper plane above them in the image
  float ambiguous_tread_area_max =
      2.0f;  ///< m^2, a plane bigger than this is a floor level, never the tread after the candidate
  float floor_beyond_riser =
      0.10f;  ///< m, a candidate's level seen this far beyond the next riser's line, beside the flight ...
  float floor_beyond_min_area =
      0.02f;  ///< m^2, ... over this much area, is the floor around the flight, not its first tread
  float floor_deeper_than_tread =
      0.03f;  ///< m, a candidate deeper than the treads ahead by this is no tread of that flight
  float tread_depth_agreement = 0.02f;  ///< m, the two treads ahead must agree in depth within this
  float tread_min_aspect = 2.0f;  ///< a level is taken for a tread (its short axis: the flight's direction)
                                  ///< when this many times wider than deep
  float curb_rise_min = 0.05f;    ///< m, a level this much above a candidate ...
  float curb_rise_max =
      0.25f;  ///< m, ... and at most this, cut by the view's bottom edge, the nadir on its side
              ///< of its straight boundary with the candidate: the user may stand on it
  float curb_boundary_gap = 0.25f;  ///< m, points of that level this near the candidate form their boundary
  float curb_straightness = 0.04f;  ///< m, largest rms off a straight line for that boundary
  float curb_min_edge = 0.8f;       ///< m, shortest such boundary (a curb's edge, not a crate's corner)
  float curb_min_edge_cut = 0.4f;   ///< m, ... or this, when the view's border cuts it at both ends
  int verify_min_pixels = 400;      ///< px, this many pixels below and nearer reject a floor candidate
  int verify_stride_px = 6;         ///< px, sampling grid of the frame for the check

  template <class V>
  void visit(V& v) {
    v.num(tilt_min, "tilt_min_deg", Unit::kDegree, 0, 90, "camera pitch below horizontal: lowest");
    v.num(tilt_max, "tilt_max_deg", Unit::kDegree, 0, 90, "camera pitch below horizontal: highest");
    v.num(roll_max, "roll_max_deg", Unit::kDegree, 0, 90, "largest camera roll");
    v.num(height_min, "height_min_m", Unit::kMetre, 0.1, 3, "camera height above the floor: lowest");
    v.num(height_max, "height_max_m", Unit::kMetre, 0.1, 3, "camera height above the floor: highest");
    v.num(usual_tilt_min, "usual_tilt_min_deg", Unit::kDegree, 0, 90,
          "the usual chest rig's pitch below horizontal, lowest: a cold start looks for the floor within the "
          "usual "
          "tilt and height first, in the whole range above only when none is found there");
    v.num(usual_tilt_max, "usual_tilt_max_deg", Unit::kDegree, 0, 90, "the usual chest rig's pitch: highest");
    v.num(usual_height_min, "usual_height_min_m", Unit::kMetre, 0.1, 3,
          "the usual chest rig's height above the floor, lowest (also where floorless stairs place the "
          "user's floor "
          "while no camera height is learned)");
    v.num(usual_height_max, "usual_height_max_m", Unit::kMetre, 0.1, 3,
          "the usual chest rig's height: highest");
    v.num(rig_learn_frames, "rig_learn_frames", Unit::kCount, 1, 1000,
          "the user's camera height is established when this many clear views of the floor (nothing lower "
          "nearer the "
          "user, no possible tread) agree within rig_height_tolerance_cm; meanwhile any height in the range "
          "is tried");
    v.num(rig_height_tolerance, "rig_height_tolerance_cm", Unit::kCentimetre, 2, 50,
          "once the camera height is established the floor is looked for only this near it (a table, bed, "
          "seat or "
          "landing below the camera is no floor whatever the rig); keep it below the lowest riser or seat");
    v.num(rig_tilt_tolerance, "rig_tilt_tolerance_deg", Unit::kDegree, 2, 45,
          "the rig's tilt is learned with its height; from then on a floor outside the usual tilt is taken "
          "only "
          "this near the rig's own (a hand-held camera that now and then grazes the floor is no level rig)");
    v.num(rig_relearn_frames, "rig_relearn_frames", Unit::kCount, 1, 100000,
          "frames in which a fresh start would find a clear floor at one other height, with none at the held "
          "one, "
          "that relearn the camera height (the wearer sat down, the rig was remounted); a lower floor needs "
          "no level "
          "in view between it and the camera");
    v.num(inlier_distance, "inlier_distance_cm", Unit::kCentimetre, 0.2, 20,
          "plane inlier distance (paper: voxel edge)");
    v.num(min_area, "min_area_m2", Unit::kNone, 0.01, 100, "smallest floor patch, square metres");
    v.num(track_max_height_jump, "track_max_height_jump_cm", Unit::kCentimetre, 0.5, 100,
          "camera height change accepted from one frame to the next");
    v.num(track_max_angle_jump, "track_max_angle_jump_deg", Unit::kDegree, 0.5, 90,
          "floor normal change accepted from one frame to the next");
    v.num(track_hold_frames, "track_hold_frames", Unit::kCount, 0, 1000,
          "frames the tracked floor is held after it was last seen (no other level taken meanwhile)");
    v.num(track_forget_frames, "track_forget_frames", Unit::kCount, 0, 100000,
          "frames the camera height above the floor is remembered after the floor was last seen: meanwhile a "
          "plane a riser or more lower (a tread below the user) is never taken for the floor");
  }
};

struct ManhattanConfig {
  float vertical_tolerance = 0.17453293f;  ///< rad, a plane counts as vertical within this (10 deg)
  float min_area = 0.03f;                  ///< m^2 of vertical planes needed for a Manhattan frame
  float cluster_tolerance =
      0.08726646f;              ///< rad, vertical normals within this of the mode vote for it (5 deg)
  float yaw_full_width = 1.0f;  ///< m, a vertical plane's vote weighs area * min(1, width / this)^2 (its
                                ///< yaw's precision grows with its width)
  float min_plane_width =
      0.6f;  ///< m, an agreeing vertical plane this wide (a wall, a riser) makes the frame trusted ...
  float max_spread =
      0.02617994f;  ///< rad, ... else the agreeing votes' weighted spread must stay below this (1.5 deg)
  float floor_beyond_margin =
      0.25f;  ///< m, floor this far beyond a vertical plane shows it stands inside the room ...
  float floor_beyond_area =
      0.05f;  ///< m^2, ... when this much floor lies there (furniture, risers; not a wall)
  float floor_beyond_height =
      0.05f;  ///< m, horizontal planes within this of the floor count as floor for that test
  float min_bounding_width =
      0.2f;  ///< m, min_plane_width for planes standing on the floor with no floor beyond them (walls)
  float range_clip_margin = 0.25f;  ///< m, a vertical plane with most points this near the depth cut-off
                                    ///< cannot make a frame of walls alone
  float far_wall_range = 4.0f;      ///< m, a wall this far away (its centroid) ...
  float far_wall_width =
      1.0f;  ///< m, ... and narrower than this has a yaw good to a few degrees only on the real sensor ...
  float far_wall_agreement = 0.08726646f;  ///< rad, ... so a frame only such walls make yields to the frame
                                           ///< of all the planes within this of it (5 deg)
  float riser_max_height = 0.22f;  ///< m, a vertical plane at most this tall with a tread on its top edge may
                                   ///< be a riser (or an open riser's tread front)
  float riser_tread_tolerance =
      0.03f;  ///< m, a horizontal plane within this of its top edge's height is its tread
  float riser_min_height = 0.10f;  ///< m, two such planes whose treads are this much apart in height ...
  float riser_going_min = 0.15f;   ///< m, ... and the one this far beyond the other ...
  float riser_going_max = 0.6f;    ///< m, ... and at most this, are a flight's risers
  float single_riser_min_width =
      0.8f;  ///< m, one standing on the floor is a riser (a single step, a curb) when this wide ...
  float single_riser_min_depth = 0.6f;  ///< m, ... and its tread is seen to go on this far beyond it
  float riser_agreement = 0.17453293f;  ///< rad, risers make the frame over far walls within this of them,
                                        ///< and far walls cannot veto it (10 deg); 0: never
  float hanging_min_height = 0.22f;     ///< m, a plane with floor beyond it whose lowest point is this high
                                        ///< (furniture, people) makes no frame alone (0: off)
  float structure_beyond_area = 0.02f;  ///< m^2, other surfaces this large beyond a vertical plane make it no
                                        ///< wall; a wall this large beyond a frame's plane may veto it ...
  float veto_min_width = 0.2f;          ///< m, ... when at least this wide
  float sliver_width =
      0.15f;  ///< m, a plane at the depth cut-off narrower than this (in-plane, narrowest) is a sliver ...
  float clipped_disagreement =
      0.2617994f;  ///< rad, ... and contradicts another direction only beyond this (15 deg)
  float band_max_thickness =
      0.05f;  ///< m, a vertical plane thinner than this on average (area / length) is a band ...
  float band_min_slope =
      0.2617994f;  ///< rad, ... whose yaw is unreliable when its long axis slopes more than this (15 deg)
  float level_band_max_height = 0.1f;  ///< m, a plane narrower than this in-plane is a band ...
  float level_band_max_tilt =
      0.43633231f;  ///< rad, ... which along a level axis may tilt this far from vertical (25 deg) ...
  float level_band_max_slope = 0.13962634f;  ///< rad, ... when its axis slopes less than this (8 deg): it
                                             ///< joins planes the image edges confirm
  float pair_min_width = 0.05f;  ///< m, without a wide plane, two agreeing parallel planes each this wide ...
  float pair_tolerance = 0.03490659f;  ///< rad, ... agreeing within this (2 deg) ...
  float pair_min_separation =
      0.15f;  ///< m, ... make the frame trusted when this far apart (two risers, a wall and a riser) ...
  bool without_floor =
      true;  ///< with no floor found, measure the frame about a floor-like plane refused as the floor
  float carry_seconds = 10.f;  ///< s, a Manhattan frame seen this recently is carried by the odometry to
                               ///< views that make none (0: never)
  float compass_min_support = 0.2f;  ///< share of the image edges' votes at their peak direction
                                     ///< (edge_compass.hpp) for it to count; 1: never asked
  float compass_agreement =
      0.03490659f;                 ///< rad, planes within this of that direction (modulo 90 deg) ... (2 deg)
  float compass_min_width = 0.2f;  ///< m, ... make the frame when one of them is this wide, even if too
                                   ///< narrow or small to be trusted alone
  float compass_wall_min_support = 0.06f;  ///< share at the peak for weaker edges to confirm wall strips only
                                           ///< (on the floor, nothing beyond them); 1: never
  float compass_veto_min_support = 0.06f;  ///< share of the edges' votes at their peak for them to give a
                                           ///< frame that narrow walls veto (1: never) ...
  float compass_veto_agreement =
      0.10471976f;  ///< rad, ... when within this of the widest vetoing wall (6 deg; 0: never)
  float compass_line_min_length =
      150.f;  ///< px, a straight edge on the floor this long (edge_compass.hpp) confirms a wall within
              ///< compass_agreement of it when the edges' dominant direction confirms none; 0: never

  template <class V>
  void visit(V& v) {
    v.num(vertical_tolerance, "vertical_tolerance_deg", Unit::kDegree, 0.5, 45,
          "a plane is vertical within this angle");
    v.num(min_area, "min_area_m2", Unit::kNone, 0, 100,
          "vertical plane area needed for a Manhattan frame, square metres");
    v.flag(without_floor, "without_floor",
           "with no floor found, measure the frame about the vertical of a floor-like plane the floor's "
           "checks refused "
           "(a tread, a seat: which level the user stands on is in doubt, which way is up is not)");
    v.num(carry_seconds, "carry_s", Unit::kSecond, 0, 600,
          "seconds a Manhattan frame seen in one view is carried by the odometry to later views whose own "
          "walls make "
          "none (walls do not turn when the user does); 0: never");
  }
};

struct ClassificationConfig {
  float parallel_threshold = 0.17453293f;  ///< rad, parallel/perpendicular tolerance (10 deg)
  float step_height_min = 0.10f;           ///< m, H_min (the world's codes; the paper's: 0.13)
  float step_height_max = 0.22f;           ///< m, H_max (the world's codes; the paper's: 0.185)
  float floor_height_tolerance = 0.04f;    ///< m, a horizontal plane this close to 0 is floor
  float step_height_tolerance = 0.02f;     ///< m, noise margin below H_min for step candidates

  template <class V>
  void visit(V& v) {
    v.num(parallel_threshold, "parallel_threshold_deg", Unit::kDegree, 0.5, 45,
          "tolerance for parallel and perpendicular");
    v.num(step_height_min, "step_height_min_cm", Unit::kCentimetre, 1, 100, "H_min, lowest step riser");
    v.num(step_height_max, "step_height_max_cm", Unit::kCentimetre, 1, 100, "H_max, highest step riser");
    v.num(floor_height_tolerance, "floor_height_tolerance_cm", Unit::kCentimetre, 0.5, 50,
          "a horizontal plane within this of the floor is floor");
    v.num(step_height_tolerance, "step_height_tolerance_cm", Unit::kCentimetre, 0, 10,
          "measurement margin: |H| >= H_min - this makes a step candidate");
  }
};

struct StairDetectionConfig {
  float same_level_tolerance = 0.03f;  ///< m, candidates within this height form one level
  float connection_radius = 0.5f;      ///< m, neighbour search radius between regions
  int connection_min_points = 10;      ///< points within the radius for a connection
  float height_tolerance = 0.02f;      ///< m, measurement slack on the H_min..H_max riser range
  int connection_max_points = 256;     ///< points per region used for the connection test (subsampled)
  float curb_height_min = 0.10f;       ///< m, lowest curb (a single level may be lower than H_min)
  float single_min_width = 0.8f;       ///< m, a single level narrower than this is an obstacle
  float single_min_depth = 0.7f;       ///< m, a single level shallower than this is an obstacle
  float curb_min_depth = 2.6f;         ///< m, a single raised level deeper than this is another floor (curb)
  // Floorless route (stairs/floorless.hpp): stairs found when perception saw no floor.
  bool floorless =
      true;  ///< look for stairs from the horizontal planes alone when there is no floor (floorless.hpp)
  float floorless_tilt_min = -0.17453293f;  ///< rad, lowest camera pitch below horizontal implied by the
                                            ///< planes (-10 deg: about level)
  float floorless_tilt_max =
      1.3962634f;  ///< rad, highest (80 deg: looking steeply down at the steps before the feet)
  int floorless_min_level_pixels = 500;      ///< px, smallest level (all its regions) of a floorless stack
  int floorless_min_levels = 2;              ///< levels one riser apart needed without a floor
  float floorless_anchor_tolerance = 0.04f;  ///< m, with the camera height remembered: the first level seen
                                             ///< lies a whole number of risers from the feet within this
  int floorless_max_hidden_steps = 1;  ///< with the camera height remembered: steps between the feet and the
                                       ///< first level seen that may be out of view (floorless.hpp: one more,
                                       ///< two going down, with the first edge at the camera's vertical)

  template <class V>
  void visit(V& v) {
    v.num(same_level_tolerance, "same_level_tolerance_cm", Unit::kCentimetre, 0.5, 20,
          "candidates within this height are one level");
    v.num(connection_radius, "connection_radius_m", Unit::kMetre, 0.05, 5,
          "neighbour search radius between regions");
    v.num(connection_min_points, "connection_min_points", Unit::kCount, 1, 100000,
          "points within the radius to connect");
    v.num(height_tolerance, "height_tolerance_cm", Unit::kCentimetre, 0, 10,
          "measurement slack on the H_min..H_max range between levels");
    v.num(curb_height_min, "curb_height_min_cm", Unit::kCentimetre, 1, 100,
          "lowest curb: a single level this far above or below the floor may be a curb");
    v.num(single_min_width, "single_min_width_m", Unit::kMetre, 0.05, 10,
          "a single level narrower than this is an obstacle, not a step");
    v.num(single_min_depth, "single_min_depth_m", Unit::kMetre, 0.05, 10,
          "a single level shallower than this is an obstacle, not a step");
    v.num(curb_min_depth, "curb_min_depth_m", Unit::kMetre, 0.1, 100,
          "a single raised level deeper than this, or running out of view on both sides and the far side, is "
          "another floor level (a curb)");
    v.flag(floorless, "floorless",
           "without a floor, look for a stack of horizontal planes one riser apart (placed from the feet "
           "while the camera "
           "height is remembered; otherwise heights relative, distance to the feet unknown)");
    v.num(floorless_tilt_min, "floorless_tilt_min_deg", Unit::kDegree, -90, 90,
          "floorless: lowest camera pitch below horizontal the horizontal planes may imply (negative: "
          "looking up)");
    v.num(floorless_tilt_max, "floorless_tilt_max_deg", Unit::kDegree, -90, 90,
          "floorless: highest camera pitch below horizontal the horizontal planes may imply");
    v.num(floorless_min_level_pixels, "floorless_min_level_pixels", Unit::kPixel, 1, 1000000,
          "floorless: smallest level (all its regions), pixels");
    v.num(floorless_min_levels, "floorless_min_levels", Unit::kCount, 2, 100,
          "floorless: levels one riser apart needed to report a staircase");
    v.num(floorless_anchor_tolerance, "floorless_anchor_tolerance_cm", Unit::kCentimetre, 0.5, 10,
          "floorless with the camera height remembered: the first level seen must lie a whole number of "
          "risers from the "
          "user's feet within this (else no staircase)");
    v.num(floorless_max_hidden_steps, "floorless_max_hidden_steps", Unit::kCount, 0, 3,
          "floorless with the camera height remembered: steps between the feet and the first level seen that "
          "may be out "
          "of view (their edges placed from the seen ones)");
  }
};

struct StairModellingConfig {
  // The building code here only describes a staircase (stairs/stair_checks.hpp: StairCodeNote);
  // what cannot be walked is physics (WalkableLimits) and never configured. Defaults: the range of the
  // world's building codes (../shared/data/SOURCES.md: USA IRC/IBC, UK Approved Document K, Germany DIN
  // 18065, Spain CTE); config/profiles/paper.yaml restores the paper's Spanish code (riser 13-18.5, tread >=
  // 28, 2R+T 54-70 cm).
  float riser_min = 0.10f;              ///< m, building code
  float riser_max = 0.22f;              ///< m
  float tread_min = 0.20f;              ///< m
  float blondel_min = 0.50f;            ///< m, 2R + T lower bound
  float blondel_max = 0.72f;            ///< m, 2R + T upper bound
  float width_min = 0.6f;               ///< m
  float manhattan_min_fraction = 0.1f;  ///< share of Manhattan points to use the Manhattan axes
  float manhattan_max_disagreement =
      0.08726646f;  ///< rad, Manhattan axes used only within this of the steps' own axes (5 deg)
  float dimension_tolerance = 0.01f;      ///< m, measurement slack on the building-code limits
  float edge_max_residual = 0.06f;        ///< m, largest deviation of a step edge from even spacing
  float tread_tolerance_per_m2 = 0.004f;  ///< m per m^2 of distance: extra slack on tread and 2R+T far away

  template <class V>
  void visit(V& v) {
    v.num(riser_min, "riser_min_cm", Unit::kCentimetre, 1, 100,
          "building code described (never a reason for silence): lowest riser");
    v.num(riser_max, "riser_max_cm", Unit::kCentimetre, 1, 100,
          "building code described: highest riser (over it: \"steep\")");
    v.num(tread_min, "tread_min_cm", Unit::kCentimetre, 1, 200,
          "building code described: shortest tread (under it: \"steep\")");
    v.num(blondel_min, "blondel_min_cm", Unit::kCentimetre, 10, 300, "building code described: lowest 2R+T");
    v.num(blondel_max, "blondel_max_cm", Unit::kCentimetre, 10, 300, "building code described: highest 2R+T");
    v.num(width_min, "width_min_cm", Unit::kCentimetre, 5, 1000,
          "building code described: narrowest staircase (what cannot be walked is fixed: rise 5-25 cm, tread "
          ">= 15 cm, width >= 50 cm)");
    v.num(dimension_tolerance, "dimension_tolerance_cm", Unit::kCentimetre, 0, 10,
          "measurement slack on the building-code limits");
    v.num(edge_max_residual, "edge_max_residual_cm", Unit::kCentimetre, 0.5, 50,
          "largest deviation of a step edge from evenly spaced edges");
  }
};

/// The stair traversal tracker (stairs/traversal.hpp, paper 5.2): the staircase held in the
/// odometry's world, corrected from the live view, and the step the user stands on.
struct TraversalConfig {
  bool enabled = true;          ///< run the tracker (false: traversal.ran stays false)
  float body_behind = 0.12f;    ///< m, the body centre behind the chest camera (horizontally)
  float body_below = 1.3f;      ///< m, the feet below the camera when no floor has measured it
  float max_distance = 5.0f;    ///< m, a staircase farther than this is not tracked
  int confirm_frames = 3;       ///< consistent detections needed to take a staircase
  float confirm_window = 0.6f;  ///< s, ... each within this of the previous one
  float lost_time = 2.0f;       ///< s unseen before the foot, after which the staircase is no longer "ahead"
  float memory_time = 30.0f;    ///< s a staircase out of view is remembered in the world
  float landing_factor = 1.8f;  ///< a tread this many goings deep is the last one (landing, floor)
  float correction_gain = 0.15f;  ///< share of the live view's residual applied per frame (times its quality)
  float tilt_gain =
      0.25f;  ///< share of the correction gain given to the vertical (the odometry's tilt drifts little)
  bool correct = true;  ///< correct the held pose from the live view (eq. 15); false: odometry only (eq. 14)
  float match_fraction =
      0.4f;  ///< a level matches a step within this share of the riser (height) and tread (edge)
  float max_yaw_disagreement = 0.34906585f;  ///< rad, a detection further than this from the model's axes is
                                             ///< another staircase (20 deg)
  float max_riser_disagreement =
      0.01f;  ///< m, a view whose riser differs more from the fused one is not used
  float max_tread_disagreement = 0.03f;  ///< m, ... whose tread differs more
  float max_tilt_disagreement =
      0.034906585f;             ///< rad, ... whose vertical differs more from the held one (2 deg)
  int near_levels = 3;          ///< the levels nearest the user whose residuals correct the pose (median)
  float arrive_margin = 0.25f;  ///< m past the last edge at which the user has arrived
  float arrive_hold = 1.5f;     ///< s the arrival is reported before searching again
  float default_tread = 0.29f;  ///< m, going assumed until one is measured (one level seen)

  template <class V>
  void visit(V& v) {
    v.flag(enabled, "enabled", "run the traversal tracker (which step, how many left, the last one)");
    v.num(body_behind, "body_behind_cm", Unit::kCentimetre, 0, 100,
          "the body centre (what stands on a step) behind the chest camera, horizontally");
    v.num(body_below, "body_below_cm", Unit::kCentimetre, 30, 250,
          "the feet below the camera when no floor has measured the camera height");
    v.num(max_distance, "max_distance_m", Unit::kMetre, 0.5, 20,
          "a staircase farther than this is not tracked");
    v.num(confirm_frames, "confirm_frames", Unit::kCount, 1, 100,
          "consistent detections needed before a staircase is taken (no false alarm from one frame)");
    v.num(confirm_window, "confirm_window_s", Unit::kSecond, 0.01, 10,
          "a confirming detection must come within this of the previous one");
    v.num(lost_time, "lost_time_s", Unit::kSecond, 0.1, 60,
          "unseen this long with the user before its foot, the staircase is no longer ahead (it stays in "
          "memory)");
    v.num(memory_time, "memory_time_s", Unit::kSecond, 0, 3600,
          "a staircase out of view is remembered in the odometry's world this long");
    v.num(landing_factor, "landing_factor", Unit::kNone, 1.1, 10,
          "a tread this many goings deep is the last one (a landing or the floor beyond)");
    v.num(correction_gain, "correction_gain_percent", Unit::kPercent, 0, 100,
          "share of the live view's residual (height, along, yaw, vertical) applied each frame, times its "
          "quality");
    v.flag(correct, "correct", "correct the odometry-held stair pose from the live view (paper eq. 15)");
    v.num(arrive_margin, "arrive_margin_cm", Unit::kCentimetre, 0, 200,
          "the user has arrived this far past the last step edge");
    v.num(arrive_hold, "arrive_hold_s", Unit::kSecond, 0, 60,
          "the arrival is reported this long, then searching again");
    v.num(default_tread, "default_tread_cm", Unit::kCentimetre, 15, 60,
          "going assumed until a tread length is measured (a single level seen)");
  }
};

/// Drop-offs (stairs/drop_detection.hpp, issue 42 item 4): the floor ending at an edge with
/// nothing within a step below it.
struct DropConfig {
  bool enabled = true;        ///< look for drop-offs
  float min_depth = 0.25f;    ///< m, a level this far below the floor is a drop (deeper than any step: 25 cm)
  float max_distance = 4.0f;  ///< m, edges farther than this along the floor are not reported
  float sensor_range =
      4.0f;  ///< m, no reading where the floor, continued, would lie nearer than this extends a drop's edge
  float min_width = 0.3f;  ///< m, an edge shorter than this is no drop (a drain, a gap in the readings)

  template <class V>
  void visit(V& v) {
    v.flag(enabled, "enabled",
           "look for drop-offs: the floor ending at an edge with nothing within a step below it");
    v.num(min_depth, "min_depth_cm", Unit::kCentimetre, 15, 100,
          "a surface seen this far below the floor beyond its edge is a drop (deeper than a step)");
    v.num(max_distance, "max_distance_m", Unit::kMetre, 1, 8,
          "drop edges farther than this along the floor are not reported");
    v.num(sensor_range, "sensor_range_m", Unit::kMetre, 1, 10,
          "the depth sensor reads a floor this far: beyond an edge, no reading where the floor would be "
          "nearer extends the drop");
    v.num(min_width, "min_width_cm", Unit::kCentimetre, 10, 200,
          "a drop edge shorter than this is not reported");
  }
};

struct OdometryConfig {
  float sigma_intensity = 5.0f;      ///< intensity units (0-255), photometric residual scale
  float sigma_inv_depth = 0.0025f;   ///< 1/m, inverse-depth residual scale
  float student_nu = 5.0f;           ///< Student-t degrees of freedom
  int pyramid_levels = 5;            ///< paper: 3; 5 (down to 40x30 px at VGA) tracks 14 cm / 7 deg per frame
  int iterations = 10;               ///< per pyramid level
  float min_valid_fraction = 0.05f;  ///< share of pixels with depth needed to track
  float max_translation = 0.3f;      ///< m per frame beyond which the estimate is a failure
  float max_rotation = 0.35f;        ///< rad per frame beyond which the estimate is a failure
  int max_points_per_level = 20000;  ///< pixels per pyramid level (a level with more is subsampled on a grid)
  float max_inv_depth_step = 0.05f;  ///< fraction of W between neighbouring full-res pixels = depth edge
  float min_update_translation = 1e-4f;       ///< m, an update below this (and the rotation one) = converged
  float min_update_rotation = 1.7453293e-4f;  ///< rad (0.01 deg)
  float min_inlier_fraction = 0.5f;           ///< share of used pixels with both residuals within 3 sigma
  bool adaptive_scale = true;  ///< weight scales follow the residuals while above sigma_I / sigma_W
  float keyframe_max_translation =
      0.10f;  ///< m from the reference frame beyond which the current frame becomes it (0: frame to frame)
  float keyframe_max_rotation =
      0.10471976f;  ///< rad from the reference frame beyond which the current frame becomes it
  float keyframe_min_overlap = 0.6f;  ///< share of the reference's finest-level points still matched, below
                                      ///< which a new reference is taken

  template <class V>
  void visit(V& v) {
    v.num(sigma_intensity, "sigma_intensity", Unit::kNone, 0.01, 255,
          "photometric scale sigma_I, grey levels 0-255");
    v.num(sigma_inv_depth, "sigma_inv_depth_per_m", Unit::kPerMetre, 1e-6, 1,
          "inverse-depth scale sigma_W, 1/m");
    v.num(student_nu, "student_nu", Unit::kNone, 1, 100,
          "Student-t degrees of freedom (weights (nu+1)/(nu+x^2))");
    v.num(pyramid_levels, "pyramid_levels", Unit::kCount, 1, 6,
          "image pyramid levels, coarse to fine (paper: 3; two more coarse ones cost little and catch 14 cm "
          "/ 7 deg)");
    v.num(iterations, "iterations", Unit::kCount, 1, 100, "Gauss-Newton iterations per level");
    v.num(min_valid_fraction, "min_valid_percent", Unit::kPercent, 0.1, 100,
          "pixels with depth needed to track");
    v.num(max_translation, "max_translation_cm", Unit::kCentimetre, 1, 500,
          "motion per frame beyond walking = failure");
    v.num(max_rotation, "max_rotation_deg", Unit::kDegree, 1, 180,
          "rotation per frame beyond walking = failure");
    v.num(min_inlier_fraction, "min_inlier_percent", Unit::kPercent, 0, 100,
          "share of used pixels whose residuals are within 3 sigma, below which the estimate is a failure");
    v.flag(adaptive_scale, "adaptive_scale",
           "far from the solution, scale the Student-t weights by the residuals' own spread (never below "
           "sigma_I, sigma_W)");
    v.num(keyframe_max_translation, "keyframe_max_translation_cm", Unit::kCentimetre, 0, 100,
          "track against one reference (keyframe) until the camera is this far from it; 0 = frame to frame");
    v.num(keyframe_max_rotation, "keyframe_max_rotation_deg", Unit::kDegree, 0, 90,
          "track against one reference (keyframe) until the camera has turned this much from it");
  }
};

struct RuntimeConfig {
  std::string log_level = "info";  ///< spdlog level
  int ring_capacity = 8;           ///< frames per ring buffer (at most 30: one second at 30 Hz)
  float status_interval = 5.0f;    ///< s between counter logs / STATUS updates
  bool realtime = true;            ///< replay paced by timestamps (false: as fast as possible)

  template <class V>
  void visit(V& v) {
    v.text(log_level, "log_level", {"trace", "debug", "info", "warn", "error", "critical", "off"},
           "log level");
    // At most about a second of frames at 30 Hz (the ring is rounded up to a power of two: 32):
    // 1024 let a slow odometry fall 20 s behind the camera with 1.4 GB of frames held (issue 41).
    v.num(ring_capacity, "ring_capacity", Unit::kCount, 2, 30, "frames held by each ring buffer");
    v.num(status_interval, "status_interval_s", Unit::kSecond, 0.1, 3600, "seconds between counter reports");
    v.flag(realtime, "realtime_replay", "pace a replay by its timestamps (false: as fast as possible)");
  }
};

struct FeedbackConfig {
  bool audio_enabled = true;
  std::string audio_device = "default";  ///< ALSA PCM name
  std::string sounds_dir = "/usr/share/stairguide/sounds";
  float volume = 0.8f;  ///< fraction of full scale
  bool haptic_enabled = true;
  std::string gpio_chip = "gpiochip0";  ///< name or /dev path; "file:PATH" writes the edges to PATH (tests)
  int gpio_line = 17;
  float min_cue_interval = 1.5f;     ///< s between two cues of the same kind
  float announce_distance = 4.0f;    ///< m, announce stairs nearer than this
  std::string verbosity = "normal";  ///< "quiet", "normal" or "verbose"
  float danger_distance = 2.0f;      ///< m, a descending staircase nearer than this always warns
  int confirm_frames = 4;            ///< frames a detection needs before it is announced
  float confirm_time = 0.3f;         ///< s a detection must persist before it is announced
  float forget_time = 3.0f;          ///< s unseen before an announced staircase is forgotten
  float repeat_time = 20.0f;         ///< s before the same staircase may be announced again
  float blind_after = 3.0f;          ///< s with no floor and no stair before "cannot see"
  float blind_repeat = 30.0f;        ///< s between two "cannot see" cues while still blind
  int count_interval = 5;            ///< steps between two spoken counts on a flight
  float min_tick_interval = 0.25f;   ///< s, shortest gap between two step ticks
  float audio_retry = 3.0f;          ///< s between two attempts to open the sound device
  bool stereo_pan = true;            ///< stereo output, each cue placed by the staircase's bearing
  float approach_range = 2.0f;  ///< m, the approach beep starts this near a descent's first edge (0: off)
  float approach_near = 0.5f;   ///< m, at and nearer than this the beep comes fastest
  float approach_interval_far = 1.5f;    ///< s between two beeps at approach_range
  float approach_interval_near = 0.25f;  ///< s between two beeps at approach_near (linear between)
  float approach_cone =
      0.61086524f;  ///< rad (35 deg), half-angle: the edge's bearing beyond it (turned away) stops the beep
  float approach_stall = 2.0f;  ///< s without coming nearer (stopped) before the beep stops
  std::string power_supply_dir =
      "/sys/class/power_supply";  ///< sysfs power-supply class (a fake folder in tests)
  float battery_poll = 10.0f;     ///< s between two readings of the battery
  float battery_low = 0.15f;      ///< fraction of full charge, at or below (not charging): "battery low"
  float battery_critical =
      0.05f;                      ///< fraction of full charge, at or below (not charging): "battery critical"
  float battery_repeat = 300.0f;  ///< s between two "battery low" while it lasts
  float battery_critical_repeat = 60.0f;  ///< s between two "battery critical" while it lasts
  float slow_lag = 0.5f;                  ///< s from capture to decision beyond which perception is behind
  float slow_after = 3.0f;                ///< s behind before "slow" is said
  float slow_repeat = 60.0f;              ///< s between two "slow" while it lasts
  bool button_enabled = false;            ///< read the wearer's push button
  std::string button_chip = "gpiochip0";  ///< name or /dev path; "file:PATH" reads presses from PATH (tests)
  int button_line = 27;                   ///< GPIO line offset of the button
  bool button_active_low = true;          ///< pressed when the line is low (a button to ground, pulled up)
  float button_debounce = 0.03f;          ///< s a level must hold to count (contact bounce is shorter)
  float button_long_press = 1.0f;         ///< s held: a long press (mute)
  float button_double_press = 0.4f;       ///< s from a release to the next press: a double press
  float mute = 300.0f;          ///< s a long press mutes the cues (a descent's warnings still sound)
  std::string language = "en";  ///< the cues' language: sounds_dir/<language>/ ("en": sounds_dir itself)

  template <class V>
  void visit(V& v) {
    v.flag(audio_enabled, "audio_enabled", "play audio cues");
    v.text(audio_device, "audio_device", {}, "ALSA PCM for the cues");
    v.text(sounds_dir, "sounds_dir", {}, "folder of the WAV cues");
    v.num(volume, "volume_percent", Unit::kPercent, 0, 100, "cue volume");
    v.flag(haptic_enabled, "haptic_enabled", "drive the buzzer on the GPIO line");
    v.text(gpio_chip, "gpio_chip", {},
           "GPIO chip of the buzzer (name or /dev path; file:PATH records the edges)");
    v.num(gpio_line, "gpio_line", Unit::kCount, 0, 1023, "GPIO line offset of the buzzer");
    v.num(min_cue_interval, "min_cue_interval_s", Unit::kSecond, 0, 60,
          "shortest gap between two cues of one kind");
    v.num(announce_distance, "announce_distance_m", Unit::kMetre, 0.2, 20,
          "announce stairs nearer than this");
    v.text(verbosity, "verbosity", {"quiet", "normal", "verbose"},
           "quiet: warnings only (earcons for stairs ahead); normal: + speech, ticks, counts; verbose: + "
           "distances, steps left");
    v.num(danger_distance, "danger_distance_m", Unit::kMetre, 0.5, 10,
          "a descending staircase nearer than this always warns");
    v.num(confirm_frames, "confirm_frames", Unit::kCount, 1, 100,
          "frames a detection needs before it is announced");
    v.num(confirm_time, "confirm_time_s", Unit::kSecond, 0, 10,
          "a detection must persist this long before it is announced");
    v.num(forget_time, "forget_time_s", Unit::kSecond, 0.1, 60,
          "an announced staircase unseen this long is forgotten");
    v.num(repeat_time, "repeat_time_s", Unit::kSecond, 0, 600,
          "the same staircase is announced again after this long");
    v.num(blind_after, "blind_after_s", Unit::kSecond, 0.1, 600,
          "no floor and no stair this long: tell the user it cannot see");
    v.num(blind_repeat, "blind_repeat_s", Unit::kSecond, 1, 3600,
          "while blind, tell it again at this interval");
    v.num(count_interval, "count_interval_steps", Unit::kCount, 1, 100,
          "steps between two spoken counts on a flight");
    v.num(min_tick_interval, "min_tick_interval_s", Unit::kSecond, 0, 5,
          "shortest gap between two step ticks");
    v.num(audio_retry, "audio_retry_s", Unit::kSecond, 0.1, 600,
          "seconds between attempts to open the sound device");
    v.flag(stereo_pan, "stereo_pan",
           "stereo output, each cue placed left or right by the staircase's bearing (false: mono)");
    v.num(approach_range, "approach_range_m", Unit::kMetre, 0, 10,
          "a descending staircase's first edge this near starts the repeating approach beep (0: off)");
    v.num(approach_near, "approach_near_m", Unit::kMetre, 0.1, 5,
          "at and nearer than this the approach beep comes fastest");
    v.num(approach_interval_far, "approach_interval_far_s", Unit::kSecond, 0.1, 10,
          "seconds between two approach beeps at approach_range_m");
    v.num(approach_interval_near, "approach_interval_near_s", Unit::kSecond, 0.1, 10,
          "seconds between two approach beeps at approach_near_m (linear between)");
    v.num(approach_cone, "approach_cone_deg", Unit::kDegree, 5, 90,
          "the edge further off straight ahead than this (turned away) stops the approach beep");
    v.num(approach_stall, "approach_stall_s", Unit::kSecond, 0.2, 60,
          "this long without coming nearer (stopped) stops the approach beep");
    v.text(power_supply_dir, "power_supply_dir", {},
           "sysfs power-supply class read for the battery (its Battery-type entries)");
    v.num(battery_poll, "battery_poll_s", Unit::kSecond, 0.1, 600,
          "seconds between two readings of the battery");
    v.num(battery_low, "battery_low_percent", Unit::kPercent, 1, 100,
          "at or below this charge, not charging: say battery low");
    v.num(battery_critical, "battery_critical_percent", Unit::kPercent, 0, 100,
          "at or below this charge, not charging: say battery critical");
    v.num(battery_repeat, "battery_repeat_s", Unit::kSecond, 10, 36000,
          "say battery low again at this interval while it lasts");
    v.num(battery_critical_repeat, "battery_critical_repeat_s", Unit::kSecond, 5, 3600,
          "say battery critical again at this interval while it lasts");
    v.num(slow_lag, "slow_lag_s", Unit::kSecond, 0.05, 10,
          "capture to decision longer than this: perception is behind the camera");
    v.num(slow_after, "slow_after_s", Unit::kSecond, 0.1, 600, "behind this long: say slow");
    v.num(slow_repeat, "slow_repeat_s", Unit::kSecond, 1, 3600,
          "say slow again at this interval while it lasts");
    v.flag(button_enabled, "button_enabled",
           "read the wearer's push button (short: where are the stairs; long: mute; double: verbosity)");
    v.text(button_chip, "button_chip", {},
           "GPIO chip of the button (name or /dev path; file:PATH reads '<seconds> down|up' lines)");
    v.num(button_line, "button_line", Unit::kCount, 0, 1023, "GPIO line offset of the button");
    v.flag(button_active_low, "button_active_low",
           "pressed when the line is low (a button to ground, the line pulled up)");
    v.num(button_debounce, "button_debounce_s", Unit::kSecond, 0.001, 0.2,
          "a level must hold this long to count (contact bounce)");
    v.num(button_long_press, "button_long_press_s", Unit::kSecond, 0.3, 5,
          "held this long: a long press (mute)");
    v.num(button_double_press, "button_double_press_s", Unit::kSecond, 0.1, 2,
          "pressed again within this of a release: a double press (verbosity)");
    v.num(mute, "mute_s", Unit::kSecond, 1, 7200,
          "a long press mutes the cues this long (a descending staircase still warns)");
    v.text(language, "language", {},
           "language of the spoken cues: sounds_dir/<language>/ (en, es, de, fr; en: sounds_dir itself)");
  }
};

/// The whole pipeline's configuration, as in config/stairguide.yaml.
struct PipelineConfig {
  CaptureConfig capture;
  SegmentationConfig segmentation;
  FloorConfig floor;
  ManhattanConfig manhattan;
  ClassificationConfig classification;
  StairDetectionConfig stair_detection;
  StairModellingConfig stair_modelling;
  TraversalConfig traversal;
  DropConfig drops;
  OdometryConfig odometry;
  RuntimeConfig runtime;
  FeedbackConfig feedback;

  template <class V>
  void visit(V& v) {
    v.section("capture", "camera and recording input", capture);
    v.section("segmentation", "plane segmentation (paper 3.1)", segmentation);
    v.section("floor", "camera-to-floor transform (paper 3.2.1)", floor);
    v.section("manhattan", "floor-to-Manhattan transform (paper 3.2.2)", manhattan);
    v.section("classification", "classification of regions (paper 3.3)", classification);
    v.section("stair_detection", "stair detection (paper 4.1)", stair_detection);
    v.section("stair_modelling", "stair modelling and validation (paper 4.2)", stair_modelling);
    v.section("traversal", "stair traversal: the step the user is on, steps left (paper 5.2)", traversal);
    v.section("drops", "drop-offs: platform edges, docks, holes, sunken floors (issue 42)", drops);
    v.section("odometry", "dense RGB-D visual odometry (paper 5.1)", odometry);
    v.section("runtime", "daemon threads, logging and counters", runtime);
    v.section("feedback", "audio cues and haptic buzzer", feedback);
  }
};

/// One cross-field problem: the two keys involved (as in the file, "floor.tilt_min_deg") and the
/// message naming them.
struct ConfigInconsistency {
  std::string key_a, key_b;
  std::string message;
};

/// Cross-field checks the per-field ranges cannot express (min <= max, min < max for the depth
/// range). Empty when the config is consistent.
std::vector<ConfigInconsistency> find_inconsistencies(const PipelineConfig& c);

/// The messages of find_inconsistencies, one per problem.
std::vector<std::string> check_consistency(const PipelineConfig& c);

/// True when every field of `a` equals the same field of `b` (floats within 1e-6 relative).
/// On a difference, `first_difference` names the key.
bool config_equal(const PipelineConfig& a, const PipelineConfig& b, std::string* first_difference = nullptr);

}  // namespace stairguide
