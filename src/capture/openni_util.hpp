#pragma once
// OpenNI2 helpers shared by the .oni and device sources (private to src/capture).
#include <OpenNI.h>

#include <string>

#include "stairguide/core/types.hpp"

namespace stairguide {

/// Initializes OpenNI2 once per process (never shut down: drivers' threads may outlive sources).
/// Returns an empty string on success, else OpenNI's error text.
std::string ensure_openni();

/// OpenNI's last extended error, trimmed, or `fallback` when it is empty.
std::string openni_error(const char* fallback);

/// Intrinsics from a field of view (radians) for an image of w x h, principal point at the centre.
CameraIntrinsics intrinsics_from_fov(int w, int h, float hfov, float vfov);

/// The 640x480 Kinect defaults (f 525, centre) scaled to w x h.
CameraIntrinsics default_intrinsics(int w, int h);

/// Copies an OpenNI depth frame (DEPTH_1_MM or DEPTH_100_UM) into metres; false for other formats.
bool depth_frame_to_metres(const openni::VideoFrameRef& f, cv::Mat& out);
/// Copies an OpenNI colour frame (RGB888, GRAY8) into BGR; false for other formats.
bool color_frame_to_bgr(const openni::VideoFrameRef& f, cv::Mat& out);

}  // namespace stairguide
