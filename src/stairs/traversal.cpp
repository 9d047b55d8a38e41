// The traversal tracker (paper 5.2). The staircase lives in the odometry's world as a pose and a
// fused model; each frame's detection, when it is the same staircase, is matched step by step to
// it: the height of each seen tread's centroid picks which step it is (a riser apart, so odometry
// drift of a few centimetres cannot confuse two), then the residuals of heights and edges say how
// far the held pose has drifted, and a share of them (by the view's quality) is applied.
#include "stairguide/stairs/traversal.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

namespace stairguide {

namespace {

bool is_flight(StairKind k) { return k == StairKind::kAscending || k == StairKind::kDescending; }

float median_of(std::vector<float>& v) {
  const std::size_t n = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(n), v.end());
  return v[n];
}

// Rotation about `axis` (unit) by `angle`.
Eigen::Matrix3f rot(const Eigen::Vector3f& axis, float angle) {
  return Eigen::AngleAxisf(angle, axis).toRotationMatrix();
}

// Re-orthonormalises a rotation that accumulated rounding.
Eigen::Matrix3f orthonormal(const Eigen::Matrix3f& R) {
  Eigen::Vector3f y = R.col(1).normalized();
  Eigen::Vector3f z = (R.col(2) - R.col(2).dot(y) * y).normalized();
  Eigen::Matrix3f out;
  out.col(0) = y.cross(z);
  out.col(1) = y;
  out.col(2) = z;
  return out;
}

// Surface height (y_S) and step-edge position (z_S) of tread j in the stair frame.
float tread_height(int dir, int j, float r) {
  return dir > 0 ? static_cast<float>(j - 1) * r : -static_cast<float>(j) * r;
}
float edge_position(int dir, int j, float t) {
  // Ascending: the near edge (nosing) of tread j; descending: its far edge, where the next drop is.
  return dir > 0 ? static_cast<float>(j - 1) * t : static_cast<float>(j) * t;
}

}  // namespace

TraversalTracker::TraversalTracker(const TraversalConfig& config) : cfg_(config) {
  seen_.reserve(32);
  match_.reserve(32);
  dz_.reserve(32);
  dy_.reserve(32);
  near_.reserve(32);
}

void TraversalTracker::reset() {
  model_ = Model{};
  candidate_ = Model{};
  out_ = TraversalResult{};
  have_last_ = false;
  arrived_at_ = -1.0;
}

float TraversalTracker::tread_of(const Model& m) const {
  return m.tread > 0.f ? m.tread : cfg_.default_tread;
}

float TraversalTracker::frame_quality(const StairResult& s, const Pose& /*T_world_camera*/) const {
  int points = 0;
  for (std::size_t k = 1; k < s.level_data.size(); ++k)
    points += static_cast<int>(s.level_data[k].points.size());
  const float pf = std::clamp(static_cast<float>(points) / 3000.f, 0.1f, 1.f);
  const float d = s.origin().norm();
  const float df = 1.f / (1.f + (d / 2.5f) * (d / 2.5f));  // depth noise grows with the square of the range
  const float ends = s.width_complete ? 1.f : 0.7f;
  const float lv = std::sqrt(std::min(1.f, static_cast<float>(s.levels) / 3.f));
  return std::clamp(pf * df * ends * lv, 0.f, 1.f);
}

// The seen levels in the world: each tread's centroid (from its points) and a point of its edge.
void TraversalTracker::gather(const StairResult& s, const Pose& T_world_camera) {
  seen_.clear();
  const Pose T_world_det = T_world_camera * s.T_camera_stair;
  const Pose T_det_camera = s.T_camera_stair.inverse();
  const int dir = s.direction();
  const float t_est = s.tread_m > 0.f ? s.tread_m : (model_.valid ? tread_of(model_) : cfg_.default_tread);
  for (std::size_t k = 1; k < s.level_data.size(); ++k) {
    const StairLevel& l = s.level_data[k];
    if (l.points.empty()) continue;
    Eigen::Vector3f c = Eigen::Vector3f::Zero();
    for (const auto& p : l.points) c += p;
    c /= static_cast<float>(l.points.size());
    SeenLevel v;
    v.points = static_cast<int>(l.points.size());
    v.centroid_w = T_world_camera * c;
    v.landing = l.depth_max - l.depth_min > cfg_.landing_factor * t_est;
    // Descending, a landing's far side is where the view ends, not an edge.
    v.has_edge = std::isfinite(l.edge) && (dir > 0 || !v.landing);
    if (v.has_edge) {
      Eigen::Vector3f e = T_det_camera * c;
      e.z() = l.edge;
      v.edge_w = T_world_det * e;
    }
    seen_.push_back(v);
  }
  // Descending, the edge where the user's level ends (the origin) is the dangerous one: it counts
  // as the far edge of the level the user stands on.
  // Only where the floor's edge was measured: with the floor remembered, the origin is placed one
  // tread before the first edge seen, an assumption that would pull the held pose by its error.
  origin_level_ = dir < 0 && !s.without_floor && !s.floor_remembered && floor_seen_;
  if (origin_level_) {
    SeenLevel v;
    v.points = 1000;
    v.centroid_w = T_world_det.translation();
    v.edge_w = v.centroid_w;
    v.has_edge = true;
    seen_.push_back(v);
  }
}

