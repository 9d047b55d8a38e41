#pragma once
/// \file manhattan_frame.hpp
/// Floor-to-Manhattan transform (paper 3.2.2). j_M is the floor's up direction; i_M and k_M are
/// the two orthogonal horizontal directions that the vertical planes' normals agree with most
/// (vote modulo 90 degrees weighted by area * (width / yaw_full_width)^2, the precision of a plane's
/// yaw, refined by a circular mean of the votes near the peak; no frame when no agreeing plane is
/// min_plane_width wide and the agreeing votes spread more than max_spread or hold no two
/// parallel planes, e.g. only people and posts in view).
/// k_M is the one nearest the user's forward direction z_F; across frames the branch nearest the
/// previous k_M is kept when the choice is ambiguous (near +-45 degrees).

#include <optional>
#include <string>
#include <vector>

#include "stairguide/core/config.hpp"
#include "stairguide/core/types.hpp"
#include "stairguide/perception/scene.hpp"

namespace stairguide {

struct ManhattanEstimate {
  bool found = false;
  std::string why;
  float yaw = 0.f;       ///< rad, k_M from z_F about y_F (positive towards x_F, the left)
  float fraction = 0.f;  ///< share of planar area on vertical planes agreeing with the frame
  float vertical_area = 0.f;  ///< m^2 of agreeing vertical planes
  Pose T_manhattan_floor = Pose::Identity();
};

/// Rotation about y_F by -yaw: maps floor coordinates into Manhattan coordinates.
Pose manhattan_pose_from_yaw(float yaw);

class ManhattanTracker {
 public:
  explicit ManhattanTracker(const ManhattanConfig& config = {});

  /// Estimates the Manhattan frame from the vertical planes among `regions`, given the floor.
  ManhattanEstimate estimate(const std::vector<PlaneRegion>& regions, const Pose& T_floor_camera);
  void reset() { prev_yaw_.reset(); }

 private:
  ManhattanConfig cfg_;
  std::optional<float> prev_yaw_;
  std::vector<float> headings_;  // scratch: agreeing planes' headings
};

}  // namespace stairguide
