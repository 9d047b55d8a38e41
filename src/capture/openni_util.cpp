#include "openni_util.hpp"

#include <cmath>
#include <mutex>
#include <opencv2/imgproc.hpp>

#include "capture_util.hpp"

namespace stairguide {

std::string ensure_openni() {
  static std::once_flag once;
  static std::string error;
  std::call_once(once, [] {
    if (openni::OpenNI::initialize() != openni::STATUS_OK)
      error = openni_error("OpenNI2 initialisation failed");
  });
  return error;
}

std::string openni_error(const char* fallback) {
  std::string e = trim(openni::OpenNI::getExtendedError());
  return e.empty() ? std::string(fallback) : e;
}

CameraIntrinsics intrinsics_from_fov(int w, int h, float hfov, float vfov) {
  CameraIntrinsics k;
  k.width = w;
  k.height = h;
  k.fx = static_cast<float>(w / (2.0 * std::tan(hfov / 2.0)));
  k.fy = static_cast<float>(h / (2.0 * std::tan(vfov / 2.0)));
  k.cx = (static_cast<float>(w) - 1.f) / 2.f;
  k.cy = (static_cast<float>(h) - 1.f) / 2.f;
  return k;
}

CameraIntrinsics default_intrinsics(int w, int h) {
  CameraIntrinsics k = CameraIntrinsics{}.scaled(static_cast<float>(w) / 640.f);
  k.width = w;
  k.height = h;
  k.fy = CameraIntrinsics{}.fy * static_cast<float>(h) / 480.f;
  k.cy = (CameraIntrinsics{}.cy + 0.5f) * static_cast<float>(h) / 480.f - 0.5f;
  return k;
}

bool depth_frame_to_metres(const openni::VideoFrameRef& f, cv::Mat& out) {
  const auto fmt = f.getVideoMode().getPixelFormat();
  double scale = 0.0;
  if (fmt == openni::PIXEL_FORMAT_DEPTH_1_MM)
    scale = 1e-3;
  else if (fmt == openni::PIXEL_FORMAT_DEPTH_100_UM)
    scale = 1e-4;
  else
    return false;
  const cv::Mat raw(f.getHeight(), f.getWidth(), CV_16UC1, const_cast<void*>(f.getData()),
                    static_cast<std::size_t>(f.getStrideInBytes()));
  raw.convertTo(out, CV_32F, scale);
  return true;
}

bool color_frame_to_bgr(const openni::VideoFrameRef& f, cv::Mat& out) {
  const auto fmt = f.getVideoMode().getPixelFormat();
  void* data = const_cast<void*>(f.getData());
  const auto stride = static_cast<std::size_t>(f.getStrideInBytes());
  if (fmt == openni::PIXEL_FORMAT_RGB888) {
    cv::cvtColor(cv::Mat(f.getHeight(), f.getWidth(), CV_8UC3, data, stride), out, cv::COLOR_RGB2BGR);
    return true;
  }
  if (fmt == openni::PIXEL_FORMAT_GRAY8) {
    cv::cvtColor(cv::Mat(f.getHeight(), f.getWidth(), CV_8UC1, data, stride), out, cv::COLOR_GRAY2BGR);
    return true;
  }
  return false;
}

}  // namespace stairguide