bool TraversalTracker::start_model(Model& m, const StairResult& s, const Pose& T_world_camera,
                                   double t) const {
  m = Model{};
  m.valid = true;
  m.direction = s.direction();
  m.kind = s.kind;
  m.T_world_stair = T_world_camera * s.T_camera_stair;
  m.T_world_stair.linear() = orthonormal(m.T_world_stair.linear());
  m.riser = s.riser_m;
  m.tread = s.tread_m;
  m.width = s.width_m;
  m.first_seen = m.last_seen = t;
  m.hits = 1;
  return m.riser > 0.f;
}

bool TraversalTracker::associate(const Model& m, const StairResult& s, const Pose& T_world_camera) {
  match_.clear();
  if (s.direction() != m.direction || m.riser <= 0.f) return false;
  const Eigen::Matrix3f& R = m.T_world_stair.linear();
  const Eigen::Vector3f y = R.col(1);
  Eigen::Vector3f zm = R.col(2), zd = T_world_camera.linear() * s.T_camera_stair.linear().col(2);
  zd -= zd.dot(y) * y;
  if (zd.norm() < 1e-3f) return false;
  zd.normalize();
  if (std::acos(std::clamp(zm.dot(zd), -1.f, 1.f)) > cfg_.max_yaw_disagreement) return false;
  // A view that measures the staircase unlike the frames fused so far (a level taken for another,
  // a merged landing) would pull the held pose off: it is not used.
  if (std::acos(std::clamp(y.dot(det_up_), -1.f, 1.f)) > cfg_.max_tilt_disagreement) return false;
  if (m.w_riser >= 1.0 && std::fabs(s.riser_m - m.riser) > cfg_.max_riser_disagreement) return false;
  if (m.w_tread >= 1.0 && s.tread_m > 0.f && s.levels >= 2 &&
      std::fabs(s.tread_m - m.tread) > cfg_.max_tread_disagreement)
    return false;
  const Pose T_sw = m.T_world_stair.inverse();
  const float r = m.riser, t = tread_of(m), mf = cfg_.match_fraction;
  const int dir = m.direction;
  for (std::size_t i = 0; i < seen_.size(); ++i) {
    const SeenLevel& v = seen_[i];
    const Eigen::Vector3f p = T_sw * v.centroid_w;
    Match mt;
    mt.step =
        dir > 0 ? static_cast<int>(std::lround(p.y() / r)) + 1 : static_cast<int>(std::lround(-p.y() / r));
    const bool origin_level = origin_level_ && i + 1 == seen_.size();
    if (mt.step < (origin_level ? 0 : 1)) continue;
    if (m.last_known && mt.step > m.last_step) continue;
    mt.dy = p.y() - tread_height(dir, mt.step, r);
    if (std::fabs(mt.dy) > mf * r) continue;
    mt.landing = v.landing;
    if (v.has_edge) {
      const float dz = (T_sw * v.edge_w).z() - edge_position(dir, mt.step, t);
      if (std::fabs(dz) <= mf * t) {
        mt.dz = dz;
        mt.has_dz = true;
      }
    }
    mt.seen = static_cast<int>(i);
    match_.push_back(mt);
  }
  return !match_.empty();
}

