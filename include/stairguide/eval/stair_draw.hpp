#pragma once
/// \file stair_draw.hpp
/// Draws a stair model over an image, as in the paper's Fig. 13: each level's points tinted in
/// order (blue, green, red ...), the model's treads and risers as wireframe boxes for the levels
/// seen, the first edge thick with its two ends marked, and a caption with kind and dimensions.

#include <opencv2/core.hpp>

#include "stairguide/core/types.hpp"
#include "stairguide/stairs/stair_result.hpp"

namespace stairguide {

/// Draws `result` over `image` (CV_8UC3, modified in place) seen through `K`. A result that was
/// not detected gets only its caption (the reason).
void draw_stair_model(cv::Mat& image, const CameraIntrinsics& K, const StairResult& result);

}  // namespace stairguide
