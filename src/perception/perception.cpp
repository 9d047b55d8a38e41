#include "stairguide/perception/perception.hpp"

#include <chrono>
#include <opencv2/imgproc.hpp>

namespace stairguide {

const char* to_string(RegionClass c) {
  switch (c) {
    case RegionClass::kUnclassified: return "unclassified";
    case RegionClass::kFloor: return "floor";
    case RegionClass::kStepCandidate: return "step_candidate";
    case RegionClass::kObstacle: return "obstacle";
    case RegionClass::kVerticalLeft: return "vertical_left";
    case RegionClass::kVerticalRight: return "vertical_right";
    case RegionClass::kVerticalFront: return "vertical_front";
    case RegionClass::kVertical: return "vertical";
    case RegionClass::kOther: return "other";
  }
  return "unclassified";
}

Perception::Perception(const SegmentationConfig& seg, const FloorConfig& floor, const ManhattanConfig& manhattan,
                       const ClassificationConfig& classification)
    : segmentation_(seg), floor_(floor), manhattan_(manhattan, CaptureConfig{}.max_range),
      classification_(classification) {}

Perception::Perception(const PipelineConfig& c)
    : Perception(c.segmentation, c.floor, c.manhattan, c.classification) {
  // Vertical planes seen at the depth cut-off give the Manhattan frame no direction.
  manhattan_ = ManhattanTracker(c.manhattan, c.capture.max_range);
}

void Perception::reset() {
  floor_.reset();
  manhattan_.reset();
}

namespace {
using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}
}  // namespace

void Perception::process(const RgbdFrame& frame, SceneResult& out) {
  const auto t0 = Clock::now();
  out.floor_found = false;
  out.why.clear();
  out.T_floor_camera = Pose::Identity();
  out.camera_height = out.camera_tilt = out.camera_roll = 0.f;
  out.floor_region = -1;
  out.floor_tracked = false;
  out.remembered_camera_height = 0.f;
  out.frames_since_floor = -1;
  out.manhattan_found = false;
  out.manhattan_why.clear();
  out.T_manhattan_floor = Pose::Identity();
  out.manhattan_yaw = out.manhattan_fraction = 0.f;
  out.timings = {};

  std::string why;
  const bool seg_ok = segmentation_.run(frame, out.regions, out.clusters, &why);
  const auto t1 = Clock::now();
  out.timings.segmentation_ms = std::chrono::duration<double, std::milli>(t1 - t0).count();
  if (!seg_ok) {
    out.why = "segmentation: " + why;
    out.timings.total_ms = ms_since(t0);
    return;
  }

  floor_est_ = floor_.detect(out.regions, frame);
  out.remembered_camera_height = floor_.remembered_height();
  out.frames_since_floor = floor_.frames_since_floor();
  const auto t2 = Clock::now();
  out.timings.floor_ms = std::chrono::duration<double, std::milli>(t2 - t1).count();
  if (floor_est_.found) {
    out.floor_found = true;
    out.T_floor_camera = floor_est_.T_floor_camera;
    out.camera_height = floor_est_.height;
    out.camera_tilt = floor_est_.tilt;
    out.camera_roll = floor_est_.roll;
    out.floor_region = floor_est_.region;
    out.floor_tracked = floor_est_.tracked;
    const ManhattanEstimate m = manhattan_.estimate(out.regions, out.T_floor_camera);
    out.manhattan_found = m.found;
    out.manhattan_fraction = m.fraction;
    out.manhattan_why = m.why;
    if (m.found) {
      out.manhattan_yaw = m.yaw;
      out.T_manhattan_floor = m.T_manhattan_floor;
    }
  } else {
    out.why = "no floor: " + floor_est_.why;
    out.manhattan_why = "no floor";
  }
  const auto t3 = Clock::now();
  out.timings.manhattan_ms = std::chrono::duration<double, std::milli>(t3 - t2).count();
  classify_regions(out, classification_);
  out.timings.classification_ms = ms_since(t3);
  out.timings.total_ms = ms_since(t0);
}

cv::Vec3b region_class_color(RegionClass c) {
  switch (c) {
    case RegionClass::kFloor: return {0, 200, 0};
    case RegionClass::kStepCandidate: return {255, 80, 0};
    case RegionClass::kObstacle:
    case RegionClass::kOther: return {0, 0, 230};
    case RegionClass::kVerticalLeft:
    case RegionClass::kVerticalRight:
    case RegionClass::kVerticalFront:
    case RegionClass::kVertical: return {0, 230, 255};
    case RegionClass::kUnclassified: return {160, 160, 160};
  }
  return {160, 160, 160};
}

cv::Mat draw_classification(const cv::Mat& base, const cv::Mat& depth, const SceneResult& scene,
                            const std::vector<int>& labels, float alpha) {
  const int H = depth.rows, W = depth.cols;
  cv::Mat img;
  if (base.type() == CV_8UC3 && base.rows == H && base.cols == W) {
    img = base.clone();
  } else if (base.type() == CV_8UC1 && base.rows == H && base.cols == W) {
    cv::cvtColor(base, img, cv::COLOR_GRAY2BGR);
  } else {
    // No usable image: shade the depth (near bright, far dark).
    img.create(H, W, CV_8UC3);
    for (int v = 0; v < H; ++v)
      for (int u = 0; u < W; ++u) {
        const float z = depth.at<float>(v, u);
        const int g = z > 0.f ? std::max(30, std::min(255, static_cast<int>(255.f - 45.f * z))) : 0;
        img.at<cv::Vec3b>(v, u) = cv::Vec3b(static_cast<uchar>(g), static_cast<uchar>(g), static_cast<uchar>(g));
      }
  }
  if (static_cast<int>(labels.size()) != H * W) return img;
  for (int v = 0; v < H; ++v) {
    for (int u = 0; u < W; ++u) {
      const int l = labels[static_cast<std::size_t>(v) * W + u];
      cv::Vec3b col;
      if (l >= 0 && l < static_cast<int>(scene.regions.size())) col = region_class_color(scene.regions[l].cls);
      else if (l <= -2) col = region_class_color(RegionClass::kObstacle);
      else continue;
      cv::Vec3b& px = img.at<cv::Vec3b>(v, u);
      for (int k = 0; k < 3; ++k)
        px[k] = static_cast<uchar>((1.f - alpha) * static_cast<float>(px[k]) + alpha * static_cast<float>(col[k]));
    }
  }
  return img;
}

}  // namespace stairguide
