#pragma once
/// \file floorless.hpp
/// Stairs found when perception saw no floor (issue #4; paper 4.1, and the vertical of 5.2: "all
/// step planes are used to compute the resulting normal as we can certainly say they are
/// horizontal planes").
///
/// Standing at the foot of a staircase looking at the steps, on the staircase itself, or with the
/// camera held level, the floor is out of view or outside the floor detector's chest-camera rules,
/// so no height above the floor exists. This route takes the vertical from the horizontal planes
/// themselves:
///
///  1. *Up*: every planar region whose normal (facing the camera) is plausible as "up" for a
///     body-worn camera: roll within FloorConfig::roll_max, and the camera pitched between
///     `floorless_tilt_min` (about level: a hand-held or level view, and the wobble of a chest
///     camera while walking) and `floorless_tilt_max` (steeply down: the steps right in front of the
///     feet). A ceiling or the underside of a board faces down (roll about 180 deg) and a wall
///     ahead of a level camera lies at 90 deg pitch: neither passes. The largest family of
///     parallel such planes (by pixels, within ClassificationConfig::parallel_threshold) gives the
///     vertical, refitted to all of its points (each region centred on its own mean).
///  2. *Levels*: the family's regions grouped by height (within `same_level_tolerance`) and by
///     connectivity (Algorithm 1's test: `connection_min_points` within `connection_radius`);
///     levels smaller than `floorless_min_level_pixels` are dropped.
///  3. *Stack*: the longest chain of levels each one riser (H_min..H_max with `height_tolerance`)
///     above the previous and connected to it; at least `floorless_min_levels`.
///  4. *Direction*: ascending when the levels rise away from the camera (the near boundary of each
///     higher level lies farther from the camera's vertical), descending when they rise towards
///     it; a stack that does neither is no staircase.
///  5. *Model*: the existing modelling (stair_modelling.hpp) on a pseudo floor frame built from the
///     common normal, with a virtual level 0 one riser beyond the first seen level (below the
///     lowest when ascending, above the highest when descending), so every seen level is a step
///     with its own edge. Its building-code validation applies unchanged. Where the first seen
///     level's edge is cut by the image border, its edge is not used: the tread then comes from the
///     risers facing the user and the other edges, or stays unknown (0) when fewer than two edges
///     are seen.
///
/// *Remembered floor* (SceneResult::remembered_camera_height > 0: the floor was seen a moment ago
/// and the camera's height above the user's feet is known): the feet lie that far below the camera
/// along `up`, so each level's height is absolute. The first level seen (in stair order: the lowest
/// ascending, the highest descending) must lie a whole number k of risers from the feet, within
/// `floorless_anchor_tolerance`: k = 0 is the floor itself (level 0, its regions seen), k = 1 the
/// first step, 2..1+`floorless_max_hidden_steps` a first level with the steps before it out of view
/// (under the camera, at the feet), their edges placed one fitted tread apart before the first seen
/// edge (the tread must then be measured). Any other stack is no staircase (kNoFirstStep). The
/// result is a normal detection (`without_floor` false, `floor_remembered` set): heights from the
/// floor, the origin on the first step's edge, the distance known.
///
/// *At the first edge* (the "lean"): the remembered height is the camera's over the feet of a user
/// walking on the level. Stepping onto the next level, the chest moves towards it (up a climb,
/// down a descent) before the foot leaves the floor, by up to half a riser when the foot reaches
/// the edge; and a chest camera hangs ahead of the feet, over the first tread, so one more step is
/// out of view (two going down, where the deeper levels are reached farther ahead by the view's
/// lowest rays). A first level k risers from the feet less a lean beyond the tolerance (at most
/// half a riser plus half the tolerance), or those steps more than `floorless_max_hidden_steps`
/// out of view, is taken only when the model puts the first edge at the camera's vertical (at
/// most 0.35 m ahead, 0.2 m behind): the user stands at the edge. Elsewhere such a stack is
/// refused as before (a lean the other way, the chest lowered at the foot of a climb by half a
/// riser or more, would be read as a lean onto the next step: one step off). In
/// the approach walks this keeps the staircase through the last 5-8 frames before the first step
/// (the top of a descent, where perception no longer verifies the floor either, and the foot of a
/// climb), first edge within a few mm.
///
/// *Cold start* (nothing remembered). A level outside the stack that can be the user's floor (a
/// chest camera's height below the camera, FloorConfig height range, and 1..1 +
/// `floorless_max_hidden_steps` risers from the first seen level on the user's side; the floor
/// perception refused, e.g. at the top of a descent whose first treads are self-occluded) anchors
/// the stack as a remembered height does (`without_floor` false, trace `floor_seen`). At the top of
/// a descent the floor around the stairwell joins the first tread seen at the walls' feet and tops
/// the stack, while the floor under the user is out of view: a top level whose nearest points lie
/// farther from the camera's vertical than the level one riser below it (no tread of the flight
/// ahead does), with every lower pair descending (two at least) and a chest camera's height below
/// the camera, is taken out of the stack as that floor (trace `floor_beside`), and the rule above
/// applies. Otherwise
/// the result has `without_floor` set: heights are relative to the first seen level, and the
/// distance from the user's feet and the first seen level's step number are unknown. The first
/// level seen whose near boundary the image border cuts may be the floor the user stands on (the
/// floor detector refused it) or the first step seen from above. It is the floor (level 0) when
/// deeper than the fitted tread plus slack (a flight's treads are all one depth; from a camera
/// held level, also deeper than a landing), or when, seen at a chest camera's pitch (FloorConfig
/// tilt range), a first tread there would put the user's floor outside a chest camera's height
/// range. It is a step when the camera is outside that range above it. Otherwise nothing says
/// which, and no staircase is reported (kNoFirstStep) rather than one step off. A first level
/// whose near boundary is in view is a step. Two levels seen cold going down, with an upright face
/// between their heights (a riser facing the user: the step rises away), are refused
/// (kNoFloor, trace `riser_against`): their one pair's direction followed where the
/// view's border cuts an oblique edge.
///
/// Pure: no I/O, no exceptions; buffers are kept between frames.

