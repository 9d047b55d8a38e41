#pragma once
// What the Manhattan tracker's files (manhattan_frame.cpp, manhattan/*.cpp) share. Internal: not a
// public header.
#include "stairguide/perception/manhattan_frame.hpp"

namespace stairguide {
namespace manhattan_detail {
constexpr float kPi = 3.14159265358979f;
constexpr float kHalfPi = 0.5f * kPi;
inline float wrap_quarter(float a) { return manhattan_wrap(a); }
// `e` found at `yaw` (its k_M branch already kept), with `agree` m^2 of vertical planes agreeing.
inline void set_frame(ManhattanEstimate& e, float yaw, float agree, float total_area) {
  e.found = true;
  e.yaw = yaw;
  e.T_manhattan_floor = manhattan_pose_from_yaw(yaw);
  e.vertical_area = agree;
  e.fraction = total_area > 0.f ? agree / total_area : 0.f;
}
}  // namespace manhattan_detail
}  // namespace stairguide
