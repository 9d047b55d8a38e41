#include "stairguide/core/types.hpp"

namespace stairguide {

CameraIntrinsics CameraIntrinsics::scaled(float s) const {
  CameraIntrinsics k = *this;
  k.width = static_cast<int>(static_cast<float>(width) * s + 0.5f);
  k.height = static_cast<int>(static_cast<float>(height) * s + 0.5f);
  k.fx = fx * s;
  k.fy = fy * s;
  // Pixel centres: a pixel at u in the full image sits at (u + 0.5) * s - 0.5 in the scaled one.
  k.cx = (cx + 0.5f) * s - 0.5f;
  k.cy = (cy + 0.5f) * s - 0.5f;
  return k;
}

RgbdFrame RgbdFrame::clone() const {
  RgbdFrame f;
  f.index = index;
  f.timestamp = timestamp;
  f.intrinsics = intrinsics;
  f.depth = depth.clone();
  f.color = color.clone();
  f.gray = gray.clone();
  return f;
}

}  // namespace stairguide