#include <Eigen/Core>
#include <vector>

#include "stairguide/core/config.hpp"
#include "stairguide/core/types.hpp"
#include "stairguide/perception/scene.hpp"
#include "stairguide/stairs/stair_detection.hpp"
#include "stairguide/stairs/stair_modelling.hpp"
#include "stairguide/stairs/stair_result.hpp"

namespace stairguide {

/// What the floorless route saw in the last frame (for tests and the CLI).
struct FloorlessTrace {
  bool up_found = false;                         ///< a plausible family of horizontal planes was found
  Eigen::Vector3f up = Eigen::Vector3f::Zero();  ///< camera frame, unit, pointing up
  float tilt = 0.f, roll = 0.f;  ///< rad, camera pitch below horizontal and roll implied by `up`
  int family_regions = 0;        ///< regions in the family
  int levels = 0;                ///< levels (height x connectivity groups) of the family
  int stacked = 0;               ///< levels in the longest stack one riser apart
  int direction = 0;             ///< +1 ascending, -1 descending, 0 undecided
  bool floor_level = false;      ///< the first seen level was taken for the floor (level 0)
  bool anchored = false;         ///< levels placed from the feet (camera height remembered or floor seen)
  bool floor_seen = false;  ///< cold start: the user's floor seen outside the stack gave the camera height
  /// The stack's top level was the floor around a stairwell (farther than the first tread below it,
  /// a chest camera's height below the camera): taken out of the stack, descending (see the file comment).
  bool floor_beside = false;
  bool landing_split = false;  ///< the stack was split at the landing the user stands on (split_at_landing)
  /// Cold, two levels going down with an upright face between their heights (a riser facing the
  /// user): the direction is contradicted and nothing is reported.
  bool riser_against = false;
  int first_index = -1;  ///< steps from the feet to the first seen level (anchored), -1 unknown
  float first_offset =
      0.f;  ///< m, first seen level's height beyond the feet (anchored; up ascending, down descending)
  /// m, anchored: how far the chest had moved towards the flight (first_index risers less
  /// first_offset) when that is more than the anchor tolerance (the user stepping onto it); 0 otherwise.
  float lean = 0.f;
  float lean_edge_ahead = 0.f;  ///< m, with a lean or the extra hidden steps: the first edge's distance ahead
                                ///< of the camera's vertical
  bool first_near_cut = false;  ///< the first seen level's near boundary lies on the image border
  float first_depth =
      0.f;  ///< m, cold start: depth seen of that level (a floor strip deeper than a tread is the floor)
  int edges_seen = 0;                ///< step edges seen inside the image (tread edges or risers)
  std::vector<float> level_heights;  ///< m, up . p of each stacked level, lowest first
  std::vector<float>
      near_distances;  ///< m, each stacked level's near boundary from the camera's vertical, lowest first
};

/// The floorless route. Pure: no I/O, no exceptions; buffers are kept between frames.
class FloorlessStairs {
 public:
  FloorlessStairs(const ClassificationConfig& classification, const StairDetectionConfig& detection,
                  const StairModellingConfig& modelling, const FloorConfig& floor);

