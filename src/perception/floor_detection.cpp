#include "stairguide/perception/floor_detection.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include <Eigen/Eigenvalues>

#include "floor_internal.hpp"

namespace stairguide {

Pose floor_pose_from_plane(const Eigen::Vector3f& up, float camera_height) {
  const Eigen::Vector3f y = up.normalized();
  Eigen::Vector3f z = Eigen::Vector3f::UnitZ() - y * y.z();
  if (z.norm() < 1e-4f) z = Eigen::Vector3f::UnitY() - y * y.y();  // looking straight down
  z.normalize();
  const Eigen::Vector3f x = y.cross(z);
  Eigen::Matrix3f R;  // rows: floor axes in camera coordinates
  R.row(0) = x.transpose();
  R.row(1) = y.transpose();
  R.row(2) = z.transpose();
  Pose T = Pose::Identity();
  T.linear() = R;
  // The camera sits camera_height above the floor origin, on y_F.
  T.translation() = Eigen::Vector3f(0.f, camera_height, 0.f);
  return T;
}

void tilt_roll_from_up(const Eigen::Vector3f& up, float& tilt, float& roll) {
  // Camera with no roll: up = (0, -cos t, -sin t) in camera coordinates (y down, z forward).
  tilt = std::asin(std::clamp(-up.z(), -1.f, 1.f));
  roll = std::atan2(-up.x(), -up.y());
}

FloorDetector::FloorDetector(const FloorConfig& config) : cfg_(config) {}

using namespace floor_detail;

FloorDetector::Reach FloorDetector::reach(const PlaneRegion& r) {
  // 2nd percentiles: robust to stray points.
  Reach out;
  // Every other point of the (already subsampled) region is plenty for a 2nd percentile.
  // About 4000 evenly spread points give the 2nd percentile to well under a pixel's spacing, and
  // keep this linear pass and the selection cheap on a floor of tens of thousands of points.
  const std::size_t step = r.points.size() > 400 ? std::max<std::size_t>(2, r.points.size() / 4000) : 1;
  near_buf_.clear();
  for (std::size_t k = 0; k < r.points.size(); k += step)
    near_buf_.push_back(foot_distance(r.normal, r.points[k]));
  out.distance = percentile(near_buf_, 20);
  near_buf_.clear();
  for (std::size_t k = 0; k < r.points.size(); k += step)
    near_buf_.push_back(nadir_tan(r.normal, r.points[k]));
  out.angle = std::atan(percentile(near_buf_, 20));
  return out;
}

void FloorDetector::sample_frame(const RgbdFrame& frame) {
  // A sparse grid of the frame's points, enough to see a riser or a seat's front (hundreds of
  // pixels) at a few microseconds per candidate test.
  samples_.clear();
  const cv::Mat& D = frame.depth;
  if (D.empty() || D.type() != CV_32FC1) return;
  const CameraIntrinsics& K = frame.intrinsics;
  const int s = std::max(1, cfg_.verify_stride_px);
  sample_weight_ = static_cast<float>(s * s);
  for (int v = s / 2; v < D.rows; v += s) {
    const float* row = D.ptr<float>(v);
    const float vn = (static_cast<float>(v) - K.cy) / K.fy;
    for (int u = s / 2; u < D.cols; u += s) {
      const float z = row[u];
      if (!(z > 0.f) || !std::isfinite(z)) continue;
      samples_.emplace_back((static_cast<float>(u) - K.cx) / K.fx * z, vn * z, z);
    }
  }
}

bool FloorDetector::nothing_below(const PlaneRegion& r, const Reach& near,
                                  const std::vector<float>& descent) const {
  // The user stands on the floor: nothing the camera sees nearer the user's feet (nearer the
  // nadir) than the floor itself can lie clearly below it. A tread, a platform, a seat or a bed
  // seen from in front has its front face (a riser, the seat's front) or the real floor under its
  // near edge, seen between it and the user's feet; the floor the user stands on only has drops
  // (a descending staircase, a curb down) beyond its own near edge. Compared by the angle from
  // the nadir, not by metres: a riser lies right under its tread's edge, nearer the nadir only
  // because it is lower.
  const float t = std::tan(std::max(0.f, near.angle - cfg_.verify_margin_angle));
  float below = 0.f;
  for (const auto& q : samples_) {
    const float h = r.normal.dot(q) + r.offset;  // height above the candidate plane
    if (h > -cfg_.verify_drop) continue;
    if (nadir_tan(r.normal, q) >= t) continue;
    if (below_any_floor(r.normal, q)) continue;
    // The levels of a descent starting at r's level (its first tread refused as the middle of a
    // stack, r the bigger level a riser above it): seen cold at the top of a flight, the first
    // tread fills the bottom of the view between the floor's pieces beside the stairwell, as near
    // the view's edge as they are. That is the drop ahead of the user, not what r stands on.
    if (std::any_of(descent.begin(), descent.end(),
                    [&](float d) { return std::fabs(h - d) < cfg_.inlier_distance; }))
      continue;
    below += sample_weight_;
  }
  return below < static_cast<float>(cfg_.verify_min_pixels);
}

bool FloorDetector::drop_under_edge(const PlaneRegion& r, const RgbdFrame& frame) const {
  // A first tread whose near edge is in view shows right under that edge, in the same image
  // columns, the top few cm of its riser: lower than the tread but hardly nearer the nadir, so
  // nothing_below's margin misses it. Column by column, walking up from the view's bottom to the
  // first pixel on the candidate's plane (its near edge in that column): the floor the user
  // stands on has nothing lower just under it (it reaches the view's border, or continues, or
  // things stand on it). Walking the depth image column by column costs a few hundred pixels per
  // column where the edge is in view, far less than the region's pixel list.
  //
  // Where the plane itself reaches the view's bottom edge in some columns, the user's level runs
  // on there under the user's side, and what drops under its edge in the other columns, deeper
  // than any riser (ambiguous_rise_max), is ahead of the user: a hole, a sunken floor or a
  // platform's edge seen across (its far wall under the floor beyond it). Those columns then count
  // as columns with no riser, unless a lower level that could be the user's floor (at the rig's
  // height; the usual chest rig's while none is learned) is what the view's bottom edge sees beside
  // it: then the plane may be a low table or a seat standing on that floor, and only the columns
  // where its near edge is in view tell. A drop of a few cm is no hole (two fits of one real floor
  // a few degrees apart), and tells as before.
  constexpr float kDrop = 0.025f;  // m, below the candidate by more than its noise
  constexpr int kRows = 16;        // px under the edge where a drop counts
  constexpr int kColStep = 4;      // px between the columns looked at
  constexpr int kMinColumns = 8;   // columns of a riser (or of a floor beside) before it counts
  const cv::Mat& D = frame.depth;
  if (D.empty() || D.type() != CV_32FC1) return false;
  const int W = D.cols, H = D.rows;
  const CameraIntrinsics& K = frame.intrinsics;
  int columns = 0, dropped = 0, deep = 0, underfoot = 0, floor_beside = 0;
  for (int u = 0; u < W; u += kColStep) {
    const float un = (static_cast<float>(u) - K.cx) / K.fx;
    int drop_row = -1;   // the highest row seen so far with a point clearly below the plane
    float lowest = 0.f;  // m, the lowest point seen below the plane in this column (negative)
    bool first = true;   // the column's lowest reading in view
    for (int v = H - 1; v >= 0; --v) {
      const float z = D.at<float>(v, u);
      if (!(z > 0.f) || !std::isfinite(z)) continue;
      const Eigen::Vector3f q(un * z, (static_cast<float>(v) - K.cy) / K.fy * z, z);
      const float h = r.normal.dot(q) + r.offset;
      if (h < -kDrop) {
        if (first && v >= H - 3 && could_be_floor(-r.normal.dot(q))) ++floor_beside;
        first = false;
        lowest = std::min(lowest, h);
        if (!below_any_floor(r.normal, q)) drop_row = v;
        continue;
      }
      first = false;
      if (h > cfg_.inlier_distance) continue;
      // On the plane: its nearest row in this column.
      if (v >= H - 3) {
        ++underfoot;
      } else {
        ++columns;
        if (drop_row >= 0 && drop_row - v <= kRows + 2) {
          ++dropped;
          deep += lowest < -cfg_.ambiguous_rise_max;
        }
      }
      break;
    }
  }
  // A riser runs along the tread's whole edge; a stray hole or a cable does not. The columns where
  // the plane runs on under the user only weigh against the drop, never make one count.
  const bool hole = deep * 2 > dropped && floor_beside < kMinColumns;
  const int weighed = columns + (hole ? underfoot : 0);
  return columns >= kMinColumns && dropped * 2 >= weighed;
}

FloorEstimate FloorDetector::select(const std::vector<PlaneRegion>& regions, const RgbdFrame& frame,
                                    float height_lo, float height_hi, float tilt_lo, float tilt_hi) {
  FloorEstimate est;
  clear_height_.reset();
  refused_as_tread_ = false;
  descent_tread_.reset();
  const float cos_par = std::cos(cfg_.horizontal_tolerance);
  const int n = static_cast<int>(regions.size());
  const float area_k = 1.f / (frame.intrinsics.fx * frame.intrinsics.fy);
  // The tracked floor, unless this is a cold probe (what would a fresh start take?).
  const std::optional<Prev> no_prev;
  const std::optional<Prev>& prev = probe_ ? no_prev : prev_;

  // Rule checks on orientation and distance.
  std::vector<int> cand;
  for (int i = 0; i < n; ++i) {
    const PlaneRegion& r = regions[i];
    const float h = r.offset;  // normals face the camera: offset = distance of the camera
    if (h < height_lo || h > height_hi) continue;
    float tilt, roll;
    tilt_roll_from_up(r.normal, tilt, roll);
    if (tilt < tilt_lo || tilt > tilt_hi || std::fabs(roll) > cfg_.roll_max) continue;
    if (r.area < cfg_.min_area * 0.1f) continue;
    cand.push_back(i);
  }
  if (cand.empty()) {
    char buf[160];
    std::snprintf(buf, sizeof buf,
                  "no plane with a chest camera's orientation and height (%.2f-%.2f m below it%s)",
                  static_cast<double>(height_lo), static_cast<double>(height_hi),
                  rig_height_ && !probe_ ? ": the user's camera height, held" : "");
    est.why = buf;
    return est;
  }
  // Hold: while the tracked floor was seen a moment ago, a plane a riser above or below it is a
  // step, never the new floor (the user cannot have changed level without passing through
  // frames where the old floor was still in view for long).
  if (prev && lost_frames_ < cfg_.track_hold_frames) {
    const float cos_jump = std::cos(cfg_.track_max_angle_jump);
    cand.erase(std::remove_if(cand.begin(), cand.end(),
                              [&](int i) {
                                return regions[i].normal.dot(prev->normal) < cos_jump ||
                                       std::fabs(regions[i].offset - prev->offset) >
                                           cfg_.track_max_height_jump;
                              }),
               cand.end());
    if (cand.empty()) {
      est.why = "the tracked floor is out of view and the planes in view are at another level (steps)";
      return est;
    }
  } else if (prev) {
    // Held no longer, but the camera's height above what the user stands on is a property of the
    // user, not of the place: on a staircase the tread underfoot is at the remembered height while
    // the treads and the landing below are a riser or more lower. A plane that much lower is
    // never the floor; with the tread underfoot out of view, no floor is reported.
    cand.erase(
        std::remove_if(cand.begin(), cand.end(),
                       [&](int i) { return regions[i].offset - prev->offset > cfg_.track_max_height_jump; }),
        cand.end());
    if (cand.empty()) {
      est.why = "the planes in view are a riser or more below the remembered floor (treads below the user)";
      return est;
    }
  }

  // Choose, verify, and on failure drop every candidate on the rejected plane and choose again:
  // a missed floor is recovered by tracking, a wrong one hides a staircase.
  int chosen = -1;
  int rejected_below = 0, rejected_stair = 0;
  while (!cand.empty()) {
    bool tracked = false;
    chosen = choose(regions, cand, area_k, tracked);
    if (chosen < 0) break;
    const PlaneRegion& f = regions[chosen];
    const Reach near = reach(f);
    // Cold, the level seen under the camera and behind its foot is what the user stands on: the
    // checks below tell a tread or a seat from the floor by what lies between it and the user's
    // feet, and nothing does.
    const bool under = !tracked && under_the_camera(regions, chosen);
    // A descent found to start at this level (its first tread refused as the middle of a stack,
    // this level the bigger one a riser above it, reaching the view's edge as near as that tread).
    descent_levels_.clear();
    if (descent_tread_ && near.angle <= descent_tread_->angle + cfg_.view_edge_angle) {
      const float rise = descent_tread_->offset - f.offset;
      if (rise >= cfg_.ambiguous_rise_min && rise <= cfg_.ambiguous_rise_max)
        for (const PlaneRegion& L : regions)
          if (L.normal.dot(f.normal) >= cos_par && L.offset >= descent_tread_->offset - cfg_.inlier_distance)
            descent_levels_.push_back(f.offset - L.offset);
    }
    const bool clear = under || (nothing_below(f, near, descent_levels_) && !drop_under_edge(f, frame));
    // The tracked floor has been told from the steps already: no ambiguity left.
    stack_below_ = false;
    const bool stair = clear && !tracked && !under &&
                       (stair_from_view_edge(regions, chosen, near, frame.depth.cols) ||
                        middle_of_stack(regions, chosen, near));
    if (stair && stack_below_) descent_tread_ = DescentTread{f.offset, near.angle};
    // Cold, passing every other check: the user may stand on a level above it at the view's edge.
    if (clear && !stair && !tracked && !under &&
        level_above_underfoot(regions, chosen, frame.depth.cols, frame.depth.rows)) {
      est.level_region = chosen;
      est.why = "the user may stand on the level above, seen at the view's edge";
      refused_as_tread_ = true;
      return est;
    }
    if (clear && !stair) {
      est.tracked = tracked;
      clear_height_ = f.offset;
      break;
    }
    // At the top of a descending staircase the treads below are nearer the user's feet than the
    // floor seen beside the stairwell, so the check above fails although the user has not moved
    // off the floor. The tracked floor is kept while the camera stays at the height last verified
    // on a clear view: stepping down onto a tread lowers the camera by a riser (13 cm or more),
    // far more than the tolerance, and then the check applies again.
    if (tracked && anchor_ && cfg_.track_anchor_tolerance > 0.f &&
        std::fabs(f.offset - *anchor_) <= cfg_.track_anchor_tolerance) {
      est.tracked = true;
      break;
    }
    if (!clear)
      ++rejected_below;
    else
      ++rejected_stair;
    if (rejected_below + rejected_stair == 1) est.level_region = chosen;
    const Eigen::Vector3f n0 = f.normal;
    const float d0 = f.offset;
    // A tread of a descent (a level a riser below it ahead, the floor a riser above): every plane
    // lower than it is a lower tread or the floor at the foot of the flight.
    const bool drop_lower = stair && stack_below_;
    cand.erase(std::remove_if(cand.begin(), cand.end(),
                              [&](int i) {
                                if (drop_lower && regions[i].offset > d0) return true;
                                return regions[i].normal.dot(n0) >= std::cos(cfg_.horizontal_tolerance) &&
                                       std::fabs(regions[i].offset - d0) < cfg_.inlier_distance;
                              }),
               cand.end());
    chosen = -1;
  }
  if (chosen < 0) {
    refused_as_tread_ = rejected_stair > 0;
    if (rejected_below + rejected_stair == 0)
      est.why = "no floor-like plane with enough area within the search window";
    else if (rejected_stair == 0)
      est.why = "every floor-like plane has something below it nearer the user (a step, a seat)";
    else if (rejected_below == 0)
      est.why =
          "the floor-like plane may be a tread: a step rises right after where the view starts, or it lies a "
          "riser below a bigger level with a drop ahead";
    else
      est.why = "the floor-like planes have something below them nearer the user, or may be a tread";
    return est;
  }
  const PlaneRegion& f = regions[chosen];
  est.found = true;
  est.region = est.level_region = chosen;
  est.normal = f.normal;
  est.offset = f.offset;
  est.height = f.offset;
  tilt_roll_from_up(f.normal, est.tilt, est.roll);
  est.T_floor_camera = floor_pose_from_plane(f.normal, f.offset);
  return est;
}

FloorEstimate FloorDetector::detect(const std::vector<PlaneRegion>& regions, const RgbdFrame& frame) {
  sample_frame(frame);
  K_ = frame.intrinsics;
  if (K_.width <= 0 || K_.height <= 0) K_.width = frame.depth.cols, K_.height = frame.depth.rows;
  // The camera's height above what the user stands on is a property of the rig and the user, not
  // of the place: once the first clear views have agreed on it, the floor is looked for only
  // within rig_height_tolerance of it (a table, a bed or a seat 0.4-0.8 m below the camera is no
  // floor, whatever the rig); until then, anywhere in the rig range.
  // Not yet established, the usual chest rig's band is looked at first, the whole rig range only
  // when no floor is found there, unless what was found there may be a tread (no floor is safer
  // than a lower plane outside the band).
  // A height held within the usual band changes nothing there (the chest rigs' floors are chosen
  // as before the rig model: held there, the traversal's correction of a climb got worse,
  // TraversalDrift); it keeps whatever lies outside the band from becoming the floor.
  const float tol = cfg_.rig_height_tolerance;
  const bool held = rig_height_.has_value() &&
                    !(*rig_height_ >= cfg_.usual_height_min && *rig_height_ <= cfg_.usual_height_max);
  probe_ = false;
  FloorEstimate est;
  if (held) {
    // The floor tracked a moment ago may be followed below it (climbing a flight, the floor left
    // behind lies a riser or more lower while still in view), as far as the usual chest band
    // reaches (as before the rig model: followed farther, the traversal's correction of a climb
    // got worse, TraversalDrift); a floor is acquired only near the held height.
    float lo = *rig_height_ - tol, hi = *rig_height_ + tol;
    if (prev_ && lost_frames_ < cfg_.track_hold_frames)
      hi = std::max(hi, std::min(prev_->offset + cfg_.track_max_height_jump, cfg_.usual_height_max));
    const TiltBand tilt = rig_tilt_band();
    est = select(regions, frame, std::max(cfg_.height_min, lo), std::min(cfg_.height_max, hi), tilt.lo,
                 tilt.hi);
  } else {
    est = select(regions, frame, std::max(cfg_.height_min, cfg_.usual_height_min),
                 std::min(cfg_.height_max, cfg_.usual_height_max),
                 std::max(cfg_.tilt_min, cfg_.usual_tilt_min), std::min(cfg_.tilt_max, cfg_.usual_tilt_max));
    if (!est.found && !refused_as_tread_) {
      // Outside the usual band one view is no evidence (a worktop or a bed filling a cold view
      // looks like the floor of a waist rig): rig_learn_frames clear views agreeing on the height
      // establish it, and the floor is reported from then on.
      // Once the rig is known, outside the usual tilt only near the rig's own tilt: a hand-held
      // camera that mostly looks 30-50 deg down and now and then grazes the floor at 15 deg is no
      // 15-deg rig (those grazing floors gave the real kitchen walk's Manhattan frame a noisy
      // vertical), while a rig mounted at 15 deg sees its floor there on every view.
      // And once the height is known, nothing far from it: a worktop 0.6-0.7 m below a hand-held
      // camera (the real kitchen's last frames) is neither the floor nor level enough to give the
      // Manhattan frame its vertical (refused as the floor, it gave those views frames 4-10 deg off).
      const TiltBand wide_tilt = rig_tilt_band();
      float wide_lo = cfg_.height_min, wide_hi = cfg_.height_max;
      if (rig_height_) {
        wide_lo = std::max(wide_lo, std::min(cfg_.usual_height_min, *rig_height_ - tol));
        wide_hi = std::min(wide_hi, std::max(cfg_.usual_height_max, *rig_height_ + tol));
      }
      FloorEstimate wide = select(regions, frame, wide_lo, wide_hi, wide_tilt.lo, wide_tilt.hi);
      if (wide.found && clear_height_ && rig_height_) {
        // Held in the band: outside it only a floor near the held height.
        if (std::fabs(wide.offset - *rig_height_) <= tol)
          est = wide;
        else
          clear_height_.reset();
      } else if (wide.found && clear_height_) {
        learn(*clear_height_, wide.tilt);
        if (rig_height_) {
          est = wide;
        } else {
          const int have = static_cast<int>(learn_.size());
          est = FloorEstimate{};
          est.level_region = wide.region;
          char buf[220];
          std::snprintf(
              buf, sizeof buf,
              "a floor-like plane %.2f m below the camera, outside the usual chest rig: %d of %d clear views "
              "to establish the camera height",
              static_cast<double>(wide.offset), std::min(have, cfg_.rig_learn_frames), cfg_.rig_learn_frames);
          est.why = buf;
          clear_height_.reset();
        }
      } else if (wide.found || wide.level_region >= 0) {
        if (wide.found && !wide.tracked)
          wide.found = false, wide.why = "a floor-like plane outside the usual chest rig";
        est = wide;
      }
    }
  }
  const std::optional<float> clear = clear_height_;
  if (est.found) {
    prev_ = Prev{est.normal, est.offset};
    lost_frames_ = 0;
    if (clear) anchor_ = *clear;
    // Clear views establish the height (tracked ones too: a walk's views are; outside the usual
    // band they were counted above). Once established only a floor chosen afresh on a clear view
    // moves it: a tracked one may be the floor left behind at the foot of a flight, a riser or
    // more lower, and following it would carry the height up the flight.
    if (clear && (rig_height_ ? !est.tracked
                              : est.offset >= cfg_.usual_height_min && est.offset <= cfg_.usual_height_max))
      learn(est.offset, est.tilt);
    relearn_.clear();
    relearn_misses_ = 0;
    return est;
  }
  lost();
  if (!held) return est;
  // Held, and no floor at the held height. Were the user's height wrong (the wearer sat down, the
  // rig was remounted), a fresh start would take a floor at another height, on a clear view, frame
  // after frame: after rig_relearn_frames such frames with no floor at the held height in
  // between, that height is the user's now. A floor farther below than held is believed only when
  // no level lies in view between the camera and it (standing on a stair, or at its top, the treads
  // nearer the camera are in view; the wearer who sat down has no level nearer than the floor).
  probe_ = true;
  const FloorEstimate cold =
      select(regions, frame, cfg_.height_min, cfg_.height_max, cfg_.tilt_min, cfg_.tilt_max);
  probe_ = false;
  const std::optional<float> other = clear_height_;
  clear_height_.reset();
  // Nor is a floor with another level a flight's rise or two from it (kStairBand) evidence: on a
  // flight the tread ahead lies a riser above the user's, frame after frame, at the same height
  // below the camera, and would relearn the height to a riser less over a long climb.
  constexpr float kStairBand = 0.3f;  // m, two of the highest risers and their measuring slack
  bool evidence = cold.found && other && std::fabs(*other - *rig_height_) > tol;
  if (evidence) {
    const float cos_par = std::cos(cfg_.horizontal_tolerance);
    for (const PlaneRegion& r : regions) {
      if (r.area < 0.1f * cfg_.min_area || r.normal.dot(cold.normal) < cos_par) continue;
      const float d = std::fabs(r.offset - *other);
      if ((*other > *rig_height_ && r.offset < *other - cfg_.inlier_distance) ||
          (d > cfg_.inlier_distance && d <= kStairBand)) {
        evidence = false;
        break;
      }
    }
  }
  if (evidence && !relearn_.empty() &&
      std::fabs(*other - relearn_.back().height) > cfg_.track_max_height_jump)
    relearn_.clear();
  if (evidence) {
    relearn_.push_back(RigView{*other, cold.tilt});
    relearn_misses_ = 0;
  } else if (!relearn_.empty() && ++relearn_misses_ > cfg_.rig_relearn_frames) {
    relearn_.clear();  // the evidence has gone stale
    relearn_misses_ = 0;
  }
  if (static_cast<int>(relearn_.size()) >= std::max(1, cfg_.rig_relearn_frames)) {
    std::vector<float> h, t;
    for (const RigView& r : relearn_) h.push_back(r.height), t.push_back(r.tilt);
    rig_height_ = median(h);
    rig_tilt_ = median(t);  // a remounted rig may also look another way
    ++rig_learned_;
    relearn_.clear();
    learn_.clear();
    // The floor of this frame is the relearned one: take it now.
    est = cold;
    est.why.clear();
    prev_ = Prev{est.normal, est.offset};
    lost_frames_ = 0;
    anchor_ = est.offset;
    return est;
  }
  if (evidence) {
    char buf[200];
    std::snprintf(
        buf, sizeof buf,
        "a floor-like plane %.2f m below the camera, not the user's %.2f m (relearning the camera height: %d "
        "of %d frames)",
        static_cast<double>(*other), static_cast<double>(*rig_height_), static_cast<int>(relearn_.size()),
        cfg_.rig_relearn_frames);
    est.why = buf;
  }
  return est;
}

void FloorDetector::learn(float height, float tilt) {
  // While not yet established: the last 2*rig_learn_frames clear views; rig_learn_frames of them
  // within the tolerance of their median height establish it (their mean height, their median
  // tilt). Once established the height is that of the floor last found (what reaches here then
  // lies within the tolerance of it); the tilt is held: a rig's mount does not move, while a
  // hand-held camera wanders (followed, a walk that now and then looks nearly level would carry
  // the tilt band down to where the floor is seen grazing and its normal is noisy).
  const int n = std::max(1, cfg_.rig_learn_frames);
  if (rig_height_) {
    rig_height_ = height;
    return;
  }
  learn_.push_back(RigView{height, tilt});
  if (static_cast<int>(learn_.size()) > 2 * n) learn_.erase(learn_.begin());
  std::vector<float> h;
  for (const RigView& r : learn_) h.push_back(r.height);
  const float med = median(h);
  float sum = 0.f;
  std::vector<float> t;
  for (const RigView& r : learn_)
    if (std::fabs(r.height - med) <= cfg_.rig_height_tolerance) sum += r.height, t.push_back(r.tilt);
  if (static_cast<int>(t.size()) >= n) {
    rig_height_ = sum / static_cast<float>(t.size());
    rig_tilt_ = median(t);
    ++rig_learned_;
    learn_.clear();
  }
}

FloorDetector::TiltBand FloorDetector::rig_tilt_band() const {
  // Not yet known: the whole rig range (the first views establish it). Known: the usual chest
  // rig's tilt, widened to the rig's own tilt and a walk's wobble about it.
  TiltBand b{cfg_.tilt_min, cfg_.tilt_max};
  if (!rig_tilt_) return b;
  b.lo = std::max(b.lo, std::min(cfg_.usual_tilt_min, *rig_tilt_ - cfg_.rig_tilt_tolerance));
  b.hi = std::min(b.hi, std::max(cfg_.usual_tilt_max, *rig_tilt_ + cfg_.rig_tilt_tolerance));
  return b;
}

void FloorDetector::lost() {
  if (prev_ && ++lost_frames_ >= std::max(cfg_.track_hold_frames, cfg_.track_forget_frames)) {
    prev_.reset();
    anchor_.reset();
  }
}

int FloorDetector::choose(const std::vector<PlaneRegion>& regions, const std::vector<int>& cand, float area_k,
                          bool& tracked) {
  tracked = false;
  // Tracking: the previous floor, when it is still in view, stays the floor (not in a cold probe).
  int chosen = -1;
  if (!probe_ && prev_ && lost_frames_ < cfg_.track_hold_frames) {
    // Of the candidates within the jump, those on the tracked plane itself (within the inlier
    // distance) come first: a bigger region a few cm off it is a blend of the floor with a face
    // standing on it (measured: 0.71 m^2 fitted 5 cm below the floor before a landing filling the
    // view, beside two floor patches of 0.35 m^2 on it).
    float best = 0.f;
    bool best_on = false;
    for (int i : cand) {
      const PlaneRegion& r = regions[i];
      const float ang = std::acos(std::clamp(r.normal.dot(prev_->normal), -1.f, 1.f));
      const float dh = std::fabs(r.offset - prev_->offset);
      if (ang > cfg_.track_max_angle_jump || dh > cfg_.track_max_height_jump) continue;
      const bool on = dh <= cfg_.inlier_distance && r.area >= 0.25f * cfg_.min_area;
      if ((on && !best_on) || (on == best_on && r.area > best)) {
        best = r.area;
        best_on = on;
        chosen = i;
      }
    }
    // A piece smaller than that is a sliver, unless the rig is learned and the piece lies at its
    // height and tilt: then the floor tracked frame after frame is what is left in view of it (a
    // standing wearer whose flight fills the view but for a strip of floor before it).
    if (chosen >= 0 && regions[chosen].area < 0.25f * cfg_.min_area &&
        !(rig_height_ && agrees_with_rig(regions[chosen]) && level_confirmed(regions, chosen)))
      chosen = -1;
    if (chosen >= 0) {
      tracked = true;
      return chosen;
    }
  }
  if (chosen < 0) {
    // Search window on z_C growing from search_start: the floor is what the user stands on, so
    // it is the plane nearest the camera's feet, not the biggest one. One pass per candidate
    // bins its footprint by window; the windows are then cumulative sums.
    const float step = std::max(cfg_.search_step, 1e-3f);
    const int steps =
        std::max(1, static_cast<int>(std::ceil((cfg_.search_max - cfg_.search_start) / step)) + 1);
    window_area_.assign(cand.size() * static_cast<std::size_t>(steps), 0.f);
    for (std::size_t c = 0; c < cand.size(); ++c) {
      const PlaneRegion& r = regions[cand[c]];
      float* bins = &window_area_[c * static_cast<std::size_t>(steps)];
      auto bin_of = [&](float z) {
        if (z <= cfg_.search_start) return 0;
        return static_cast<int>(std::ceil((z - cfg_.search_start) / step));
      };
      // The region's point subsample is enough to measure its footprint per window.
      if (!r.points.empty()) {
        const float k = area_k / std::max(std::fabs(r.offset), 0.01f) * static_cast<float>(r.pixel_count) /
                        static_cast<float>(r.points.size());
        // Without pixels (points from another segmentation, e.g. a voxel grid) each point
        // stands for an equal share of the area.
        const bool uniform = r.pixels.empty();
        const float ku = r.area / static_cast<float>(r.points.size());
        for (const auto& q : r.points) {
          const float z = q.z();
          const int b = bin_of(z);
          if (b < steps) bins[b] += uniform ? ku : z * z * z * k;
        }
      }
      for (int s = 1; s < steps; ++s) bins[s] += bins[s - 1];
    }
    for (int s = 0; s < steps && chosen < 0; ++s) {
      float best = 0.f;
      for (std::size_t c = 0; c < cand.size(); ++c) {
        const float a = window_area_[c * static_cast<std::size_t>(steps) + s];
        if (a >= cfg_.min_area && a > best) {
          best = a;
          chosen = cand[c];
        }
      }
    }
  }
  if (chosen < 0) chosen = strip_at_feet(regions, cand);
  if (chosen >= 0) {
    // The user stands on the floor: of two parallel candidates a riser or more apart, the floor
    // is the lower one when it reaches as near the user's feet in the view (a seat, a first step
    // or a landing right ahead is nearer the camera and can be bigger in the window). Nearness
    // is the angle from the nadir: in metres a higher plane seen at the bottom of the view is
    // always nearer than the lower floor seen beside it.
    const float cos_par = std::cos(cfg_.horizontal_tolerance);
    const int first = chosen;
    float best = reach(regions[first]).angle;
    for (int i : cand) {
      if (i == first) continue;
      const PlaneRegion& r = regions[i];
      // A patch of a lower plane at the user's feet outranks a bigger step ahead (but not a sliver).
      if (r.area < 0.25f * cfg_.min_area || r.normal.dot(regions[first].normal) < cos_par) continue;
      if (r.offset - regions[chosen].offset < cfg_.inlier_distance) continue;  // only lower planes
      const float a = reach(r).angle;
      if (a <= best + cfg_.view_edge_angle) {
        best = std::min(best, a);
        chosen = i;
      }
    }
  }
  return chosen;
}

bool FloorDetector::level_confirmed(const std::vector<PlaneRegion>& regions, int c) const {
  // A strip a few cm deep fixes its normal poorly (a 4 cm sliver of floor under a first riser fitted
  // 5 deg off, 7 cm off in height); a level of min_area or more in view fixes "up" well. The strip's
  // normal must agree with such a level's, within what a well-fixed plane of a few hundred pixels
  // per cm of depth gives.
  constexpr float kAgreement = 0.035f;  // rad (2 deg)
  const float cos_agree = std::cos(kAgreement);
  for (std::size_t j = 0; j < regions.size(); ++j)
    if (static_cast<int>(j) != c && regions[j].area >= cfg_.min_area &&
        regions[j].normal.dot(regions[c].normal) >= cos_agree)
      return true;
  return false;
}

bool FloorDetector::could_be_floor(float below) const {
  if (rig_height_) return std::fabs(below - *rig_height_) <= cfg_.rig_height_tolerance;
  // Not yet learned: the usual chest rig is the prior.
  return below >= cfg_.usual_height_min && below <= cfg_.usual_height_max;
}

bool FloorDetector::agrees_with_rig(const PlaneRegion& r) const {
  float tilt, roll;
  tilt_roll_from_up(r.normal, tilt, roll);
  if (std::fabs(roll) > cfg_.roll_max || !could_be_floor(r.offset)) return false;
  if (rig_tilt_) return std::fabs(tilt - *rig_tilt_) <= cfg_.rig_tilt_tolerance;
  return tilt >= cfg_.usual_tilt_min && tilt <= cfg_.usual_tilt_max;
}

int FloorDetector::strip_at_feet(const std::vector<PlaneRegion>& regions,
                                 const std::vector<int>& cand) const {
  // Standing 0.5-0.7 m from an edge (a platform, a dock, a hole) or at the foot of a flight that
  // fills the view, the floor in view is a strip along the view's bottom edge, smaller than
  // min_area in every window. Its area says little; where it lies says much: the level the view's
  // bottom edge sees (the border nearest the user's feet), at the height and tilt of the rig
  // (learned, or the usual chest rig while not yet learned). Such a strip is offered as the floor
  // when no bigger one is; every check of a floor (nothing lower nearer the feet, no tread, no level
  // underfoot above it) then applies as to any other candidate.
  const int W = K_.width, H = K_.height;
  if (W <= 0 || H <= 0) return -1;
  const int edge_row = H - 1 - std::max(2, H / 60);  // rows this low are the view's bottom edge
  int best = -1;
  for (int i : cand) {
    const PlaneRegion& r = regions[i];
    if (r.pixels.empty() || !agrees_with_rig(r) || !level_confirmed(regions, i)) continue;
    int lowest_row = 0;
    for (int p : r.pixels) lowest_row = std::max(lowest_row, p / W);
    if (lowest_row < edge_row) continue;  // its near edge is seen: not what the user stands on
    if (best < 0 || r.area > regions[best].area) best = i;
  }
  return best;
}

}  // namespace stairguide
