#include "stairguide/stairs/stair_detection.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "stairguide/stairs/stair_checks.hpp"

namespace stairguide {
namespace {
constexpr int kDoubtfulMinPoints = 100;   // a lower level this big nearer than the floor ...
constexpr float kDoubtfulMargin = 0.15f;  // ... by this much (m) makes the floor doubtful
// Hidden first steps: at most this many steps under the bottom of the view. From a chest camera
// looking 30-60 degrees down, standing at the edge, two are hidden at most; more would be a level
// far below that no one would call the next flight.
constexpr int kMaxHiddenSteps = 3;
// The first level seen reaches the bottom of the view when its lowest image row (as y/z) is within
// this of the lowest row any region reaches (about 10 px at a 525 px focal length; regions lose a
// few rows at the border to the normal estimation).
constexpr float kViewBottomSlack = 0.02f;
// A first step found by its stack (build_stack) lies within this of the floor seen from above: a
// person or a wall end (about half a metre) hides the foot of the flight, plus the usual radius.
constexpr float kStackReach = 1.0f;
// A lone first level is set aside for another first step at most this many times (a head, then
// the shoulders).
constexpr int kMaxLoneLevels = 3;
// A candidate this many times larger than another, both one riser above the last level but at
// heights apart, takes the next level's place (see sweep).
constexpr int kBiggerLevel = 4;
// m, two consecutive rises of one flight differ by less than this: the codes allow about 1 cm
// between a flight's risers, a floor finish or a worn first step a little more, and the heights of
// far levels carry a couple of cm of noise. Boxes stacked in steps rose 25, 20 and 25 cm
// (world2_boxes seed 801 #10, told as a flight while the limit was 6 cm).
constexpr float kRiseMismatch = 0.04f;
// A riser (riser_seen): an upright face between two levels. Its points lie within this of the
// heights between them (m: the nosing's rows and the depth noise at a few metres) ...
constexpr float kRiserBandSlack = 0.03f;
// ... and all but this share of them (a few rows of the tread above taken into the face; the same
// share of the upper level may lie before it, beyond the nosing) ...
constexpr float kRiserOutside = 0.1f;
// ... reach within this of both levels (m: the rows lost at a region's border to the normals, a
// nosing's shadow under the tread) ...
constexpr float kRiserReach = 0.05f;
// ... its top within this of the upper level's points (m: the face meets the tread's edge; a
// book standing on a shelf board stops a couple of cm under the next board, behind its front) ...
constexpr float kRiserTouch = 0.05f;
// ... the upper level behind it but for a nosing this deep (m; the codes allow 2-4 cm) ...
constexpr float kRiserNosing = 0.06f;
// ... and across this share of the upper level's width (a riser is solid from one end of the step
// to the other; a handrail post, a stringer's facet or a row of books is not).
constexpr float kRiserCover = 0.5f;
// m, slack on the depth a tread holds before the next level (see going(): a quantile of noisy
// points, and a nosing over it).
constexpr float kGoingSlack = 0.02f;
// An upright region smaller than this (points) is no riser.
constexpr int kRiserMinPoints = 30;
}  // namespace

StairDetection::StairDetection(const ClassificationConfig& classification, const StairDetectionConfig& config)
    : cls_(classification), cfg_(config) {}

void StairDetection::prepare(const SceneResult& scene, int region, Candidate& c) const {
  const PlaneRegion& r = scene.regions[static_cast<std::size_t>(region)];
  c.region = region;
  const std::size_t n = r.points.size();
  const std::size_t cap = static_cast<std::size_t>(std::max(1, cfg_.connection_max_points));
  // An even stride keeps the sample spread over the whole region, which is what the neighbour test
  // needs; the required count is scaled by the stride so "10 points" keeps its meaning.
  c.stride = static_cast<int>((n + cap - 1) / cap);
  if (c.stride < 1) c.stride = 1;
  c.sample.clear();
  c.lo.setConstant(std::numeric_limits<float>::max());
  c.hi.setConstant(-std::numeric_limits<float>::max());
  for (std::size_t i = 0; i < n; i += static_cast<std::size_t>(c.stride)) {
    c.sample.push_back(r.points[i]);
    c.lo = c.lo.cwiseMin(r.points[i]);
    c.hi = c.hi.cwiseMax(r.points[i]);
  }
}

namespace {
// The lowest image row (as y/z: no intrinsics needed) that a region's points reach.
float lowest_row(const PlaneRegion& r) {
  float low = -std::numeric_limits<float>::max();
  for (const Eigen::Vector3f& p : r.points)
    if (p.z() > 0.05f) low = std::max(low, p.y() / p.z());
  return low;
}
}  // namespace

float StairDetection::view_bottom(const SceneResult& scene) const {
  float low = -std::numeric_limits<float>::max();
  for (const PlaneRegion& r : scene.regions) low = std::max(low, lowest_row(r));
  return low;
}

bool StairDetection::connected(const Candidate& c, const LevelSeed& level, bool horizontal,
                               float radius) const {
  const float r = radius > 0.f ? radius : cfg_.connection_radius, r2 = r * r;
  const int need = std::max(1, (cfg_.connection_min_points + c.stride - 1) / c.stride);
  int found = 0;
  for (int region : level.regions) {
    const int slot = region_slot_[static_cast<std::size_t>(region)];
    if (slot < 0) continue;
    const Candidate& l = pool_[static_cast<std::size_t>(slot)];
    if (l.sample.empty()) continue;
    // Boxes farther apart than the radius cannot hold a pair of neighbours (in 3D; the horizontal
    // test is rare and runs on the whole samples).
    if (!horizontal) {
      const Eigen::Vector3f gap = (l.lo - c.hi).cwiseMax(c.lo - l.hi).cwiseMax(Eigen::Vector3f::Zero());
      if (gap.squaredNorm() > r2) continue;
    }
    const float reach = horizontal ? std::numeric_limits<float>::max() : r;
    const Eigen::Vector3f blo = l.lo.array() - reach, bhi = l.hi.array() + reach;
    for (const Eigen::Vector3f& p : c.sample) {
      if ((p.array() < blo.array()).any() || (p.array() > bhi.array()).any()) continue;
      for (const Eigen::Vector3f& q : l.sample) {
        Eigen::Vector3f d = p - q;
        if (horizontal) d -= up_ * up_.dot(d);
        if (d.squaredNorm() <= r2) {
          if (++found >= need) return true;
          break;
        }
      }
    }
  }
  return false;
}

void StairDetection::build(int direction, StairHypothesis& hyp) {
  hyp.direction = direction;
  hyp.hidden_steps = 0;
  hyp.levels.resize(1);
  LevelSeed& floor = hyp.levels[0];
  floor.index = 0;
  floor.height = 0.f;
  floor.point_count = 0;
  floor.regions.clear();
  for (int slot : floor_slots_) {
    floor.regions.push_back(pool_[static_cast<std::size_t>(slot)].region);
    floor.point_count += static_cast<int>(pool_[static_cast<std::size_t>(slot)].sample.size()) *
                         pool_[static_cast<std::size_t>(slot)].stride;
  }
  // Read now: sweep() grows hyp.levels, and `floor` (a reference into it) dangles after a
  // reallocation (ThreadSanitizer saw the read of freed memory below, in a walk's frame).
  const bool floor_seen = !floor.regions.empty();

  // Candidates on this side of the floor, sorted by distance to it (Algorithm 1: sortByHeight).
  order_.clear();
  for (int slot : candidates_)
    if (pool_[static_cast<std::size_t>(slot)].height * static_cast<float>(direction) > 0.f)
      order_.push_back(slot);
  std::sort(order_.begin(), order_.end(), [&](int a, int b) {
    return std::fabs(pool_[static_cast<std::size_t>(a)].height) <
           std::fabs(pool_[static_cast<std::size_t>(b)].height);
  });
  hyp.candidates = static_cast<int>(order_.size());
  assigned_.assign(order_.size(), 0);
  sweep(hyp);
  if (hyp.step_levels() == 1) {
    // A lone level, nothing one riser beyond it: the first candidate at a first step's height
    // that touches the floor may be a person's head or shoulders standing in a stairwell, or a
    // sliver at its rim, and it keeps the real first step (a few cm lower or higher) out. Try the
    // other candidates as the first step, the lone level left out, and keep a flight (two levels
    // or more) if they give one. A lone level that is the only thing there stays as it was.
    saved_levels_ = hyp.levels;
    saved_assigned_ = assigned_;
    bool found = false;
    for (int tries = 0; tries < kMaxLoneLevels && !found; ++tries) {
      left_out_ = assigned_;  // the lone levels so far stay out of the sweep
      hyp.levels.resize(1);
      sweep(hyp);
      if (hyp.step_levels() >= 2) {
        for (std::size_t i = 0; i < assigned_.size(); ++i)
          if (left_out_[i]) assigned_[i] = 0;
        found = true;
      } else if (hyp.step_levels() == 0) {
        break;
      }
    }
    if (!found) {
      hyp.levels = saved_levels_;
      assigned_ = saved_assigned_;
    }
  }
  if (direction < 0 && floor_tracked_ && floor_seen) {
    if (hyp.step_levels() == 0) {
      build_hidden(hyp);
    } else if (hyp.step_levels() == 1) {
      // One level alone one riser down, and nothing one riser below it: a sliver at the stairwell's
      // rim (a rail, a wall top mixed with the floor) can take the first step's place and hide a
      // flight whose first treads are under the view. Try the hidden-first-steps route on the
      // other candidates; its stack (evenly spaced, a whole number of risers below the tracked
      // floor, reaching the bottom of the view) replaces the lone level.
      saved_levels_ = hyp.levels;
      saved_assigned_ = assigned_;
      hyp.levels.resize(1);
      std::fill(assigned_.begin(), assigned_.end(), 0);
      if (!build_hidden(hyp)) {
        hyp.levels = saved_levels_;
        assigned_ = saved_assigned_;
      }
    }
  }
  // A rise beyond the code's H_max (up to the physical 25 cm) is taken for a step on physical
  // evidence that it is climbed as one, not on the level heights alone: two shelf boards 25 cm
  // apart, the lower 25 cm up, are a flight of two steps by their heights (shelves_static seed 4
  // view 4). From the floor, its riser must be seen: a solid face from the floor up to the
  // level's near edge (a shelf board has open space, or the wall far behind, under it), or, with
  // open risers, the stack above it must be a flight's profile: the level and the next each
  // holding a foot before the one above (world2_steep seed 913 #15, four open treads, which the
  // three-level rule had let through; one such pair is not enough: shelves_static seed 4 #4, two
  // boards 25 cm apart, measured one 36 cm deep before the other). Above a
  // tread, that tread must hold a foot before the level (a going of a tread at least: open risers
  // show no riser; a shelf's boards stand flush above each other, a bed frame's rim is 3-5 cm wide
  // before the mattress), or, cut by the bottom of the view so that its depth is not seen, have
  // the riser. A cellar or attic stair with 24-25 cm risers shows all of it (world2_steep seed
  // 801 #7, two treads in view, was silenced while three levels were asked for). Going down the
  // risers face away from the user and are never seen, and nothing standing on a floor lies below
  // it: a descent is not asked.
  if (hyp.step_levels() > 0 && hyp.hidden_steps == 0 && direction > 0) {
    const float code_max = cls_.step_height_max + cfg_.height_tolerance;
    const float foot = WalkableLimits{}.tread_min - kGoingSlack;
    for (int k = 1; k <= hyp.step_levels(); ++k) {
      const float rise = std::fabs(hyp.levels[static_cast<std::size_t>(k)].height) -
                         std::fabs(hyp.levels[static_cast<std::size_t>(k - 1)].height);
      if (rise <= code_max) continue;
      const bool climbed =
          k == 1 ? riser_seen(hyp, k) ||
                       (hyp.step_levels() >= 3 && going(hyp, 2) >= foot && going(hyp, 3) >= foot)
                 : going(hyp, k) >= foot || (reaches_view_bottom(hyp, k - 1) && riser_seen(hyp, k));
      if (climbed) continue;
      for (std::size_t j = static_cast<std::size_t>(k); j < hyp.levels.size(); ++j)
        for (int region : hyp.levels[j].regions)
          for (std::size_t i = 0; i < order_.size(); ++i)
            if (pool_[static_cast<std::size_t>(order_[i])].region == region) assigned_[i] = 0;
      hyp.levels.resize(static_cast<std::size_t>(k));
      break;
    }
  }
  if (hyp.step_levels() == 0 && direction > 0 && floor_seen) build_stack(hyp);

  hyp.rejected = 0;
  for (char a : assigned_)
    if (!a) ++hyp.rejected;
  if (hyp.candidates == 0)
    hyp.verdict = StairVerdict::kNoCandidates;
  else
    hyp.verdict = hyp.step_levels() > 0 ? StairVerdict::kDetected : StairVerdict::kNoFirstStep;
}

namespace {
// m, the wearer's own feet lie within this of the camera's vertical (a chest or waist camera hangs
// 0.1-0.2 m ahead of the feet, the toes reach 0.3 m ahead of it).
constexpr float kFeetReach = 0.5f;

// The wearer's own foot (above the floor: it stands on it): a horizontal patch shorter in every direction
// than the least width of a step cut by the view's border (WalkableLimits::width_cut_min), every point of it
// within the feet's reach of the camera's vertical. It starts no level: standing on the floor before the
// flight, the user's feet are never on its first step. A foot's top 8-11 cm up at the bottom of
// the view took the first level, and the flight behind it came out "a level stands on the one
// below it" (world2_legs seed 913 #6) or its first tread was left out of the stack.
bool own_foot(const SceneResult* scene, int region, const Eigen::Vector3f& up) {
  if (!scene) return false;
  const PlaneRegion& r = scene->regions[static_cast<std::size_t>(region)];
  if (r.rect_length_major >= WalkableLimits{}.width_cut_min || r.points.empty()) return false;
  const std::size_t stride = std::max<std::size_t>(1, r.points.size() / 200);
  for (std::size_t i = 0; i < r.points.size(); i += stride) {
    const Eigen::Vector3f& p = r.points[i];
    if ((p - up * up.dot(p)).norm() > kFeetReach) return false;
  }
  return true;
}
}  // namespace

void StairDetection::sweep(StairHypothesis& hyp) {
  // hyp.levels grows below: the floor is read through the vector each time, never a held reference.
  const bool floor_visible = !hyp.levels[0].regions.empty();
  const float hmin = cls_.step_height_min - cfg_.height_tolerance;
  const float hmax = step_rise_max(cls_) + cfg_.height_tolerance;
  // The first level may be a curb lower than H_min; modelling decides whether a low level is one.
  const float first_min = std::min(cls_.step_height_min, cfg_.curb_height_min) - cfg_.height_tolerance;
  // Going down from a tracked floor, a first level deeper than the code's riser is left to the
  // hidden-first-steps route (build_hidden), which counts the risers to it: two 13 cm steps under
  // the view (26 cm) are within the physical riser range and were taken for one step, every step
  // number after them one off (the top of a descent, test_stairs_edge).
  const float first_max =
      hyp.direction < 0 && floor_tracked_ ? cls_.step_height_max + cfg_.height_tolerance : hmax;

  // Repeat the sweep until nothing changes: a fragment of a level that only touches a later level
  // (split by an occluding person) joins on the next sweep.
  bool changed = true;
  while (changed) {
    changed = false;
    for (std::size_t i = 0; i < order_.size(); ++i) {
      if (assigned_[i]) continue;
      const Candidate& c = pool_[static_cast<std::size_t>(order_[i])];
      const float s = std::fabs(c.height);
      const int n_levels = hyp.step_levels();
      if (n_levels == 0) {
        if (s < first_min || s > first_max) continue;
        if (c.height > 0.f && own_foot(scene_, c.region, up_)) continue;
        if (floor_visible && !connected(c, hyp.levels[0])) continue;
        LevelSeed& l = hyp.levels.emplace_back();
        l.index = 1;
        l.height = c.height;
        l.point_count = static_cast<int>(c.sample.size()) * c.stride;
        l.regions.assign(1, c.region);
        assigned_[i] = 1;
        changed = true;
        continue;
      }
      // Same height as an existing level: fuse when connected to the levels around it.
      int same = -1;
      float best = cfg_.same_level_tolerance;
      for (int j = 1; j <= n_levels; ++j) {
        const float d = std::fabs(s - std::fabs(hyp.levels[static_cast<std::size_t>(j)].height));
        if (d <= best) {
          best = d;
          same = j;
        }
      }
      const float top = std::fabs(hyp.levels.back().height);
      // Two candidates may both lie one riser above the last level, at heights apart: a sliver at
      // a tread's nosing or a rail top 13 cm down, and the whole next tread 17 cm down. Taking the
      // nearer in height would stop the flight there (the rest no longer a riser apart), so a much
      // larger one nearer the riser so far takes the place (bigger_next_level) and the sliver
      // stays out. Nearer the riser only: a far tread seen as a sliver is the next level, not the
      // big landing 5 cm above it.
      bool next = same < 0 && s - top >= hmin && s - top <= hmax;
      // A flight has one riser: the next level lies about as far above the last as the last above
      // the one below it (the floor for the first; unknown on the hidden-steps route, where the
      // first seen level lies a number of risers down). A wearer's foot 10 cm up at the bottom of
      // the view took the first level, the second tread 25 cm above it the next, and the first
      // tread between them (13 times the foot's points) was left out: "a level stands on the one
      // below it" (world2_legs seed 912 #1 and #3, once the range reached the physical 25 cm).
      if (next && (n_levels >= 2 || !hidden_sweep_)) {
        const float below =
            n_levels >= 2 ? std::fabs(hyp.levels[static_cast<std::size_t>(n_levels - 1)].height) : 0.f;
        if (std::fabs((s - top) - (top - below)) > kRiseMismatch) next = false;
      }
      if (same < 0 && !next) continue;
      if (same < 0 && c.height > 0.f && own_foot(scene_, c.region, up_)) continue;
      bool link = false;
      for (int j = 0; j <= n_levels && !link; ++j) {
        const LevelSeed& l = hyp.levels[static_cast<std::size_t>(j)];
        // Levels farther apart in height than the radius cannot be within it.
        if (std::fabs(s - std::fabs(l.height)) > cfg_.connection_radius) continue;
        link = connected(c, l);
      }
      if (!link) continue;
      const int pts = static_cast<int>(c.sample.size()) * c.stride;
      if (next && bigger_next_level(hyp, i, top, pts)) continue;
      if (same >= 0) {
        LevelSeed& l = hyp.levels[static_cast<std::size_t>(same)];
        l.height = (l.height * static_cast<float>(l.point_count) + c.height * static_cast<float>(pts)) /
                   static_cast<float>(l.point_count + pts);
        l.point_count += pts;
        l.regions.push_back(c.region);
      } else {
        LevelSeed& l = hyp.levels.emplace_back();
        l.index = hyp.levels[static_cast<std::size_t>(n_levels)].index + 1;
        l.height = c.height;
        l.point_count = pts;
        l.regions.assign(1, c.region);
      }
      assigned_[i] = 1;
      changed = true;
    }
  }
}

bool StairDetection::bigger_next_level(const StairHypothesis& hyp, std::size_t i, float top, int pts) const {
  const int n_levels = hyp.step_levels();
  // The riser so far: the levels' own spacing, or the first level's height above the floor (not on
  // the hidden-first-steps route, where that is a number of risers yet unknown).
  float riser = 0.f;
  if (n_levels >= 2)
    riser = (top - std::fabs(hyp.levels[1].height)) / static_cast<float>(n_levels - 1);
  else if (!hidden_sweep_)
    riser = top;
  if (riser <= 0.f) return false;
  const float hmin = cls_.step_height_min - cfg_.height_tolerance;
  const float hmax = step_rise_max(cls_) + cfg_.height_tolerance;
  const float expected = top + riser;
  const float s = std::fabs(pool_[static_cast<std::size_t>(order_[i])].height);
  for (std::size_t j = 0; j < order_.size(); ++j) {
    if (j == i || assigned_[j]) continue;
    const Candidate& o = pool_[static_cast<std::size_t>(order_[j])];
    const float so = std::fabs(o.height);
    if (so - top < hmin || so - top > hmax || std::fabs(so - s) <= cfg_.same_level_tolerance) continue;
    if (std::fabs(so - expected) >= std::fabs(s - expected)) continue;
    if (static_cast<int>(o.sample.size()) * o.stride < kBiggerLevel * pts) continue;
    for (int k = 0; k <= n_levels; ++k) {
      const LevelSeed& l = hyp.levels[static_cast<std::size_t>(k)];
      if (std::fabs(so - std::fabs(l.height)) > cfg_.connection_radius) continue;
      if (connected(o, l)) return true;
    }
  }
  return false;
}

void StairDetection::level_points(const StairHypothesis& hyp, int k,
                                  std::vector<Eigen::Vector3f>& pts) const {
  pts.clear();
  if (k == 0) {
    for (int slot : floor_slots_) {
      const Candidate& c = pool_[static_cast<std::size_t>(slot)];
      pts.insert(pts.end(), c.sample.begin(), c.sample.end());
    }
    return;
  }
  for (int region : hyp.levels[static_cast<std::size_t>(k)].regions) {
    const int slot = region_slot_[static_cast<std::size_t>(region)];
    if (slot < 0) continue;
    const Candidate& c = pool_[static_cast<std::size_t>(slot)];
    pts.insert(pts.end(), c.sample.begin(), c.sample.end());
  }
}

bool StairDetection::reaches_view_bottom(const StairHypothesis& hyp, int k) {
  if (!scene_) return false;
  if (view_bottom_ == -std::numeric_limits<float>::max()) view_bottom_ = view_bottom(*scene_);
  for (int region : hyp.levels[static_cast<std::size_t>(k)].regions)
    if (lowest_row(scene_->regions[static_cast<std::size_t>(region)]) >= view_bottom_ - kViewBottomSlack)
      return true;
  return false;
}

float StairDetection::going(const StairHypothesis& hyp, int k) {
  // Each point of level k-1 (a tread) has the horizontal distance to the nearest point of level k
  // before it: a tread's points reach a going in front of the next tread; a shelf board's seen
  // part lies under the board above it (about 0), a bed frame's rim within its 3-5 cm of the
  // mattress. The 90th percentile: how deep a foot finds room.
  if (!scene_ || k < 2) return 0.f;
  level_points(hyp, k - 1, lower_);
  level_points(hyp, k, upper_);
  if (lower_.empty() || upper_.empty()) return 0.f;
  dist_.clear();
  for (const Eigen::Vector3f& p : lower_) {
    float best = std::numeric_limits<float>::max();
    for (const Eigen::Vector3f& q : upper_) {
      Eigen::Vector3f d = p - q;
      d -= up_ * up_.dot(d);
      best = std::min(best, d.squaredNorm());
    }
    dist_.push_back(best);
  }
  const std::size_t i = dist_.size() * 9 / 10;
  std::nth_element(dist_.begin(), dist_.begin() + static_cast<long>(i), dist_.end());
  // Nor deeper than the level is on average (its area over its length): a rim seen round a corner
  // of the mattress lies far from the part of the mattress in view, yet is a strip a few cm wide.
  float area = 0.f, length = 0.f;
  for (int region : hyp.levels[static_cast<std::size_t>(k - 1)].regions) {
    const PlaneRegion& r = scene_->regions[static_cast<std::size_t>(region)];
    area += r.area;
    length = std::max(length, r.rect_length_major);
  }
  const float mean_depth = length > 0.f ? area / length : 0.f;
  const float room = std::min(std::sqrt(dist_[i]), mean_depth);
  // Nor more than the upper level's near edge lies beyond the lower one's, along the horizontal
  // from the lower level's middle to the upper one's (each edge a 5% quantile): a shelf's boards
  // stand flush above each other, and one seen only in part (cut by the top of the view) still
  // starts where the board under it starts.
  Eigen::Vector3f cl = Eigen::Vector3f::Zero(), cu = Eigen::Vector3f::Zero();
  for (const auto& p : lower_) cl += p;
  for (const auto& p : upper_) cu += p;
  Eigen::Vector3f dir = cu / static_cast<float>(upper_.size()) - cl / static_cast<float>(lower_.size());
  dir -= up_ * up_.dot(dir);
  if (dir.norm() < 1e-3f) return 0.f;
  dir.normalize();
  auto near_edge = [&](const std::vector<Eigen::Vector3f>& pts) {
    dist_.clear();
    for (const auto& p : pts) dist_.push_back(dir.dot(p));
    const std::size_t j = dist_.size() / 20;
    std::nth_element(dist_.begin(), dist_.begin() + static_cast<long>(j), dist_.end());
    return dist_[j];
  };
  return std::min(room, near_edge(upper_) - near_edge(lower_));
}

bool StairDetection::riser_seen(const StairHypothesis& hyp, int k) {
  if (!scene_ || k < 1 || k >= static_cast<int>(hyp.levels.size())) return false;
  const float lo_h = std::fabs(hyp.levels[static_cast<std::size_t>(k - 1)].height);
  const float hi_h = std::fabs(hyp.levels[static_cast<std::size_t>(k)].height);
  level_points(hyp, k, upper_);
  if (upper_.empty()) return false;
  const float sin_vert = std::sin(cls_.parallel_threshold);
  const float touch2 = kRiserTouch * kRiserTouch;
  float cover = 0.f;
  for (const PlaneRegion& r : scene_->regions) {
    if (static_cast<int>(r.points.size()) < kRiserMinPoints || std::fabs(r.normal.dot(up_)) > sin_vert)
      continue;
    // Its horizontal normal, towards the camera: the side the lower level (and the user) is on.
    Eigen::Vector3f n = r.normal - up_ * up_.dot(r.normal);
    if (n.norm() < 1e-3f) continue;
    n.normalize();
    if (n.dot(r.centroid) > 0.f) n = -n;
    const Eigen::Vector3f e = up_.cross(n);  // along the face, horizontal
    const std::size_t stride = std::max<std::size_t>(1, r.points.size() / 200);
    int in_band = 0, total = 0;
    float bottom = std::numeric_limits<float>::max(), top = -std::numeric_limits<float>::max();
    float e_lo = std::numeric_limits<float>::max(), e_hi = -std::numeric_limits<float>::max();
    for (std::size_t i = 0; i < r.points.size(); i += stride) {
      const float h = up_.dot(r.points[i]) + up_offset_;
      ++total;
      if (h < lo_h - kRiserBandSlack || h > hi_h + kRiserBandSlack) continue;
      ++in_band;
      bottom = std::min(bottom, h);
      top = std::max(top, h);
      const float a = e.dot(r.points[i]);
      e_lo = std::min(e_lo, a);
      e_hi = std::max(e_hi, a);
    }
    if (in_band == 0 || static_cast<float>(total - in_band) > kRiserOutside * static_cast<float>(total))
      continue;
    if (bottom > lo_h + kRiserReach || top < hi_h - kRiserReach) continue;
    // The upper level behind the face (a nosing's depth allowed), its extent along the face, and
    // the face's top meeting it.
    int behind = 0;
    bool touches = false;
    float u_lo = std::numeric_limits<float>::max(), u_hi = -std::numeric_limits<float>::max();
    for (const Eigen::Vector3f& q : upper_) {
      if (n.dot(q - r.centroid) < kRiserNosing) ++behind;
      const float a = e.dot(q);
      u_lo = std::min(u_lo, a);
      u_hi = std::max(u_hi, a);
    }
    if (static_cast<float>(behind) < (1.f - kRiserOutside) * static_cast<float>(upper_.size())) continue;
    for (std::size_t i = 0; i < r.points.size() && !touches; i += stride) {
      const Eigen::Vector3f& p = r.points[i];
      if (up_.dot(p) + up_offset_ < hi_h - kRiserReach) continue;
      for (const Eigen::Vector3f& q : upper_)
        if ((p - q).squaredNorm() <= touch2) {
          touches = true;
          break;
        }
    }
    if (!touches || u_hi <= u_lo) continue;
    cover += std::max(0.f, std::min(e_hi, u_hi) - std::max(e_lo, u_lo)) / (u_hi - u_lo);
    if (cover >= kRiserCover) return true;
  }
  return false;
}

bool StairDetection::build_hidden(StairHypothesis& hyp) {
  const float hmin = cls_.step_height_min - cfg_.height_tolerance;
  const float hmax = step_rise_max(cls_) + cfg_.height_tolerance;
  const LevelSeed& floor = hyp.levels[0];
  if (!scene_) return false;
  view_bottom_ = view_bottom(*scene_);
  // The seed: the candidate nearest the floor in height that is too low to be the first step,
  // reaches the bottom of the view and lies beside the floor seen from above. Candidates are in
  // height order, so the first that qualifies is the first level seen.
  for (std::size_t i = 0; i < order_.size(); ++i) {
    if (assigned_[i]) continue;
    const Candidate& c = pool_[static_cast<std::size_t>(order_[i])];
    const float s = std::fabs(c.height);
    if (s <= hmax) continue;
    if (s > static_cast<float>(kMaxHiddenSteps + 1) * hmax) break;
    if (static_cast<int>(c.sample.size()) * c.stride < kDoubtfulMinPoints) continue;
    if (lowest_row(scene_->regions[static_cast<std::size_t>(c.region)]) < view_bottom_ - kViewBottomSlack)
      continue;
    if (!connected(c, floor, true)) continue;
    LevelSeed& l = hyp.levels.emplace_back();
    l.index = 1;  // provisional: set from the stack's spacing below
    l.height = c.height;
    l.point_count = static_cast<int>(c.sample.size()) * c.stride;
    l.regions.assign(1, c.region);
    assigned_[i] = 1;
    hidden_sweep_ = true;  // the first level's risers are not known yet
    sweep(hyp);
    hidden_sweep_ = false;
    // The stack's own spacing is the riser; the first level seen must lie a whole number of them
    // (two or more) below the floor. One level alone says nothing of the riser.
    const int n = hyp.step_levels();
    bool ok = n >= 2;
    int m = 0;
    if (ok) {
      const float first = std::fabs(hyp.levels[1].height), last = std::fabs(hyp.levels.back().height);
      const float riser = (last - first) / static_cast<float>(n - 1);
      ok = riser >= hmin && riser <= hmax;
      if (ok) {
        m = static_cast<int>(std::lround(first / riser));
        ok = m >= 2 && m <= kMaxHiddenSteps + 1 &&
             std::fabs(first - static_cast<float>(m) * riser) <= cfg_.same_level_tolerance;
      }
    }
    if (ok) {
      for (int k = 1; k <= n; ++k) hyp.levels[static_cast<std::size_t>(k)].index = m + k - 1;
      hyp.hidden_steps = m - 1;
      return true;
    }
    // Not a staircase with hidden first steps: undo, nothing else is tried (the next candidate
    // down would be a level of this same stack).
    hyp.levels.resize(1);
    assigned_.assign(order_.size(), 0);
    return false;
  }
  return false;
}

bool StairDetection::build_stack(StairHypothesis& hyp) {
  // The connection rule (a first step must touch the floor) keeps a table top or a bench seat,
  // floating above the floor, from being a first step. A level that does not touch the floor is
  // still a first step when it lies one riser above the floor, beside the floor seen from above
  // (a person or a wall hides where the flight meets the floor), and carries a flight: at least
  // one more level, each a whole riser above the last, all with the same riser inside the building
  // code. Furniture does not stack that way; shelves that happen to (boards one riser apart) stand
  // straight above each other and have no tread, which modelling refuses.
  const float hmin = cls_.step_height_min - cfg_.height_tolerance;
  const float hmax = cls_.step_height_max + cfg_.height_tolerance;
  const LevelSeed& floor = hyp.levels[0];
  for (std::size_t i = 0; i < order_.size(); ++i) {
    if (assigned_[i]) continue;
    const Candidate& c = pool_[static_cast<std::size_t>(order_[i])];
    const float s = std::fabs(c.height);
    if (s < hmin) continue;
    if (s > hmax) break;  // candidates are in height order: none higher can be the first step
    if (static_cast<int>(c.sample.size()) * c.stride < kDoubtfulMinPoints) continue;
    if (!connected(c, floor, true, kStackReach)) continue;
    LevelSeed& l = hyp.levels.emplace_back();
    l.index = 1;
    l.height = c.height;
    l.point_count = static_cast<int>(c.sample.size()) * c.stride;
    l.regions.assign(1, c.region);
    assigned_[i] = 1;
    sweep(hyp);
    const int n = hyp.step_levels();
    bool ok = n >= 2;
    if (ok) {
      const float first = std::fabs(hyp.levels[1].height), last = std::fabs(hyp.levels.back().height);
      const float riser = (last - first) / static_cast<float>(n - 1);
      ok = riser >= hmin && riser <= hmax;
      // Every level, the first included, a whole riser above the one below it (the floor at 0).
      for (int k = 1; k <= n && ok; ++k)
        ok = std::fabs(std::fabs(hyp.levels[static_cast<std::size_t>(k)].height) -
                       static_cast<float>(k) * riser) <= cfg_.same_level_tolerance;
    }
    if (ok) return true;
    // Not a flight: undo and try the next candidate at step height (another piece of furniture
    // may sit beside a real first step).
    hyp.levels.resize(1);
    std::fill(assigned_.begin(), assigned_.end(), 0);
  }
  return false;
}

void StairDetection::run(const SceneResult& scene, StairDetectionOutput& out) {
  out.candidates = 0;
  out.ascending.levels.clear();
  out.descending.levels.clear();
  out.ascending.candidates = out.descending.candidates = 0;
  out.ascending.rejected = out.descending.rejected = 0;
  out.ascending.hidden_steps = out.descending.hidden_steps = 0;
  out.ascending.verdict = out.descending.verdict = StairVerdict::kNoCandidates;
  out.ascending.direction = 1;
  out.descending.direction = -1;
  if (!scene.floor_found) {
    out.verdict = StairVerdict::kNoFloor;
    out.ascending.verdict = out.descending.verdict = StairVerdict::kNoFloor;
    return;
  }
  // Heights come from the floor transform: y_F of a camera point is its height above the floor.
  const Eigen::Matrix3f R = scene.T_floor_camera.linear();
  const Eigen::Vector3f up = R.row(1).transpose();
  const float up_offset = scene.T_floor_camera.translation().y();
  up_ = up;
  up_offset_ = up_offset;
  floor_tracked_ = scene.floor_tracked;
  view_bottom_ = -std::numeric_limits<float>::max();
  const float cos_parallel = std::cos(cls_.parallel_threshold);

  region_slot_.assign(scene.regions.size(), -1);
  candidates_.clear();
  floor_slots_.clear();
  used_ = 0;
  auto take_slot = [&](int region) {
    if (static_cast<std::size_t>(used_) >= pool_.size()) pool_.emplace_back();
    const int slot = used_++;
    prepare(scene, region, pool_[static_cast<std::size_t>(slot)]);
    region_slot_[static_cast<std::size_t>(region)] = slot;
    return slot;
  };
  for (std::size_t i = 0; i < scene.regions.size(); ++i) {
    const PlaneRegion& r = scene.regions[i];
    if (r.points.empty()) continue;
    const float h = up.dot(r.centroid) + up_offset;
    if (r.cls == RegionClass::kFloor || static_cast<int>(i) == scene.floor_region) {
      take_slot(static_cast<int>(i));
      floor_slots_.push_back(region_slot_[i]);
      continue;
    }
    bool candidate = r.cls == RegionClass::kStepCandidate;
    // A curb can be lower than H_min: perception calls such a horizontal plane an obstacle, but the
    // single-level case (paper 4.1, last paragraph) still has to see it.
    if (!candidate && r.cls == RegionClass::kObstacle && std::fabs(r.normal.dot(up)) >= cos_parallel &&
        std::fabs(h) >= cfg_.curb_height_min - cfg_.height_tolerance)
      candidate = true;
    if (!candidate) continue;
    const int slot = take_slot(static_cast<int>(i));
    pool_[static_cast<std::size_t>(slot)].height = h;
    candidates_.push_back(slot);
  }
  out.candidates = static_cast<int>(candidates_.size());
  if (candidates_.empty()) {
    out.verdict = StairVerdict::kNoCandidates;
    return;
  }
  // The floor the user stands on is the nearest level in front of the feet. A lower level nearer
  // than it means perception took something else (a tread, a shelf board) for the floor; every
  // height would then be off by that much, so nothing is reported. Not so for a tracked floor: at
  // the top of a descent the floor at the feet leaves the view, the floor seen beside the
  // stairwell is farther than the treads below, and perception has kept that floor only because
  // it agrees with the one verified on the frames before and the camera is still at the height it
  // had over it (the user has not stepped down).
  if (!floor_slots_.empty() && !scene.floor_tracked) {
    auto near_distance = [&](const Candidate& c) {
      dist_.clear();
      for (const auto& p : c.sample) dist_.push_back((p - up * up.dot(p)).norm());
      const std::size_t i = dist_.size() / 20;
      std::nth_element(dist_.begin(), dist_.begin() + static_cast<long>(i), dist_.end());
      return dist_[i];
    };
    float floor_near = std::numeric_limits<float>::max();
    for (int slot : floor_slots_) {
      const Candidate& f = pool_[static_cast<std::size_t>(slot)];
      if (!f.sample.empty()) floor_near = std::min(floor_near, near_distance(f));
    }
    for (int slot : candidates_) {
      const Candidate& c = pool_[static_cast<std::size_t>(slot)];
      if (c.height > -(cls_.step_height_min - cfg_.height_tolerance) || c.sample.empty()) continue;
      if (static_cast<int>(c.sample.size()) * c.stride < kDoubtfulMinPoints) continue;
      if (near_distance(c) < floor_near - kDoubtfulMargin) {
        out.verdict = StairVerdict::kFloorDoubtful;
        out.ascending.verdict = out.descending.verdict = StairVerdict::kFloorDoubtful;
        return;
      }
    }
  }
  scene_ = &scene;
  build(1, out.ascending);
  build(-1, out.descending);
  scene_ = nullptr;
  out.verdict = StairVerdict::kDetected;
}

}  // namespace stairguide