  /// Looks for a staircase in a frame without floor (scene.floor_found is not read: the caller
  /// decides when to run it). Fills every field of `out` except the timings; `out.detected` says
  /// whether a validated staircase was found, `out.without_floor` is always set. A frame with no
  /// stack of levels gets verdict kNoFloor.
  void run(const SceneResult& scene, const CameraIntrinsics* K, StairResult& out);

  /// What the last run saw.
  const FloorlessTrace& trace() const { return trace_; }

 private:
  struct Node {
    std::vector<int> regions;  ///< indices into the input scene
    float height = 0.f;        ///< m, up . p, pixel-weighted
    int pixels = 0;
    std::vector<Eigen::Vector3f> sample;  ///< evenly subsampled points of all its regions
    Eigen::Vector3f lo, hi;               ///< bounding box of the sample
    int stride = 1;                       ///< points per sample point (largest over its regions)
  };

  /// The stack's direction and size after the direction phase.
  /// With no one direction: the stack split at the landing the user stands on (the nearest level,
  /// flights rising and falling away from it); the kept flight's direction, 0 when it is no landing.
  int split_at_landing();
  struct StackDirection {
    int dir = 0;  ///< +1 ascending, -1 descending, 0 undecided (no staircase)
    int n = 0;    ///< stacked levels (the floor beside a stairwell taken out)
  };
  /// The stack's heights fitted against the stair index.
  struct StackFit {
    float level0 = 0.f;  ///< up . p of the virtual level 0 (camera frame), m
    float riser = 0.f;   ///< m
  };

  // ---- phases (run's order; see the file comment's steps) ----
  /// Up (floorless_up.cpp, step 1): the vertical from the largest family of plausible horizontal
  /// planes; false when there is none.
  bool find_up(const SceneResult& scene);
  /// Levels (floorless_stack.cpp, step 2): the family grouped by height and connectivity into
  /// nodes_, ordered by height in order_.
  void build_nodes(const SceneResult& scene);
  /// Stack (step 3): the longest chain of levels one riser apart, each connected to the one below
  /// and rising by the same riser, into chain_ (lowest first); trace_.stacked, level_heights.
  void build_stack();
  /// Direction (step 4): every pair of levels must rise away from the camera (ascending) or
  /// towards it (descending), one tie allowed. At the top of a descent seen cold, a top level a
  /// chest camera's height below the camera and farther than the tread below it is the floor
  /// beside the stairwell: taken out of the stack (trace_.floor_beside), descending.
  StackDirection stack_direction();
  /// Model (step 5): chain_ in stair order, its heights fitted against the index; the virtual
  /// level 0 sits where that line meets index 0, so it adds nothing to modelling's riser fit.
  StackFit fit_stack_heights(int dir, int n);
  /// Cold start (floorless_cold.cpp): nothing remembered. The user's floor seen outside the stack
  /// anchors it (run_anchored); two levels going down against a riser facing the user are refused;
  /// otherwise the stack is modelled and decide_first_level says what its first level is.
  void run_cold(const SceneResult& scene, const CameraIntrinsics* K, int dir, int n, const StackFit& fit,
                StairResult& out);
  /// Cold start, the first seen level cut by the image border at its near side: the floor (deeper
  /// than the tread plus slack, or where a first tread would put the user's floor outside a chest
  /// camera's height range), a step (the camera outside that range above it), or, from a wearer's
  /// rig, modelled on it as the floor with its count unknown (`without_floor`); else kNoFirstStep.
  void decide_first_level(const SceneResult& scene, const CameraIntrinsics* K, int dir, StairResult& out);

