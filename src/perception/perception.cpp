#include "stairguide/perception/perception.hpp"

#include "manhattan/internal.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
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

Perception::Perception(const SegmentationConfig& seg, const FloorConfig& floor,
                       const ManhattanConfig& manhattan, const ClassificationConfig& classification)
    : segmentation_(seg),
      floor_(floor),
      manhattan_(manhattan, CaptureConfig{}.max_range, seg.depth_noise_coeff),
      classification_(classification),
      manhattan_cfg_(manhattan) {
  EdgeCompassConfig compass;
  compass.line_min_length = manhattan.compass_line_min_length;
  compass_ = EdgeCompass(compass);
}

Perception::Perception(const PipelineConfig& c)
    : Perception(c.segmentation, c.floor, c.manhattan, c.classification) {
  // Vertical planes seen at the depth cut-off give the Manhattan frame no direction.
  manhattan_ = ManhattanTracker(c.manhattan, c.capture.max_range, c.segmentation.depth_noise_coeff);
  max_range_ = c.capture.max_range;
}

void Perception::reset() {
  floor_.reset();
  manhattan_.reset();
  sightings_.clear();
  last_yaw_.reset();
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
  out.manhattan_carried = false;
  out.manhattan_carried_age = 0.f;
  out.T_upright_camera = Pose::Identity();
  out.manhattan_without_floor = false;
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
  // The Manhattan frame about an upright frame's vertical (the floor's, or without a floor that of
  // a floor-like plane refused as the floor); the image edges' compass is asked lazily, through a
  // lambda holding one reference: std::function keeps so small a callable in place, with no
  // allocation per frame.
  auto manhattan = [&](const Pose& T_upright_camera) {
    out.T_upright_camera = T_upright_camera;
    const struct {
      EdgeCompass& compass;
      const RgbdFrame& frame;
      const Pose& T;
      float max_range;
    } ask{compass_, frame, T_upright_camera, max_range_};
    const ManhattanEstimate m = manhattan_.estimate(out.regions, T_upright_camera, [&ask]() {
      return ask.compass.estimate(ask.frame.gray, ask.frame.intrinsics, ask.T, ask.frame.depth,
                                  ask.max_range);
    });
    out.manhattan_found = m.found;
    out.manhattan_fraction = m.fraction;
    out.manhattan_why = m.why;
    if (m.found) {
      out.manhattan_yaw = m.yaw;
      out.T_manhattan_floor = m.T_manhattan_floor;
      last_yaw_ = m.yaw;
    }
  };
  if (floor_est_.found) {
    out.floor_found = true;
    out.T_floor_camera = floor_est_.T_floor_camera;
    out.camera_height = floor_est_.height;
    out.camera_tilt = floor_est_.tilt;
    out.camera_roll = floor_est_.roll;
    out.floor_region = floor_est_.region;
    out.floor_tracked = floor_est_.tracked;
    manhattan(out.T_floor_camera);
  } else {
    out.why = "no floor: " + floor_est_.why;
    if (manhattan_cfg_.without_floor && floor_est_.level_region >= 0) {
      // Refused as the floor for where it lies (a tread, a seat: the user's level is in doubt),
      // a floor-like plane is still level: the walls and risers are upright about its normal.
      const PlaneRegion& level = out.regions[static_cast<std::size_t>(floor_est_.level_region)];
      manhattan(floor_pose_from_plane(level.normal, level.offset));
      out.manhattan_without_floor = out.manhattan_found;
      if (!out.manhattan_found)
        out.manhattan_why = "no floor; about a floor-like plane's vertical: " + out.manhattan_why;
    } else {
      out.manhattan_why = "no floor";
    }
  }
  const auto t3 = Clock::now();
  out.timings.manhattan_ms = std::chrono::duration<double, std::milli>(t3 - t2).count();
  classify_regions(out, classification_);
  out.timings.classification_ms = ms_since(t3);
  out.timings.total_ms = ms_since(t0);
}

namespace {
using manhattan_detail::wrap_quarter;
}  // namespace

