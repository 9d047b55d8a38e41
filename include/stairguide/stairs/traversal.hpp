#pragma once
/// \file traversal.hpp
/// Odometry-aided stair traversal (paper 5.2, the paper's ST): the staircase a detection found is
/// held in the odometry's world (eq. 14) while the user walks onto it and its first edge leaves
/// the view, corrected frame by frame from what the live view sees of it (eq. 15: the vertical
/// from the tread normals, the yaw from the step edges, the height from the tread centroids, the
/// along-stair offset from the edges in sight; across the stair the odometry is trusted). The body
/// centre located in that stair frame gives the step the user stands on; the model grows as new
/// steps come into view and learns the last one (a tread much deeper than the going: a landing or
/// the floor beyond).
///
///   TraversalTracker tracker(config.traversal);    // once
///   // per frame, after perception and the stair stage, with the odometry's pose of the frame:
///   const TraversalResult& t = tracker.update(scene, stair, T_world_camera, trusted, timestamp);
///   ... t.state, t.step_index, t.steps_left, t.last_known ...
///
/// Pure: no I/O, no threads, no exceptions; a few hundred floating-point operations per level.
///
/// Stair frame S as in stair_result.hpp: tread j (1 = first step, N = the landing or floor after
/// the last riser) spans z_S in [(j-1) t, j t) (the last one has no end); ascending its surface is
/// at y_S = (j-1) r, descending at y_S = -j r. The step the user stands on is j for the body centre
/// at z_S in that span (0 before the first edge), as the synthetic ground truth counts it.

#include <cstdint>
#include <utility>
#include <vector>

#include "stairguide/core/config.hpp"
#include "stairguide/core/types.hpp"
#include "stairguide/perception/scene.hpp"
#include "stairguide/stairs/stair_result.hpp"
#include "stairguide/stairs/traversal_result.hpp"

namespace stairguide {

class TraversalTracker {
 public:
  explicit TraversalTracker(const TraversalConfig& config = {});

  /// One frame: perception's scene, the stair stage's result on it, and the odometry's pose of the
  /// same frame. `pose_trusted` false (the odometry failed or has no pose for the frame yet): the
  /// camera is taken to be where it was on the last frame and the live view alone corrects the
  /// staircase. `track` changes whenever the odometry's world is a new one (tracking restarted):
  /// the staircase is carried into it through the last camera pose.
  const TraversalResult& update(const SceneResult& scene, const StairResult& stair,
                                const Pose& T_world_camera, bool pose_trusted, double timestamp,
                                std::uint64_t track = 0);

  /// Forgets the staircase (and the memory): searching from nothing.
  void reset();
  /// New values from a reloaded config, from the next frame on; the staircase held, the count and
  /// the memory are kept (a reload on the flight must not lose the user's step).
  void reconfigure(const TraversalConfig& config) { cfg_ = config; }
  const TraversalResult& result() const { return out_; }
  /// The staircase held (tracked or remembered).
  bool holding() const { return model_.valid; }

 private:
  struct Model {
    bool valid = false;
    int direction = 0;
    StairKind kind = StairKind::kNone;
    Pose T_world_stair = Pose::Identity();
    float riser = 0.f, tread = 0.f, width = 0.f;
    double w_riser = 0, w_tread = 0, w_width = 0;  // accumulated weights of the fused values
    double sum_riser = 0, sum_tread = 0, sum_width = 0;
    float width_partial = 0.f;  // widest seen without both ends
    int steps_known = 0;
    bool last_known = false;
    int last_step = 0;  // N: the landing / floor beyond (valid when last_known)
    double first_seen = 0, last_seen = 0;
    int hits = 0;
    double weight = 0;  // total quality seen
  };
  // One seen level, in the model's frame after association.
  struct SeenLevel {
    Eigen::Vector3f centroid_w;  // world
    Eigen::Vector3f edge_w;      // world, a point of its step edge (valid: has_edge)
    bool has_edge = false;
    bool landing = false;
    int points = 0;
  };

  float tread_of(const Model& m) const;
  void gather(const StairResult& stair, const Pose& T_world_camera);
  bool start_model(Model& m, const StairResult& stair, const Pose& T_world_camera, double t) const;
  /// Matches the seen levels to the steps of `m`; fills match_ and the mean residuals. False when
  /// the detection is not this staircase.
  bool associate(const Model& m, const StairResult& stair, const Pose& T_world_camera);
  void correct(Model& m, float quality, bool apply_pose);
  void fuse_dimensions(Model& m, const StairResult& stair, float quality) const;
  void grow(Model& m) const;
  float frame_quality(const StairResult& stair, const Pose& T_world_camera) const;

  TraversalConfig cfg_;
  TraversalResult out_;
  Model model_, candidate_;
  std::vector<SeenLevel> seen_;
  struct Match {
    int step = 0;
    float dy = 0.f, dz = 0.f;
    bool has_dz = false;
    bool landing = false;
    int seen = 0;  // index into seen_
  };
  std::vector<Match> match_;
  std::vector<float> dz_, dy_;
  std::vector<std::pair<float, int>> near_;  // squared distance to the camera, index into match_
  Eigen::Vector3f det_up_ = Eigen::Vector3f::UnitY(), det_forward_ = Eigen::Vector3f::UnitZ();  // world
  bool remembered_ = false;
  bool floor_seen_ = false,
       origin_level_ = false;  // this frame: the floor found; the origin is a measured edge
  Eigen::Vector3f pivot_ = Eigen::Vector3f::Zero();  // world, what the orientation correction turns about
  Pose T_world_camera_last_ = Pose::Identity();
  bool have_last_ = false;
  std::uint64_t track_ = 0;
  double arrived_at_ = -1.0;
};

}  // namespace stairguide