  // ---- helpers ----
  void add_to_node(const SceneResult& scene, int region, Node& node) const;
  /// Merges the nodes first..used-1 of one height cluster while any two are connected; returns
  /// the new end of the used nodes.
  std::size_t merge_connected_nodes(std::size_t first, std::size_t used);
  bool connected(const Node& a, const Node& b) const;
  float near_distance(const Node& n);
  /// Positions along z_S of the risers facing the user, by band (k: between levels k-1 and k;
  /// n+1: above the top level), from the input scene; NaN where none.
  void riser_positions(const SceneResult& scene, const StairResult& r, int n, float level0_plane);
  /// Pseudo floor frame at `level0`, steps chain_[first..], modelling, edges refined.
  void model(const SceneResult& scene, const CameraIntrinsics* K, int dir, int first, float level0,
             StairResult& out);
  /// True when most of level k's edge line (at height y in the stair frame) lies on the image border.
  bool edge_cut(const CameraIntrinsics& K, const StairResult& r, int k, float y) const;
  /// The same for the line across level k at `z` along z_S.
  bool line_cut(const CameraIntrinsics& K, const StairResult& r, int k, float y, float z) const;
  /// Anchoring (floorless_anchor.cpp): the stack placed from the floor `camera_height` below the
  /// camera (remembered or seen; see the file comment); `level0` is the stack's fitted level 0.
  void run_anchored(const SceneResult& scene, const CameraIntrinsics* K, int dir, float riser, float level0,
                    float camera_height, StairResult& out);
  /// True when an upright region of the input scene stands between heights h_lo < h_hi (up . p,
  /// camera frame): a riser facing the user.
  bool riser_between(const SceneResult& scene, float h_lo, float h_hi);
  /// The first stacked level is the user's floor (level 0): models the steps above it, or refuses
  /// (kNoFloor, false) when only one level stands on it (the single-level case needs the floor).
  bool model_on_floor_level(const SceneResult& scene, const CameraIntrinsics* K, int dir, StairResult& out);
  /// Cold start: the camera height above a level outside the stack that can be the user's floor
  /// (a chest camera's height below, 1..1+max hidden risers from the first seen level on the
  /// user's side; the biggest such), 0 when there is none.
  float seen_floor_height(int dir, float riser) const;
  /// Moves a model whose first level is step `hidden + 1` (steps 1..hidden out of view) so that its
  /// origin, heights and indices count from the floor.
  static void add_hidden_steps(StairResult& out, int dir, int hidden);
  /// Tread and origin from the edges seen inside the image and the risers; validation again.
  void refine_edges(const SceneResult& scene, const CameraIntrinsics* K, int dir, int n, StairResult& out);
  /// The step edges seen inside the image (k, position along z_S) into edge_k_, edge_e_: a riser
  /// facing the user (plus the nosing measured where both agree) or a tread edge not on the image
  /// border (trace_.edges_seen).
  void collect_seen_edges(const SceneResult& scene, const CameraIntrinsics* K, int dir, int n,
                          StairResult& out);
  /// Tread from the seen edges by consensus (out.tread_m) and the origin's `shift` along z_S;
  /// false, with kInconsistentEdges, when fewer than two thirds of the edges agree.
  bool fit_seen_edges(int dir, StairResult& out, float& shift) const;
  /// Moves the origin `shift` along z_S, and the levels' edges and extents with it.
  static void shift_origin(int n, float shift, StairResult& out);

  ClassificationConfig cls_;
  StairDetectionConfig det_;
  StairModellingConfig mod_;
  FloorConfig floor_;
  StairModelling modelling_;
  FloorlessTrace trace_;

  std::vector<int> cand_;      ///< regions plausible as horizontal
  std::vector<int> family_;    ///< regions of the family
  std::vector<float> height_;  ///< per family member
  std::vector<Node> nodes_;
  std::vector<int> order_, best_len_, best_prev_, chain_;
  std::vector<long> best_pix_;
  std::vector<float> dist_, tmp_, riser_pos_, edge_k_, edge_e_;
  std::vector<int> riser_n_;
  std::vector<int> index_map_;  ///< pseudo-scene region -> input region
  float level0_ = 0.f;          ///< up . p of the virtual level 0 (camera frame), m
  SceneResult pseudo_;          ///< the pseudo floor frame and the regions modelling needs
  StairHypothesis hyp_;
};

}  // namespace stairguide