ManhattanSighting Perception::manhattan_sighting(const SceneResult& out, double timestamp) const {
  ManhattanSighting sg;
  if (!out.floor_found || !out.manhattan_found || out.manhattan_carried) return sg;
  const Eigen::Matrix3f R_fc = out.T_floor_camera.linear();
  const float sin_tol = std::sin(manhattan_cfg_.vertical_tolerance);
  // The view's frame weighs what its agreeing vertical planes weigh in the estimator: area times
  // the square of their horizontal width (a plane's yaw is as precise as it is wide).
  const Eigen::Vector3f up_c = R_fc.transpose() * Eigen::Vector3f::UnitY();
  const float full_w = std::max(manhattan_cfg_.yaw_full_width, 1e-3f);
  float weight = 0.f;
  for (const PlaneRegion& r : out.regions) {
    const Eigen::Vector3f nf = R_fc * r.normal;
    if (std::fabs(nf.y()) > sin_tol || r.points.empty()) continue;
    if (std::fabs(wrap_quarter(std::atan2(nf.x(), nf.z()) - out.manhattan_yaw)) >
        manhattan_cfg_.cluster_tolerance)
      continue;
    const Eigen::Vector3f hz = up_c.cross(r.normal).normalized();
    float lo = hz.dot(r.points.front()), hi = lo;
    for (const Eigen::Vector3f& q : r.points) {
      lo = std::min(lo, hz.dot(q));
      hi = std::max(hi, hz.dot(q));
    }
    const float s = std::min(1.f, (hi - lo) / full_w);
    weight += r.area * s * s;
  }
  sg.valid = true;
  sg.k_camera =
      R_fc.transpose() * Eigen::Vector3f(std::sin(out.manhattan_yaw), 0.f, std::cos(out.manhattan_yaw));
  sg.weight = std::max(weight, 1e-6f);
  sg.timestamp = timestamp;
  return sg;
}

void Perception::hold_manhattan(const ManhattanSighting& sighting, const OdometryLink& odometry) {
  constexpr std::size_t kMaxSightings = 128;
  if (!sighting.valid || !(manhattan_cfg_.carry_seconds > 0.f)) return;
  if (!sightings_.empty() && odometry.track != sightings_track_) {
    if (sighting.timestamp < sightings_.back().time) return;  // a late one from the old world
    sightings_.clear();
  }
  sightings_track_ = odometry.track;
  if (sightings_.size() == kMaxSightings) sightings_.erase(sightings_.begin());
  const Sighting held{(odometry.T_world_camera.linear() * sighting.k_camera).normalized(), sighting.timestamp,
                      sighting.weight};
  // In time order: a view whose pose came late goes before the ones held since.
  auto at = sightings_.end();
  while (at != sightings_.begin() && (at - 1)->time > held.time) --at;
  sightings_.insert(at, held);
}