void TraversalTracker::correct(Model& m, float quality, bool apply_pose) {
  out_.corr_height_m = out_.corr_along_m = out_.corr_yaw_rad = 0.f;
  out_.corrected = false;
  if (!apply_pose || match_.empty()) return;
  const double w_prior = m.weight;
  m.weight += quality;
  // The first views average (the pose is their quality-weighted mean); later ones follow the
  // drift with at least the configured gain.
  const float g =
      std::clamp(static_cast<float>(std::max(static_cast<double>(quality) / std::max(1e-6, w_prior + quality),
                                             static_cast<double>(cfg_.correction_gain * quality))),
                 0.f, 1.f);
  Pose& T = m.T_world_stair;
  // ---- orientation: the vertical, then the yaw, about the point under the camera ----
  // Turning about the user keeps where the user stands on the staircase (what is counted) and lets
  // the translation below bring the levels in sight into place; turning about the levels far ahead
  // would move the user by the angle times that distance.
  const Eigen::Vector3f pivot = pivot_;
  const Eigen::Matrix3f R0 = T.linear();
  Eigen::Matrix3f dR = Eigen::Matrix3f::Identity();
  {
    const Eigen::Vector3f y = R0.col(1), ym = det_up_;
    const Eigen::Vector3f ax = y.cross(ym);
    const float s = ax.norm(), c = y.dot(ym);
    if (s > 1e-6f) dR = rot(ax / s, cfg_.tilt_gain * g * std::atan2(s, c));
    const Eigen::Vector3f y1 = dR * y;
    Eigen::Vector3f z1 = dR * R0.col(2), zm = det_forward_ - det_forward_.dot(y1) * y1;
    if (zm.norm() > 1e-3f) {
      zm.normalize();
      const float yaw = std::atan2(z1.cross(zm).dot(y1), z1.dot(zm));
      dR = rot(y1, g * yaw) * dR;
      out_.corr_yaw_rad = g * yaw;
    }
  }
  T.translation() = pivot + dR * (T.translation() - pivot);
  T.linear() = orthonormal(dR * R0);
  // ---- position: heights from the tread centroids, along from the edges in sight ----
  const Pose T_sw = T.inverse();
  const float r = m.riser, t = tread_of(m);
  // From the levels nearest the user (the next steps, what is counted; depth noise grows with the
  // square of the range): the median of the nearest few, so that one level taken for another (a
  // landing merged with a tread) does not pull the rest.
  near_.clear();
  for (std::size_t i = 0; i < match_.size(); ++i) {
    const SeenLevel& v = seen_[static_cast<std::size_t>(match_[i].seen)];
    near_.emplace_back((v.centroid_w - pivot).squaredNorm(), static_cast<int>(i));
  }
  std::sort(near_.begin(), near_.end());
  std::vector<float>& dz = dz_;
  std::vector<float>& dy = dy_;
  dz.clear();
  dy.clear();
  for (const auto& [d2, i] : near_) {
    const Match& mt = match_[static_cast<std::size_t>(i)];
    const SeenLevel& v = seen_[static_cast<std::size_t>(mt.seen)];
    if (static_cast<int>(dy.size()) < cfg_.near_levels)
      dy.push_back((T_sw * v.centroid_w).y() - tread_height(m.direction, mt.step, r));
    if (mt.has_dz && static_cast<int>(dz.size()) < cfg_.near_levels)
      dz.push_back((T_sw * v.edge_w).z() - edge_position(m.direction, mt.step, t));
  }
  const float cy = dy.empty() ? 0.f : median_of(dy);
  const float cz = dz.empty() ? 0.f : median_of(dz);
  // Across the stair (x_S) the view says nothing: the odometry is trusted.
  T.translation() += T.linear() * Eigen::Vector3f(0.f, g * cy, g * cz);
  out_.corr_height_m = g * cy;
  out_.corr_along_m = g * cz;
  out_.corrected = true;
}

void TraversalTracker::fuse_dimensions(Model& m, const StairResult& s, float q) const {
  if (s.riser_m > 0.f) {
    m.sum_riser += static_cast<double>(q) * s.riser_m;
    m.w_riser += q;
  }
  if (s.tread_m > 0.f && s.levels >= 2) {
    m.sum_tread += static_cast<double>(q) * s.tread_m;
    m.w_tread += q;
  }
  if (s.width_complete) {
    m.sum_width += static_cast<double>(q) * s.width_m;
    m.w_width += q;
  } else {
    m.width_partial = std::max(m.width_partial, s.width_m);
  }
  if (m.w_riser > 0) m.riser = static_cast<float>(m.sum_riser / m.w_riser);
  if (m.w_tread > 0) m.tread = static_cast<float>(m.sum_tread / m.w_tread);
  m.width = m.w_width > 0 ? static_cast<float>(m.sum_width / m.w_width) : m.width_partial;
}

