#include "stairguide/eval/stair_draw.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/imgproc.hpp>

#include "stairguide/stairs/stair_result.hpp"

namespace stairguide {
namespace {

bool project(const CameraIntrinsics& K, const Eigen::Vector3f& p, cv::Point& out) {
  if (p.z() < 0.05f) return false;
  out = cv::Point(static_cast<int>(std::lround(K.fx * p.x() / p.z() + K.cx)),
                  static_cast<int>(std::lround(K.fy * p.y() / p.z() + K.cy)));
  return true;
}

void segment(cv::Mat& img, const CameraIntrinsics& K, const Eigen::Vector3f& a, const Eigen::Vector3f& b,
             const cv::Scalar& c, int thickness) {
  cv::Point pa, pb;
  if (project(K, a, pa) && project(K, b, pb)) cv::line(img, pa, pb, c, thickness, cv::LINE_AA);
}

cv::Scalar level_colour(int k) {
  static const cv::Scalar c[] = {{255, 80, 0},  {0, 200, 0},   {0, 0, 255},
                                 {255, 0, 255}, {0, 220, 255}, {255, 255, 0}};
  return c[static_cast<std::size_t>(k) % 6];
}

// A legend of the overlay's colours, bottom left: the levels drawn, the first edge and the axes.
void draw_legend(cv::Mat& img, int levels) {
  const int n = std::min(levels, 6);
  const int rows = 3 + (n > 0 ? 1 : 0), h = 18 * rows + 8, w = 250;
  const cv::Rect box(6, img.rows - h - 6, w, h);
  if (box.y < 0 || box.width > img.cols) return;
  cv::rectangle(img, box, {255, 255, 255}, cv::FILLED);
  cv::rectangle(img, box, {0, 0, 0}, 1);
  auto label = [&](int row, const char* s) {
    cv::putText(img, s, {box.x + 60, box.y + 16 + 18 * row}, cv::FONT_HERSHEY_SIMPLEX, 0.42, {0, 0, 0}, 1,
                cv::LINE_AA);
  };
  int row = 0;
  if (n > 0) {
    for (int k = 0; k < n; ++k)
      cv::rectangle(img, cv::Point(box.x + 6 + 8 * k, box.y + 6), cv::Point(box.x + 12 + 8 * k, box.y + 16),
                    level_colour(k), cv::FILLED);
    label(row++, "levels 1, 2, 3 ... (points, boxes)");
  }
  const int y1 = box.y + 12 + 18 * row;
  cv::line(img, {box.x + 6, y1}, {box.x + 50, y1}, {0, 0, 0}, 2);
  cv::circle(img, {box.x + 50, y1}, 4, {0, 255, 255}, 2, cv::LINE_AA);
  label(row++, "first edge and its ends");
  const int y2 = box.y + 12 + 18 * row;
  cv::line(img, {box.x + 6, y2}, {box.x + 20, y2}, {0, 0, 255}, 2);
  cv::line(img, {box.x + 21, y2}, {box.x + 35, y2}, {0, 255, 0}, 2);
  cv::line(img, {box.x + 36, y2}, {box.x + 50, y2}, {255, 0, 0}, 2);
  label(row++, "stair axes x (edge), y (up), z (in)");
  label(row++, "colours: red, green, blue");
}

}  // namespace

void draw_stair_model(cv::Mat& img, const CameraIntrinsics& K, const StairResult& r) {
  if (img.empty() || img.type() != CV_8UC3) return;
  char caption[256];
  if (!r.detected) {
    std::snprintf(caption, sizeof caption, "no stair: %s", to_string(r.verdict));
    cv::putText(img, caption, {10, 24}, cv::FONT_HERSHEY_SIMPLEX, 0.6, {0, 0, 0}, 3, cv::LINE_AA);
    cv::putText(img, caption, {10, 24}, cv::FONT_HERSHEY_SIMPLEX, 0.6, {255, 255, 255}, 1, cv::LINE_AA);
    return;
  }
  // Level points, tinted in order.
  for (std::size_t k = 1; k < r.level_data.size(); ++k) {
    const cv::Scalar c = level_colour(static_cast<int>(k) - 1);
    const auto& pts = r.level_data[k].points;
    const std::size_t stride = std::max<std::size_t>(1, pts.size() / 3000);
    for (std::size_t i = 0; i < pts.size(); i += stride) {
      cv::Point p;
      if (project(K, pts[i], p) && p.x >= 0 && p.y >= 0 && p.x < img.cols && p.y < img.rows) {
        cv::Vec3b& px = img.at<cv::Vec3b>(p);
        for (int ch = 0; ch < 3; ++ch) px[ch] = static_cast<uchar>(0.5 * px[ch] + 0.5 * c[ch]);
      }
    }
  }
  // The model: for each level seen, its tread rectangle and the riser below it (in the stair
  // frame: x along the edge, y up, z into the staircase).
  const Pose& T = r.T_camera_stair;
  const float hw = 0.5f * r.width_m;
  const int dir =
      r.kind == StairKind::kDescending || (r.level_data.size() > 1 && r.level_data[1].height < 0.f) ? -1 : 1;
  const float tread = r.tread_m > 0.f ? r.tread_m : 0.3f;
  auto S = [&](float x, float y, float z) { return Eigen::Vector3f(T * Eigen::Vector3f(x, y, z)); };
  for (int k = 1; k <= r.levels; ++k) {
    const cv::Scalar c = level_colour(k - 1);
    // Ascending: tread k at y = (k-1)R from z = (k-1)T; descending: tread k at y = -kR from (k-1)T.
    const float y = dir > 0 ? static_cast<float>(k - 1) * r.riser_m : -static_cast<float>(k) * r.riser_m;
    const float y_prev = dir > 0 ? y - r.riser_m : y + r.riser_m;
    const float z0 = static_cast<float>(k - 1) * tread, z1 = z0 + tread;
    segment(img, K, S(-hw, y, z0), S(hw, y, z0), c, 2);
    segment(img, K, S(-hw, y, z1), S(hw, y, z1), c, 1);
    segment(img, K, S(-hw, y, z0), S(-hw, y, z1), c, 1);
    segment(img, K, S(hw, y, z0), S(hw, y, z1), c, 1);
    // Riser from the previous level to this one, at z0.
    segment(img, K, S(-hw, y_prev, z0), S(-hw, y, z0), c, 1);
    segment(img, K, S(hw, y_prev, z0), S(hw, y, z0), c, 1);
    segment(img, K, S(-hw, y_prev, z0), S(hw, y_prev, z0), c, 1);
  }
  // First edge, thick, with its ends and the stair axes at the origin.
  segment(img, K, r.edge_left, r.edge_right, {255, 255, 255}, 4);
  segment(img, K, r.edge_left, r.edge_right, {0, 0, 0}, 2);
  for (const auto& e : {r.edge_left, r.edge_right}) {
    cv::Point p;
    if (project(K, e, p)) cv::circle(img, p, 6, {0, 255, 255}, 2, cv::LINE_AA);
  }
  segment(img, K, S(0, 0, 0), S(0.25f, 0, 0), {0, 0, 255}, 2);
  segment(img, K, S(0, 0, 0), S(0, 0.25f, 0), {0, 255, 0}, 2);
  segment(img, K, S(0, 0, 0), S(0, 0, 0.25f), {255, 0, 0}, 2);
  std::snprintf(caption, sizeof caption, "%s, %d levels: riser %.1f cm, tread %.1f cm, width %.0f cm (%s)",
                to_string(r.kind), r.levels, 100.f * r.riser_m, 100.f * r.tread_m, 100.f * r.width_m,
                to_string(r.method));
  cv::putText(img, caption, {10, 24}, cv::FONT_HERSHEY_SIMPLEX, 0.55, {0, 0, 0}, 3, cv::LINE_AA);
  cv::putText(img, caption, {10, 24}, cv::FONT_HERSHEY_SIMPLEX, 0.55, {255, 255, 255}, 1, cv::LINE_AA);
  draw_legend(img, r.levels);
}

}  // namespace stairguide
