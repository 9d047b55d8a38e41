// `stairguide analyze INPUT [--frame N] [--json] [--png OUT.png]`: perception (paper section 3) on
// one frame: floor, Manhattan frame, every region with its class, and stage timings; --png draws
// the classification in the paper's Fig. 3 f colours.
#include <cmath>
#include <cstdio>
#include <iterator>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <utility>
#include <string>

#include "cli/command.hpp"
#include "cli/write_image.hpp"
#include "cli/open_input.hpp"
#include "stairguide/capture/frame_source.hpp"
#include "stairguide/perception/perception.hpp"

namespace stairguide::cli {
namespace {

// A legend of the region colours (the paper's Fig. 3f), bottom left, so the picture reads alone.
void draw_class_legend(cv::Mat& img) {
  const std::pair<RegionClass, const char*> items[] = {
      {RegionClass::kFloor, "floor"},
      {RegionClass::kStepCandidate, "step candidate (horizontal)"},
      {RegionClass::kVertical, "vertical (wall, riser)"},
      {RegionClass::kObstacle, "obstacle or other"},
      {RegionClass::kUnclassified, "unclassified"}};
  const int n = static_cast<int>(std::size(items)), h = 18 * n + 8, w = 230;
  const cv::Rect box(6, img.rows - h - 6, w, h);
  if (box.y < 0 || box.width > img.cols) return;
  cv::rectangle(img, box, cv::Scalar(255, 255, 255), cv::FILLED);
  cv::rectangle(img, box, cv::Scalar(0, 0, 0), 1);
  for (int i = 0; i < n; ++i) {
    const cv::Vec3b c = region_class_color(items[i].first);
    const int y = box.y + 16 + 18 * i;
    cv::rectangle(img, cv::Point(box.x + 6, y - 10), cv::Point(box.x + 26, y), cv::Scalar(c[0], c[1], c[2]),
                  cv::FILLED);
    cv::putText(img, items[i].second, cv::Point(box.x + 32, y), cv::FONT_HERSHEY_SIMPLEX, 0.42,
                cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  }
}

std::string json_escape(const std::string& s) {
  std::string o;
  for (char c : s) {
    if (c == '"' || c == '\\') o += '\\';
    if (static_cast<unsigned char>(c) < 0x20) {
      o += ' ';
      continue;
    }
    o += c;
  }
  return o;
}

int analyze(Context& ctx) {
  const bool json = ctx.flag("--json");
  const auto png = ctx.option("--png");
  const long index = ctx.int_option("--frame", 0, 100000000).value_or(0);
  const auto pos = ctx.positionals(1, 1);
  const std::string& input = pos[0];

  const std::unique_ptr<FrameSource> source = open_input(input, ctx.config.capture, "stairguide analyze");
  if (!source) return 1;
  if (source->frame_count() >= 0 && index >= source->frame_count()) {
    std::fprintf(stderr, "stairguide analyze: --frame %ld is out of range: %s has %ld frame(s)\n", index,
                 source->describe().c_str(), source->frame_count());
    return 1;
  }
  // Frames before N go through perception too, so that the floor and Manhattan tracking see the
  // same history as in a live run; unless the source's frames are unrelated views.
  Perception perception(ctx.config);
  RgbdFrame frame;
  SceneResult scene;
  const bool independent = source->independent_frames();
  for (long i = 0; i <= index; ++i) {
    const ReadResult r = source->read(frame);
    if (!r.ok()) {
      std::fprintf(stderr, "stairguide analyze: frame %ld of %s: %s\n", i, source->describe().c_str(),
                   r.message.empty() ? "end of input" : r.message.c_str());
      return 1;
    }
    if (!independent || i == index) perception.process(frame, scene);
  }
  const Eigen::Matrix3f Rf = scene.T_floor_camera.linear();
  if (json) {
    std::printf("{\"input\": \"%s\", \"frame\": %ld, \"width\": %d, \"height\": %d, \"floor_found\": %s",
                json_escape(input).c_str(), index, frame.depth.cols, frame.depth.rows,
                scene.floor_found ? "true" : "false");
    if (scene.floor_found)
      std::printf(", \"camera_height_m\": %.4f, \"camera_tilt_deg\": %.3f, \"camera_roll_deg\": %.3f",
                  scene.camera_height, rad2deg(scene.camera_tilt), rad2deg(scene.camera_roll));
    else
      std::printf(", \"why\": \"%s\"", json_escape(scene.why).c_str());
    std::printf(", \"manhattan_found\": %s", scene.manhattan_found ? "true" : "false");
    if (scene.manhattan_found)
      std::printf(
          ", \"manhattan_yaw_deg\": %.3f, \"manhattan_fraction\": %.3f, \"manhattan_without_floor\": %s",
          rad2deg(scene.manhattan_yaw), scene.manhattan_fraction,
          scene.manhattan_without_floor ? "true" : "false");
    else
      std::printf(", \"manhattan_why\": \"%s\"", json_escape(scene.manhattan_why).c_str());
    std::printf(", \"regions\": [");
    for (std::size_t i = 0; i < scene.regions.size(); ++i) {
      const PlaneRegion& r = scene.regions[i];
      const Eigen::Vector3f n = scene.floor_found ? Eigen::Vector3f(Rf * r.normal) : r.normal;
      std::printf(
          "%s{\"id\": %d, \"class\": \"%s\", \"normal\": [%.4f, %.4f, %.4f], \"normal_frame\": \"%s\", "
          "\"height_m\": %s, \"pixels\": %d, \"area_m2\": %.4f, \"length_m\": %.3f, \"width_m\": %.3f, "
          "\"extent\": %.3f, \"curvature\": %.5f, \"centroid_camera\": [%.3f, %.3f, %.3f]}",
          i ? ", " : "", r.id, to_string(r.cls), n.x(), n.y(), n.z(), scene.floor_found ? "floor" : "camera",
          std::isnan(r.height) ? "null" : std::to_string(r.height).c_str(), r.pixel_count, r.area,
          r.rect_length_major, r.rect_length_minor, r.hull_extent, r.curvature, r.centroid.x(),
          r.centroid.y(), r.centroid.z());
    }
    std::printf(
        "], \"clusters\": %zu, \"timings_ms\": {\"segmentation\": %.3f, \"floor\": %.3f, \"manhattan\": "
        "%.3f, "
        "\"classification\": %.3f, \"total\": %.3f}}\n",
        scene.clusters.size(), scene.timings.segmentation_ms, scene.timings.floor_ms,
        scene.timings.manhattan_ms, scene.timings.classification_ms, scene.timings.total_ms);
  } else {
    std::printf("%s, frame %ld (%dx%d)\n", source->describe().c_str(), index, frame.depth.cols,
                frame.depth.rows);
    if (scene.floor_found)
      std::printf("floor: camera height %.3f m, tilt %.2f deg, roll %.2f deg (region %d)\n",
                  scene.camera_height, rad2deg(scene.camera_tilt), rad2deg(scene.camera_roll),
                  scene.floor_region);
    else
      std::printf("floor: not found (%s)\n", scene.why.c_str());
    if (scene.manhattan_found)
      std::printf("manhattan: yaw %.2f deg (%.0f%% of plane area on aligned vertical planes)%s\n",
                  rad2deg(scene.manhattan_yaw), 100.f * scene.manhattan_fraction,
                  scene.manhattan_without_floor
                      ? ", no floor: about the vertical of a floor-like plane refused as the floor"
                      : "");
    else
      std::printf("manhattan: not found (%s)\n", scene.manhattan_why.c_str());
    std::printf("%zu regions, %zu obstacle clusters\n", scene.regions.size(), scene.clusters.size());
    std::printf("  %3s %-15s %-26s %9s %8s %8s %13s\n", "id", "class",
                scene.floor_found ? "normal (floor frame)" : "normal (camera)", "height m", "pixels",
                "area m2", "size m");
    for (const PlaneRegion& r : scene.regions) {
      const Eigen::Vector3f n = scene.floor_found ? Eigen::Vector3f(Rf * r.normal) : r.normal;
      char h[32];
      if (std::isnan(r.height))
        std::snprintf(h, sizeof h, "%9s", "-");
      else
        std::snprintf(h, sizeof h, "%9.3f", r.height);
      std::printf("  %3d %-15s (%7.3f %7.3f %7.3f) %s %8d %8.3f %6.2f x %4.2f\n", r.id, to_string(r.cls),
                  n.x(), n.y(), n.z(), h, r.pixel_count, r.area, r.rect_length_major, r.rect_length_minor);
    }
    std::printf(
        "timings: segmentation %.2f ms, floor %.2f ms, manhattan %.2f ms, classification %.2f ms, total %.2f "
        "ms\n",
        scene.timings.segmentation_ms, scene.timings.floor_ms, scene.timings.manhattan_ms,
        scene.timings.classification_ms, scene.timings.total_ms);
  }
  if (png) {
    const cv::Mat base = !frame.color.empty() ? frame.color : frame.gray;
    cv::Mat img = draw_classification(base, frame.depth, scene, perception.labels());
    draw_class_legend(img);
    if (!write_image(*png, img, "stairguide analyze")) return 1;
  }
  return 0;
}

}  // namespace

SG_COMMAND("analyze", "analyze INPUT [--frame N] [--json] [--png OUT.png]",
           "perception on one frame: floor, Manhattan frame, classified planes, timings", analyze);

}  // namespace stairguide::cli