void TraversalTracker::grow(Model& m) const {
  for (const Match& mt : match_) {
    if (mt.landing && mt.step >= 1 && mt.step >= m.steps_known - 1) {
      m.last_known = true;
      m.last_step = mt.step;
    }
    m.steps_known = std::max(m.steps_known, mt.step);
  }
  if (m.last_known) m.steps_known = m.last_step;
}

const TraversalResult& TraversalTracker::update(const SceneResult& scene, const StairResult& stair,
                                                const Pose& T_world_camera, bool pose_trusted,
                                                double timestamp, std::uint64_t track) {
  const auto t0 = std::chrono::steady_clock::now();
  out_ = TraversalResult{};
  out_.ran = cfg_.enabled;
  if (!cfg_.enabled) return out_;
  const double now = timestamp;

  // ---- the camera in the odometry's world ----
  Pose T_wc = T_world_camera;
  if (!pose_trusted) {
    if (have_last_) T_wc = T_world_camera_last_;  // taken as still; the live view corrects the rest
  } else if (have_last_ && track != track_) {
    // A new world: the staircase is carried through the last camera pose.
    const Pose carry = T_wc * T_world_camera_last_.inverse();
    if (model_.valid) model_.T_world_stair = carry * model_.T_world_stair;
    if (candidate_.valid) candidate_.T_world_stair = carry * candidate_.T_world_stair;
  }
  if (pose_trusted) track_ = track;
  const bool have_pose = pose_trusted || have_last_;
  if (!have_pose) {
    out_.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    return out_;
  }
  T_world_camera_last_ = T_wc;
  have_last_ = true;

  // ---- this frame's detection ----
  // A single step or a curb is what the end of a flight looks like from its last steps (the last
  // riser and the landing, the last drop to the floor): it corrects a staircase held, never starts one.
  const bool det = stair.detected &&
                   (is_flight(stair.kind) || (model_.valid && stair.kind != StairKind::kNone)) &&
                   stair.direction() != 0 && stair.levels >= 1 && stair.riser_m > 0.f &&
                   stair.origin().norm() <= cfg_.max_distance;
  if (det) {
    floor_seen_ = scene.floor_found;
    gather(stair, T_wc);
    pivot_ = T_wc.translation();
    det_up_ = (T_wc.linear() * stair.T_camera_stair.linear().col(1)).normalized();
    det_forward_ = (T_wc.linear() * stair.T_camera_stair.linear().col(2)).normalized();
  }
  float quality = det ? frame_quality(stair, T_wc) : 0.f;

  // Where the body is on the model (before this frame's correction): decides what may correct it.
  auto body_along = [&](const Model& m) {
    const Pose T_sw = m.T_world_stair.inverse();
    const Eigen::Vector3f c = T_sw * T_wc.translation();
    Eigen::Vector3f f = T_sw.linear() * T_wc.linear().col(2);
    f.y() = 0.f;
    f = f.norm() > 1e-3f ? Eigen::Vector3f(f.normalized()) : Eigen::Vector3f::UnitZ();
    return (c - cfg_.body_behind * f).z();
  };

  bool used = false;
  if (det && model_.valid && associate(model_, stair, T_wc)) {
    bool first_edge_seen = false;
    for (const Match& mt : match_) first_edge_seen |= mt.has_dz && mt.step == (model_.direction > 0 ? 1 : 0);
    const bool apply = cfg_.correct || (first_edge_seen && body_along(model_) < 0.f);
    correct(model_, quality, apply);
    if (is_flight(stair.kind)) fuse_dimensions(model_, stair, quality);
    grow(model_);
    model_.last_seen = now;
    ++model_.hits;
    used = true;
  } else if (det && !stair.without_floor && is_flight(stair.kind)) {
    // A staircase not (or no longer) held: confirmed over a few frames before it is taken.
    if (candidate_.valid && now - candidate_.last_seen <= cfg_.confirm_window &&
        associate(candidate_, stair, T_wc)) {
      correct(candidate_, quality, true);
      fuse_dimensions(candidate_, stair, quality);
      grow(candidate_);
      candidate_.last_seen = now;
      ++candidate_.hits;
    } else if (start_model(candidate_, stair, T_wc, now) && associate(candidate_, stair, T_wc)) {
      candidate_.weight = quality;
      fuse_dimensions(candidate_, stair, quality);
      grow(candidate_);
    } else {
      candidate_.valid = false;
    }
    const bool replace =
        !model_.valid || (now - model_.last_seen > cfg_.lost_time && body_along(model_) < 0.f);
    if (candidate_.valid && candidate_.hits >= cfg_.confirm_frames && replace) {
      model_ = candidate_;
      candidate_.valid = false;
      remembered_ = false;
      used = true;
    }
    out_.corr_height_m = out_.corr_along_m = out_.corr_yaw_rad = 0.f;
    out_.corrected = false;
  }
  if (!used) {
    out_.corr_height_m = out_.corr_along_m = out_.corr_yaw_rad = 0.f;
    out_.corrected = false;
    quality = 0.f;
  }
  out_.in_view = used;
  out_.quality = quality;

  if (!model_.valid) {
    out_.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    return out_;
  }

  // ---- the body centre on the staircase ----
  const Model& m = model_;
  const Pose T_sw = m.T_world_stair.inverse();
  const Eigen::Vector3f c = T_sw * T_wc.translation();
  Eigen::Vector3f f = T_sw.linear() * T_wc.linear().col(2);
  f.y() = 0.f;
  f = f.norm() > 1e-3f ? Eigen::Vector3f(f.normalized()) : Eigen::Vector3f::UnitZ();
  const Eigen::Vector3f body = c - cfg_.body_behind * f;
  const float below = scene.remembered_camera_height > 0.f ? scene.remembered_camera_height : cfg_.body_below;
  const float t = tread_of(m);
  const float along = body.z();
  int step = along < 0.f ? 0 : static_cast<int>(std::floor(along / t)) + 1;
  if (m.width > 0.f && std::fabs(body.x()) > 0.5f * m.width + 0.4f) step = 0;  // beside the flight
  if (m.last_known) step = std::min(step, m.last_step);

  // ---- distance and bearing to the first edge (as StairSummary: from the point under the camera) ----
  {
    const Pose T_cw = T_wc.inverse();
    const Eigen::Vector3f up = T_cw.linear() * m.T_world_stair.linear().col(1);
    const Eigen::Vector3f o = T_cw * m.T_world_stair.translation();
    const Eigen::Vector3f oh = o - o.dot(up) * up;
    Eigen::Vector3f fwd = Eigen::Vector3f::UnitZ() - up.z() * up;
    if (fwd.norm() >= 1e-3f) {
      fwd.normalize();
      const Eigen::Vector3f right = fwd.cross(up);
      out_.distance_m = oh.norm();
      out_.bearing_rad = std::atan2(oh.dot(right), oh.dot(fwd));
    }
  }

  out_.kind = m.kind;
  out_.direction = m.direction;
  out_.remembered = remembered_;
  out_.step_index = step;
  out_.steps_climbed = step;
  out_.steps_known = m.steps_known;
  out_.last_known = m.last_known;
  out_.steps_left = m.last_known ? std::max(0, m.last_step - step) : -1;
  out_.riser_m = m.riser;
  out_.tread_m = t;
  out_.width_m = m.width;
  out_.T_world_stair = m.T_world_stair;
  out_.body_along_m = along;
  out_.body_height_m = c.y() - below;

  bool drop = false;
  if (arrived_at_ >= 0.0) {
    out_.state = TraversalState::kArrived;
    if (now - arrived_at_ >= cfg_.arrive_hold) drop = true;
  } else if (step >= 1) {
    out_.state =
        (m.last_known && step >= m.last_step - 1) ? TraversalState::kLastStep : TraversalState::kOnStairs;
    if (m.last_known && step == m.last_step &&
        along >= edge_position(1, m.last_step, t) + cfg_.arrive_margin) {
      out_.state = TraversalState::kArrived;
      arrived_at_ = now;
    }
  } else {
    const double unseen = now - m.last_seen;
    const bool at_foot = std::isfinite(out_.distance_m) && out_.distance_m < 1.0f;
    if (unseen <= cfg_.lost_time || (at_foot && unseen <= cfg_.memory_time)) {
      out_.state = TraversalState::kStairAhead;
    } else {
      out_.state = TraversalState::kSearching;  // out of view: kept in the world for a while
      remembered_ = true;
      out_.remembered = true;
      if (unseen > cfg_.memory_time) drop = true;
    }
  }
  if (drop) {
    // Nothing held any more: the frame reads as searching from nothing.
    const bool in_view = out_.in_view;
    const float quality = out_.quality;
    out_ = TraversalResult{};
    out_.ran = true;
    out_.in_view = in_view;
    out_.quality = quality;
    model_ = Model{};
    candidate_ = Model{};
    arrived_at_ = -1.0;
    remembered_ = false;
  }
  out_.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return out_;
}

}  // namespace stairguide