void Perception::apply_odometry(const OdometryLink& odometry, double timestamp, SceneResult& out) {
  const float carry = manhattan_cfg_.carry_seconds;
  // Another odometry world (lost track, restart), or time going backwards (another recording):
  // the directions held are meaningless in it.
  if (!sightings_.empty() && (odometry.track != sightings_track_ || timestamp < sightings_.back().time))
    sightings_.clear();
  sightings_track_ = odometry.track;
  std::size_t stale = 0;
  while (stale < sightings_.size() && timestamp - sightings_[stale].time > carry) ++stale;
  sightings_.erase(sightings_.begin(), sightings_.begin() + static_cast<std::ptrdiff_t>(stale));
  if (!out.floor_found || !(carry > 0.f)) return;
  const Eigen::Matrix3f R_wc = odometry.T_world_camera.linear();
  const Eigen::Matrix3f R_fc = out.T_floor_camera.linear();
  const float sin_tol = std::sin(manhattan_cfg_.vertical_tolerance);
  const float tol = manhattan_cfg_.cluster_tolerance;
  const ManhattanSighting own = manhattan_sighting(out, timestamp);
  const bool seen = own.valid;
  // The held frames in this view's floor frame, fading with age (a third of carry_seconds), and
  // this view's own. The odometry's world need not be level: the floor seen now says what is
  // horizontal, and each direction is projected on it.
  std::vector<HeldVote>& votes = held_votes_;
  votes.clear();
  const float fade = 3.f / carry;
  for (const Sighting& sg : sightings_) {
    Eigen::Vector3f k_f = R_fc * (R_wc.transpose() * sg.k_world);
    k_f.y() = 0.f;
    if (k_f.norm() < 0.5f) continue;  // not horizontal in this view: the odometry or the floor is wrong
    votes.push_back({wrap_quarter(std::atan2(k_f.x(), k_f.z())),
                     sg.weight * std::exp(-fade * static_cast<float>(timestamp - sg.time)), sg.time});
  }
  if (seen) {
    votes.push_back({wrap_quarter(out.manhattan_yaw), own.weight, timestamp});
    hold_manhattan(own, odometry);
  }
  if (votes.empty()) return;
  // The direction most of the weight agrees on (modulo 90 degrees): the mode of a histogram,
  // refined by the circular mean of 4 * angle of the votes near it (as the estimator).
  ManhattanHistogram hist;
  for (const HeldVote& v : votes) hist.add(v.a, v.w);
  const float mode = hist.mode();
  float sc = 0.f, ss = 0.f;
  double newest = -1e300;
  for (const HeldVote& v : votes) {
    if (std::fabs(wrap_quarter(v.a - mode)) > tol) continue;
    sc += v.w * std::cos(4.f * v.a);
    ss += v.w * std::sin(4.f * v.a);
    newest = std::max(newest, v.time);
  }
  float yaw = wrap_quarter(0.25f * std::atan2(ss, sc));
  if (seen) {
    const float off = std::fabs(wrap_quarter(out.manhattan_yaw - yaw));
    if (off <= tol) {
      // The view agrees with what is held: the frame reported is the weighted mean of both, on
      // the view's own branch. One view's yaw is off by degrees on real walls (the kitchen's spread
      // 6.2 deg view by view, 2.2 deg held); the odometry's drift over seconds is far less.
      const float y = out.manhattan_yaw + wrap_quarter(yaw - out.manhattan_yaw);
      out.manhattan_yaw = y;
      out.T_manhattan_floor = manhattan_pose_from_yaw(y);
      last_yaw_ = y;
      classify_regions(out, classification_);  // left / right / front against the axes reported
      return;
    }
    char buf[160];
    std::snprintf(
        buf, sizeof buf,
        "this view's planes made a frame %.1f deg off the one held in the world, and weigh less: kept "
        "the held one",
        off * 57.2957795f);
    out.manhattan_why = buf;
  }
  // k_M on the branch last reported, as ManhattanTracker keeps it for the frames it sees.
  yaw = manhattan_keep_branch(yaw, last_yaw_);
  // Share of the planar area on vertical planes along the axes reported (the same measure the
  // estimator reports): stair modelling asks for its own share before it uses a frame.
  float total = 0.f, agree = 0.f;
  for (const PlaneRegion& r : out.regions) {
    total += r.area;
    const Eigen::Vector3f nf = R_fc * r.normal;
    if (std::fabs(nf.y()) <= sin_tol && std::fabs(wrap_quarter(std::atan2(nf.x(), nf.z()) - yaw)) <= tol)
      agree += r.area;
  }
  out.manhattan_found = true;
  out.manhattan_carried = true;
  out.manhattan_carried_age = static_cast<float>(timestamp - newest);
  out.manhattan_yaw = yaw;
  out.T_manhattan_floor = manhattan_pose_from_yaw(yaw);
  out.manhattan_fraction = total > 0.f ? agree / total : 0.f;
  last_yaw_ = yaw;
  classify_regions(out, classification_);  // left / right / front against the axes reported
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
        img.at<cv::Vec3b>(v, u) =
            cv::Vec3b(static_cast<uchar>(g), static_cast<uchar>(g), static_cast<uchar>(g));
      }
  }
  if (static_cast<int>(labels.size()) != H * W) return img;
  for (int v = 0; v < H; ++v) {
    for (int u = 0; u < W; ++u) {
      const int l = labels[static_cast<std::size_t>(v) * W + u];
      cv::Vec3b col;
      if (l >= 0 && l < static_cast<int>(scene.regions.size()))
        col = region_class_color(scene.regions[l].cls);
      else if (l <= -2)
        col = region_class_color(RegionClass::kObstacle);
      else
        continue;
      cv::Vec3b& px = img.at<cv::Vec3b>(v, u);
      for (int k = 0; k < 3; ++k)
        px[k] = static_cast<uchar>((1.f - alpha) * static_cast<float>(px[k]) +
                                   alpha * static_cast<float>(col[k]));
    }
  }
  return img;
}

}  // namespace stairguide
