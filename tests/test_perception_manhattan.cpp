// Manhattan frame (paper 3.2.2, issue 3) on single synthetic views named in the issue's notes.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "manhattan_test_util.hpp"
#include "stairguide/synth/synth.hpp"
#include "stairguide/perception/perception.hpp"

using namespace stairguide;

namespace {

struct View {
  SceneResult sc;
  FrameTruth truth;
  float yaw_err = -1.f;  // degrees; < 0: no frame
};

// One view of the held-out sweep: preset, view index, seed.
struct Case {
  const char* preset;
  long index;
  std::uint32_t seed;
};

View run_view(const std::string& preset, long index, std::uint32_t seed,
              const ManhattanConfig& manhattan = {}, const synth::SynthOptions& options = {}) {
  View v;
  RgbdFrame frame;
  synth::render_preset_frame(preset, index, seed, options, frame, v.truth);
  Perception P(SegmentationConfig{}, FloorConfig{}, manhattan);
  P.process(frame, v.sc);
  v.yaw_err = sg_test::manhattan_yaw_error_deg(v.sc, v.truth);
  return v;
}

// The view shows at least `min_wall_px` of wall or riser and gets a frame within 2 degrees.
void expect_frame_within_2deg(const Case& c, int min_wall_px) {
  const View v = run_view(c.preset, c.index, c.seed);
  const std::string name =
      std::string(c.preset) + " #" + std::to_string(c.index) + " seed " + std::to_string(c.seed);
  ASSERT_GE(v.truth.wall_or_riser_pixels, min_wall_px) << name;
  EXPECT_GE(v.yaw_err, 0.f) << name << ": no frame (" << v.sc.manhattan_why << ")";
  EXPECT_LE(v.yaw_err, 2.f) << name;
}

// With the real-like noise the view gets a frame within 2 degrees, a staircase in view; with
// `rule_off` its frame is more than 2 degrees off (or, when `none_counts`, there is none): the rule
// that `rule_off` turns off is what makes it right.
void expect_right_by_the_rule(const Case& c, const ManhattanConfig& rule_off, bool none_counts) {
  const synth::SynthOptions real_like = synth::with_real_kinect_noise();
  const std::string name =
      std::string(c.preset) + " #" + std::to_string(c.index) + " seed " + std::to_string(c.seed);
  const View v = run_view(c.preset, c.index, c.seed, ManhattanConfig{}, real_like);
  ASSERT_TRUE(v.truth.any_stair_visible()) << name;
  EXPECT_GE(v.yaw_err, 0.f) << name << ": no frame (" << v.sc.manhattan_why << ")";
  EXPECT_LE(v.yaw_err, 2.f) << name;
  const View w = run_view(c.preset, c.index, c.seed, rule_off, real_like);
  EXPECT_TRUE(w.yaw_err > 2.f || (none_counts && w.yaw_err < 0.f))
      << name << ": " << w.yaw_err << " deg off without the rule, the test does not test";
}

}  // namespace

constexpr std::uint32_t kSuiteSeed = 20261123u;  // test_perception's default seed

// A person's front 0.4 to 0.5 m wide and, within 5 degrees of it, a leg or an arm 3 to 4 cm wide
// made a frame 5 to 14 degrees off with a staircase in view; on s4 #22 two parts of one person
// 0.42 and 0.18 m wide, 9 cm apart along their normal, 19 degrees off. Such planes make no frame.
TEST(ManhattanFrame, PeopleMakeNoWrongFrame) {
  const struct {
    long index;
    std::uint32_t seed;
  } views[] = {{0, 1}, {23, 1}, {22, 4}, {7, 6}};
  for (const auto& c : views) {
    const View v = run_view("people_static", c.index, c.seed);
    ASSERT_TRUE(v.truth.any_stair_visible()) << "#" << c.index << " seed " << c.seed;
    EXPECT_TRUE(v.yaw_err < 0.f || v.yaw_err <= 2.f)
        << "people_static #" << c.index << " seed " << c.seed << ": frame " << v.yaw_err << " deg off";
  }
}

// A riser 0.22 m wide and a far wall at the depth cut-off, parallel to within 2.6 degrees, were
// taken for a pair of parallel planes: frame 2.6 degrees off with the staircase in view.
TEST(ManhattanFrame, PlanesParallelOnlyToDegreesMakeNoPair) {
  const View v = run_view("descending_static", 12, 6);
  ASSERT_TRUE(v.truth.any_stair_visible());
  EXPECT_TRUE(v.yaw_err < 0.f || v.yaw_err <= 2.f)
      << "descending_static #12 seed 6: frame " << v.yaw_err << " deg off";
}

// Narrow strips of one riser (0.13 and 0.15 m, 1.1 m apart on one line) and of one wall (0.13 and
// 0.12 m, 1.4 m apart) were refused as too narrow: together they are as wide as they span.
TEST(ManhattanFrame, StripsOfOnePlaneMakeAFrame) {
  for (const Case& c : {Case{"ascending_static", 17, kSuiteSeed}, Case{"people_static", 17, kSuiteSeed}})
    expect_frame_within_2deg(c, 1000);
}

// A strip of wall 0.23 to 0.29 m wide seen past shelves or a sofa turned against the room has only
// 0.014 to 0.016 m^2 in view: half of it beyond the furniture's plane vetoes the furniture's frame
// (14 degrees off before).
TEST(ManhattanFrame, SmallWallBeyondFurnitureVetoesItsFrame) {
  const Case views[] = {{"sofa_static", 6, 12}, {"shelves_static", 19, 11}};
  for (const auto& c : views) {
    const View v = run_view(c.preset, c.index, c.seed);
    EXPECT_TRUE(v.yaw_err < 0.f || v.yaw_err <= 2.f)
        << c.preset << " #" << c.index << " seed " << c.seed << ": frame " << v.yaw_err << " deg off";
  }
}

// A wall seen beyond furniture turned against the room, as wide as a wall that makes a frame on its
// own (ManhattanConfig::min_plane_width), gives the frame: the furniture's frame is wrong, the
// room's is in view (before: a sofa's or shelves' frame vetoed, and no frame at all).
TEST(ManhattanFrame, WideWallBeyondFurnitureGivesTheFrame) {
  const Case views[] = {{"sofa_static", 23, kSuiteSeed}, {"sofa_static", 13, 1}, {"shelves_static", 13, 3}};
  for (const Case& c : views) expect_frame_within_2deg(c, 1000);
}

// A wall seen mostly at the depth cut-off, a band a few decimetres tall, fixes its tilt poorly, and
// the tilt's error leaked into its yaw: these frames were 2.65 to 4.25 deg off, three of them with
// a staircase in view (seed 4 descending #14, seed 18 descending #6, seed 10 people #12). Its plane
// held upright gives them within 2 deg.
TEST(ManhattanFrame, WallAtTheDepthCutOffIsHeldUpright) {
  const Case views[] = {{"descending_static", 14, 4}, {"descending_static", 6, 18},
                        {"floor_only_static", 9, 1},  {"shelves_static", 6, 1},
                        {"people_static", 12, 10},    {"table_static", 14, 17}};
  for (const Case& c : views) expect_frame_within_2deg(c, 200);
}

// A wall standing on the floor with no floor beyond it, 0.29 m wide between shelves turned 17 deg
// against the room: trusted from ManhattanConfig::min_bounding_width (0.2 m, as wide as a wall
// that may veto a frame) it gives the room's frame (before, at 0.3 m: it only vetoed the
// shelves' frame, and there was none).
TEST(ManhattanFrame, NarrowWallOnTheFloorGivesTheFrame) {
  expect_frame_within_2deg({"shelves_static", 18, kSuiteSeed}, 500);
}

// A handrail beside an open-sided descent, seen against the floor below, comes out as a vertical
// band a few centimetres thick along the flight's slope, 0.85-1.6 m long: its plane is fixed only
// up to a turn about that sloping axis, which turns its yaw. It made frames 4.4-5.5 deg off with
// the staircase in view; it makes none now.
TEST(ManhattanFrame, SlopedHandrailMakesNoFrame) {
  const Case views[] = {{"descending_static", 16, 1},
                        {"descending_static", 7, 7},
                        {"descending_static", 20, 11},
                        {"people_static", 6, 9}};
  for (const auto& c : views) {
    const View v = run_view(c.preset, c.index, c.seed);
    ASSERT_TRUE(v.truth.any_stair_visible()) << c.preset << " #" << c.index << " seed " << c.seed;
    EXPECT_TRUE(v.yaw_err < 0.f || v.yaw_err <= 2.f)
        << c.preset << " #" << c.index << " seed " << c.seed << ": frame " << v.yaw_err << " deg off";
  }
}

// The image edges' compass (edge_compass.hpp) confirms planes too narrow or too small to be
// trusted alone: on the suite's seed, a wall 0.58 m wide below the floor seen past a person whose
// front is 16 deg off (people #7), and the riser and side of a short flight seen only as a corner
// like a box's (ascending_short #15, two faces at right angles prove nothing alone). Without the
// compass (compass_min_support 1: never asked) neither view has a frame.
TEST(ManhattanFrame, SmallPlanesConfirmedByTheImageEdges) {
  ManhattanConfig no_compass;
  no_compass.compass_min_support = 1.f;
  for (const auto& c : {std::make_pair("people_static", 7L), std::make_pair("ascending_short_static", 15L)}) {
    const View v = run_view(c.first, c.second, kSuiteSeed);
    ASSERT_GE(v.truth.wall_or_riser_pixels, 200) << c.first << " #" << c.second;
    EXPECT_GE(v.yaw_err, 0.f) << c.first << " #" << c.second << ": no frame (" << v.sc.manhattan_why << ")";
    EXPECT_LE(v.yaw_err, 2.f) << c.first << " #" << c.second;
    const View w = run_view(c.first, c.second, kSuiteSeed, no_compass);
    EXPECT_LT(w.yaw_err, 0.f) << c.first << " #" << c.second << " without the compass: a frame " << w.yaw_err
                              << " deg off";
  }
}

namespace {

/// Image edges (edge_compass.hpp) whose direction is `yaw` (rad) with `support`, for
/// ManhattanTracker::estimate's compass.
std::function<EdgeCompassResult()> compass_at(float yaw, float support = 0.4f) {
  return [yaw, support]() {
    EdgeCompassResult c;
    c.valid = true;
    c.yaw = yaw;
    c.support = support;
    c.weight = 1.f;
    return c;
  };
}

/// A level camera 1.3 m above the floor (camera x right, y down, z ahead; floor x left, y up).
Pose level_camera() {
  Pose T = Pose::Identity();
  T.linear() = Eigen::Vector3f(-1.f, -1.f, 1.f).asDiagonal();
  T.translation() = Eigen::Vector3f(0.f, 1.3f, 0.f);
  return T;
}

/// A planar rectangle `width` (along `along_f`, horizontal) x `height` (along `across_f`) centred
/// at `c_f`, normal `n_f` (floor frame, towards the camera); points every `step` m, in camera
/// coordinates, with what ManhattanTracker reads of a region.
PlaneRegion rectangle(const Pose& T_floor_camera, const Eigen::Vector3f& c_f, const Eigen::Vector3f& n_f,
                      const Eigen::Vector3f& along_f, const Eigen::Vector3f& across_f, float width,
                      float height, float step) {
  PlaneRegion r;
  const Pose T_cf = T_floor_camera.inverse();
  for (float a = -0.5f * width; a <= 0.5f * width + 1e-4f; a += step)
    for (float h = -0.5f * height; h <= 0.5f * height + 1e-4f; h += step)
      r.points.push_back(T_cf * (c_f + a * along_f + h * across_f));
  r.normal = T_cf.linear() * n_f;
  r.centroid = T_cf * c_f;
  r.offset = -r.normal.dot(r.centroid);
  r.pixel_count = static_cast<int>(r.points.size());
  r.area = width * height;
  const bool wide = width >= height;
  r.rect_axis_major = T_cf.linear() * (wide ? along_f : across_f);
  r.rect_axis_minor = T_cf.linear() * (wide ? across_f : along_f);
  r.rect_length_major = std::max(width, height);
  r.rect_length_minor = std::min(width, height);
  return r;
}

/// A vertical plane `width` x 0.3 m, floating 0.85 m above the floor 2 m ahead (no floor seen,
/// not standing on it: a cupboard's front, a person), its normal at `yaw` (rad) from z_F,
/// facing the camera; points every 2 cm.
PlaneRegion vertical_patch(const Pose& T_floor_camera, float yaw, float width) {
  const Eigen::Vector3f n_f(-std::sin(yaw), 0.f, -std::cos(yaw));  // towards the camera
  const Eigen::Vector3f along_f(std::cos(yaw), 0.f, -std::sin(yaw));
  return rectangle(T_floor_camera, Eigen::Vector3f(0.f, 1.0f, 2.f), n_f, along_f, Eigen::Vector3f::UnitY(),
                   width, 0.3f, 0.02f);
}

/// A band `length` x 0.07 m along a level axis at `yaw` (rad), its plane tilted `tilt` (rad) from
/// vertical about that axis (a riser's strip whose fit the noise turned), 0.1 m above the floor
/// 2 m ahead, facing the camera; points every 1 cm.
PlaneRegion tilted_band(const Pose& T_floor_camera, float yaw, float tilt, float length) {
  const Eigen::Vector3f n_h(-std::sin(yaw), 0.f, -std::cos(yaw));  // towards the camera
  const Eigen::Vector3f along_f(std::cos(yaw), 0.f, -std::sin(yaw));
  const Eigen::Vector3f n_f = std::cos(tilt) * n_h + std::sin(tilt) * Eigen::Vector3f::UnitY();
  return rectangle(T_floor_camera, Eigen::Vector3f(0.f, 0.135f, 2.f), n_f, along_f,
                   n_f.cross(along_f).normalized(), length, 0.07f, 0.01f);
}

/// An upright rectangle `width` x `height` standing on the floor, its foot's centre `ahead` m in
/// front of the camera, its normal at `yaw` (rad) from z_F facing the camera; points every `step` m.
PlaneRegion upright_on_floor(const Pose& T_floor_camera, float ahead, float yaw, float width, float height,
                             float step) {
  const Eigen::Vector3f n_f(-std::sin(yaw), 0.f, -std::cos(yaw));
  const Eigen::Vector3f along_f(std::cos(yaw), 0.f, -std::sin(yaw));
  return rectangle(T_floor_camera, Eigen::Vector3f(0.f, 0.5f * height, ahead), n_f, along_f,
                   Eigen::Vector3f::UnitY(), width, height, step);
}

/// The floor from `from` to `to` m ahead, 4 m wide; points every 5 cm.
PlaneRegion floor_between(const Pose& T_floor_camera, float from, float to) {
  return rectangle(T_floor_camera, Eigen::Vector3f(0.f, 0.f, 0.5f * (from + to)), Eigen::Vector3f::UnitY(),
                   Eigen::Vector3f::UnitX(), Eigen::Vector3f::UnitZ(), 4.f, to - from, 0.05f);
}

/// `r` moved `down` m straight down (a plane standing below the floor's level).
PlaneRegion lowered(PlaneRegion r, const Pose& T_floor_camera, float down) {
  const Pose T_cf = T_floor_camera.inverse();
  const Eigen::Vector3f d(0.f, down, 0.f);
  for (Eigen::Vector3f& p : r.points) p = T_cf * (T_floor_camera * p - d);
  r.centroid = T_cf * (T_floor_camera * r.centroid - d);
  r.offset = -r.normal.dot(r.centroid);
  return r;
}

/// A step: its riser `width` wide, from `base` to `base + height` above the floor, its foot
/// `ahead` m in front of the camera, its normal at `yaw` (rad) from z_F facing the camera; and its
/// tread (or any level surface on its top edge) going `depth` m on beyond it. Points every 2 cm.
std::vector<PlaneRegion> step(const Pose& T_floor_camera, float ahead, float yaw, float width, float base,
                              float height, float depth) {
  const Eigen::Vector3f n_f(-std::sin(yaw), 0.f, -std::cos(yaw));
  const Eigen::Vector3f along_f(std::cos(yaw), 0.f, -std::sin(yaw));
  const Eigen::Vector3f foot(0.f, 0.f, ahead);
  return {rectangle(T_floor_camera, foot + Eigen::Vector3f(0.f, base + 0.5f * height, 0.f), n_f, along_f,
                    Eigen::Vector3f::UnitY(), width, height, 0.02f),
          rectangle(T_floor_camera, foot + Eigen::Vector3f(0.f, base + height, 0.f) - 0.5f * depth * n_f,
                    Eigen::Vector3f::UnitY(), along_f, n_f, width, depth, 0.02f)};
}

}  // namespace

// A wall 4.6 m away and 0.6 m wide (ManhattanConfig::far_wall_range, far_wall_width) is the only
// wall in view, its yaw 4 deg off as the real sensor's far walls are; a riser 1.5 m wide stands
// 2.5 m away with the floor going on beyond it. The walls' frame alone would be the wall's; the
// riser, within far_wall_agreement of it, gives the frame instead (with the real-like noise such
// walls made frames 2 to 5 deg off with a staircase in view). Furniture turned 20 deg against the
// room keeps the wall's frame, and so does a riser beside a wall near enough to fix its yaw.
TEST(ManhattanFrame, FarNarrowWallYieldsToNearerPlanesAgreeingWithIt) {
  const Pose T = level_camera();
  const float deg = 3.14159265f / 180.f;
  const float wall_yaw = 4.f * deg;
  const ManhattanConfig cfg;
  auto frame = [&](float riser_yaw, float wall_ahead, const ManhattanConfig& c) {
    ManhattanTracker m(c);
    return m.estimate(
        {floor_between(T, 0.8f, wall_ahead), upright_on_floor(T, wall_ahead, wall_yaw, 0.6f, 0.4f, 0.02f),
         upright_on_floor(T, 2.5f, riser_yaw, 1.5f, 0.17f, 0.02f)},
        T);
  };
  {
    const ManhattanEstimate e = frame(0.f, 4.6f, cfg);
    ASSERT_TRUE(e.found) << e.why;
    // The riser's frame, with the wall's vote in it (area x width^2: a sixth of the riser's weight).
    EXPECT_LT(std::fabs(e.yaw), 1.5f * deg) << "the far wall's frame, " << e.yaw / deg << " deg";
  }
  {
    ManhattanConfig walls_first = cfg;
    walls_first.far_wall_agreement = 0.f;
    const ManhattanEstimate e = frame(0.f, 4.6f, walls_first);
    ASSERT_TRUE(e.found) << e.why;
    EXPECT_NEAR(e.yaw, wall_yaw, 0.1f * deg) << "without the rule, the walls' frame: the test does not test";
  }
  {
    const ManhattanEstimate e = frame(20.f * deg, 4.6f, cfg);
    ASSERT_TRUE(e.found) << e.why;
    EXPECT_NEAR(e.yaw, wall_yaw, 0.1f * deg) << "furniture turned 20 deg took the frame from the wall";
  }
  {
    const ManhattanEstimate e = frame(0.f, 3.5f, cfg);
    ASSERT_TRUE(e.found) << e.why;
    EXPECT_NEAR(e.yaw, wall_yaw, 0.1f * deg) << "a wall 3.5 m away yielded to the riser";
  }
}

// A wall 4.6 m away, 0.6 m wide, is the only wall in view, its yaw 7 deg off as the real sensor's
// far walls are (2.5 to 7 deg in the synthetic views with real-like noise); the staircase's risers
// nearer by 2 m are right to a few tenths. Risers (ManhattanConfig::riser_*: a flight's, open risers'
// tread fronts, a single step's) make the frame over such walls within riser_agreement; planes that
// carry a level surface but are no risers do not: a sofa's back cushion on its seat (one such plane,
// not a flight) and a shelf's plinth under its bottom board (0.34 m deep; a single step's tread goes
// on 0.6 m or more).
TEST(ManhattanFrame, RisersOverruleFarWalls) {
  const Pose T = level_camera();
  const float deg = 3.14159265f / 180.f;
  const float wall_yaw = 7.f * deg;
  auto frame = [&](std::vector<PlaneRegion> planes, const ManhattanConfig& c) {
    // The floor goes on beside the staircase or the furniture, up to the wall: they stand inside the room.
    planes.push_back(floor_between(T, 0.8f, 4.4f));
    planes.push_back(upright_on_floor(T, 4.6f, wall_yaw, 0.6f, 0.4f, 0.02f));
    ManhattanTracker m(c);
    return m.estimate(planes, T);
  };
  auto flight = [&](float yaw) {
    std::vector<PlaneRegion> planes;
    for (int k = 0; k < 3; ++k)
      for (PlaneRegion& r : step(T, 2.5f + 0.28f * k, yaw, 1.0f, 0.17f * k, 0.17f, 0.28f))
        planes.push_back(r);
    return planes;
  };
  const ManhattanConfig cfg;
  ManhattanConfig no_risers = cfg;
  no_risers.riser_agreement = 0.f;
  // The frame `planes` make with the far wall is `yaw` (rad) within 0.1 deg.
  auto expect_frame = [&](const std::vector<PlaneRegion>& planes, const ManhattanConfig& c, float yaw,
                          const char* what) {
    const ManhattanEstimate e = frame(planes, c);
    ASSERT_TRUE(e.found) << what << ": " << e.why;
    EXPECT_NEAR(e.yaw, yaw, 0.1f * deg) << what << ": frame " << e.yaw / deg << " deg";
  };
  expect_frame(flight(0.f), cfg, 0.f, "a flight's risers");
  expect_frame(flight(0.f), no_risers, wall_yaw,
               "without the rule (the wall's frame, or the test does not test)");
  // Open risers: each tread's front, 5 cm tall, carries it; no riser below.
  std::vector<PlaneRegion> open;
  for (int k = 0; k < 3; ++k)
    for (PlaneRegion& r : step(T, 2.5f + 0.28f * k, 0.f, 1.0f, 0.17f * (k + 1) - 0.05f, 0.05f, 0.25f))
      open.push_back(r);
  expect_frame(open, cfg, 0.f, "open risers' tread fronts");
  // A descent's drop: the floor's edge face, from the floor down 1 m, 1.5 m wide.
  expect_frame({lowered(upright_on_floor(T, 2.5f, 0.f, 1.5f, 1.0f, 0.02f), T, 1.0f)}, cfg, 0.f,
               "a drop's face");
  expect_frame(step(T, 2.5f, 0.f, 1.2f, 0.f, 0.17f, 1.0f), cfg, 0.f, "a single step");
  expect_frame(flight(20.f * deg), cfg, wall_yaw, "a flight 13 deg from the wall, beyond riser_agreement");
  std::vector<PlaneRegion> sofa = step(T, 2.2f, 0.f, 1.6f, 0.f, 0.44f, 0.6f);  // its front and seat
  for (PlaneRegion& r : step(T, 2.8f, 0.f, 1.6f, 0.44f, 0.19f, 0.2f))
    sofa.push_back(r);  // the back's cushion
  expect_frame(sofa, cfg, wall_yaw, "a sofa's cushion on its seat");
  expect_frame(step(T, 2.5f, 0.f, 0.87f, 0.f, 0.15f, 0.34f), cfg, wall_yaw, "a shelf's plinth");
}

// A plane on the floor narrower than min_plane_width makes the walls' frame alone only with nothing
// beyond it, as a wall strip: a person's shins 0.22 m wide at the top of a descent, turned 44 deg,
// with the flight and the wall at its foot beyond them (real-like noise, seed 1 people #13: 23 deg
// off with the staircase in view), make none; the wall below, 1 m wide, gives the frame. With
// nothing beyond them, the same shins would pass for a wall strip.
TEST(ManhattanFrame, NarrowPlaneWithStructureBeyondItIsNoWall) {
  const Pose T = level_camera();
  const float deg = 3.14159265f / 180.f;
  const float person = 44.f * deg;
  // The floor seen in front of the person, 1.2 m wide, all on the camera's side of their plane.
  const PlaneRegion floor = rectangle(T, Eigen::Vector3f(0.f, 0.f, 1.4f), Eigen::Vector3f::UnitY(),
                                      Eigen::Vector3f::UnitX(), Eigen::Vector3f::UnitZ(), 1.2f, 1.2f, 0.05f);
  const PlaneRegion shins = upright_on_floor(T, 2.6f, person, 0.22f, 0.44f, 0.02f);
  const PlaneRegion wall_below = lowered(upright_on_floor(T, 5.0f, 0.f, 1.0f, 0.6f, 0.02f), T, 0.9f);
  {
    ManhattanTracker m;
    const ManhattanEstimate e = m.estimate({floor, shins, wall_below}, T);
    ASSERT_TRUE(e.found) << e.why;
    EXPECT_LT(std::fabs(e.yaw), 0.5f * deg) << "the person's frame, " << e.yaw / deg << " deg";
  }
  {
    ManhattanTracker m;
    const ManhattanEstimate e = m.estimate({floor, shins}, T);
    ASSERT_TRUE(e.found) << e.why;
    EXPECT_NEAR(e.yaw, person, 0.1f * deg) << "with nothing beyond it, a strip on the floor is a wall";
  }
  const View v = run_view("people_static", 13, 1, ManhattanConfig{}, synth::with_real_kinect_noise());
  ASSERT_TRUE(v.truth.any_stair_visible());
  EXPECT_TRUE(v.yaw_err < 0.f || v.yaw_err <= 2.f)
      << "people_static #13 seed 1: frame " << v.yaw_err << " deg off";
}

// Furniture hangs above the floor inside the room (ManhattanConfig::hanging_min_height): a bench's
// apron 1.3 m wide and 6 cm tall under its seat, turned 12 deg against the room, and the edges of
// two desks 0.9 m wide, one row behind the other, make no frame (a frame 12 deg off before, with
// nothing else in view to say so). Open risers' tread fronts 0.6 m wide, the lowest standing on the
// floor, still make a frame in a pair with an upper one (two treads between them unseen: no flight
// to mark as risers). The image edges confirming the furniture change nothing.
TEST(ManhattanFrame, HangingFurnitureMakesNoFrameAlone) {
  const Pose T = level_camera();
  const float deg = 3.14159265f / 180.f;
  const float turned = 12.f * deg;
  const PlaneRegion floor = floor_between(T, 0.8f, 4.4f);  // beyond the furniture: it stands inside
  std::vector<PlaneRegion> bench = step(T, 2.2f, turned, 1.3f, 0.41f, 0.06f, 0.4f);
  bench.push_back(floor);
  std::vector<PlaneRegion> desks = step(T, 2.0f, turned, 0.9f, 0.68f, 0.04f, 0.6f);
  for (PlaneRegion& r : step(T, 2.8f, turned, 0.9f, 0.68f, 0.04f, 0.6f)) desks.push_back(r);
  desks.push_back(floor);
  ManhattanConfig off;
  off.hanging_min_height = 0.f;
  for (const auto& [planes, what] :
       {std::make_pair(bench, "a bench's apron"), std::make_pair(desks, "two desks' edges")}) {
    ManhattanTracker m;
    const ManhattanEstimate e = m.estimate(planes, T);
    EXPECT_FALSE(e.found) << what << ": frame " << e.yaw / deg << " deg";
    // The image edges agreeing with the furniture (its own edges) confirm nothing more.
    ManhattanTracker m_edges;
    const ManhattanEstimate e_edges = m_edges.estimate(planes, T, compass_at(turned));
    EXPECT_FALSE(e_edges.found) << what << ", its edges confirming it: frame " << e_edges.yaw / deg << " deg";
    ManhattanTracker m_off(off);
    const ManhattanEstimate e_off = m_off.estimate(planes, T);
    ASSERT_TRUE(e_off.found) << what << " without the rule (or the test does not test): " << e_off.why;
    EXPECT_NEAR(e_off.yaw, turned, 0.1f * deg) << what << " without the rule";
  }
  std::vector<PlaneRegion> open = step(T, 2.5f, 0.f, 0.6f, 0.12f, 0.05f, 0.25f);
  for (PlaneRegion& r : step(T, 3.06f, 0.f, 0.6f, 0.46f, 0.05f, 0.25f)) open.push_back(r);
  open.push_back(floor);
  ManhattanTracker m;
  const ManhattanEstimate e = m.estimate(open, T);
  ASSERT_TRUE(e.found) << "open risers' tread fronts: " << e.why;
  EXPECT_NEAR(e.yaw, 0.f, 0.1f * deg);
}

// The compass only says which planes to believe: a plane too narrow to make a frame alone
// (0.3 m, floating) makes one when the image edges agree with it within compass_agreement (the
// frame is the plane's yaw, not the compass's), and none when they disagree by more, when the
// edges have too little support, or when the plane is narrower than compass_min_width.
TEST(ManhattanFrame, CompassConfirmsOnlyAgreeingPlanes) {
  const Pose T = level_camera();
  const float yaw = 0.3f;  // 17 deg
  const ManhattanConfig cfg;
  {
    ManhattanTracker m(cfg);
    const ManhattanEstimate alone = m.estimate({vertical_patch(T, yaw, 0.3f)}, T);
    EXPECT_FALSE(alone.found) << "a 0.3 m plane floating above the floor made a frame alone";
  }
  {
    ManhattanTracker m(cfg);
    const ManhattanEstimate e = m.estimate({vertical_patch(T, yaw, 0.3f)}, T, compass_at(yaw + 0.02f, 0.4f));
    ASSERT_TRUE(e.found) << e.why;
    EXPECT_NEAR(e.yaw, yaw, 1e-3f) << "the frame is the plane's yaw";
  }
  {
    ManhattanTracker m(cfg);
    const ManhattanEstimate e =
        m.estimate({vertical_patch(T, yaw, 0.3f)}, T, compass_at(yaw + cfg.compass_agreement + 0.01f, 0.4f));
    EXPECT_FALSE(e.found) << "edges disagreeing by more than compass_agreement confirmed the plane";
  }
  {
    ManhattanTracker m(cfg);
    const ManhattanEstimate e =
        m.estimate({vertical_patch(T, yaw, 0.3f)}, T, compass_at(yaw, 0.9f * cfg.compass_min_support));
    EXPECT_FALSE(e.found) << "edges with too little support confirmed the plane";
  }
  {
    ManhattanTracker m(cfg);
    const ManhattanEstimate e = m.estimate({vertical_patch(T, yaw, 0.16f)}, T, compass_at(yaw, 0.4f));
    EXPECT_FALSE(e.found) << "a plane narrower than compass_min_width was confirmed";
  }
}

// The views whose only wall in range is a strip at the depth cut-off, its fit too doubtful to trust
// alone, and whose edges have no dominant direction (a floor of random texture fills the view):
// on the suite's seed, a lone sliver of wall 0.55 m wide beside a bare floor (floor_only #17) and a
// wall 0.47 m wide seen past a bench turned 23 deg (bench #14). The foot of the wall ahead, beyond
// the cut-off, is a straight edge on the floor across the image, and the wall in range agrees with
// it; on seeds 5 and 17, floor joints and a rug's edge do the same (ascending #7, room_clutter #0)
// and give the frame within 0.1 deg where the walls' own fit was 2.0-2.1 deg off. Without the
// lines (compass_line_min_length 0) none of these views has a frame.
TEST(ManhattanFrame, FloorLinesConfirmWallsAtTheCutOff) {
  ManhattanConfig no_lines;
  no_lines.compass_line_min_length = 0.f;
  for (const Case& c : {Case{"floor_only_static", 17, kSuiteSeed}, Case{"bench_static", 14, kSuiteSeed},
                        Case{"ascending_static", 7, 5u}, Case{"room_clutter_static", 0, 17u}}) {
    const std::string name =
        std::string(c.preset) + " #" + std::to_string(c.index) + " seed " + std::to_string(c.seed);
    const View v = run_view(c.preset, c.index, c.seed);
    ASSERT_GE(v.truth.wall_or_riser_pixels, 200) << name;
    EXPECT_GE(v.yaw_err, 0.f) << name << ": no frame (" << v.sc.manhattan_why << ")";
    std::printf("%s: %.2f deg off\n", name.c_str(), v.yaw_err);
    EXPECT_LE(v.yaw_err, 1.f) << name;
    const View w = run_view(c.preset, c.index, c.seed, no_lines);
    EXPECT_LT(w.yaw_err, 0.f) << name << " without the lines: a frame " << w.yaw_err << " deg off";
  }
}

/// Image edges without a dominant direction (a floor of random texture: `support` under
/// compass_wall_min_support) but with one long straight edge on the floor at `line_yaw` (rad).
std::function<EdgeCompassResult()> compass_with_floor_line(float line_yaw, float support = 0.02f) {
  return [line_yaw, support]() {
    EdgeCompassResult c;
    c.valid = true;
    c.yaw = line_yaw + 0.35f;  // the chance peak of the texture's edges, 20 deg away
    c.support = support;
    c.weight = 1.f;
    EdgeLine l;
    l.heading = line_yaw;
    l.length = 500.f;
    l.span = 560.f;
    c.lines.push_back(l);
    return c;
  };
}

// A long straight edge on the floor (the foot of a wall, a floor joint) confirms a wall that
// agrees with it within compass_agreement, compass_min_width wide, when the edges' dominant
// direction confirms nothing; the frame is the line's direction. It confirms no plane with floor
// beyond it (furniture, a person, a riser: inside the room, with its own edges along it), none
// that disagrees by more than compass_agreement, and none narrower than compass_min_width.
TEST(ManhattanFrame, FloorLineConfirmsAWall) {
  const Pose T = level_camera();
  const float yaw = 0.3f;  // 17 deg
  const float deg = 3.14159265f / 180.f;
  const ManhattanConfig cfg;
  {
    ManhattanTracker m(cfg);
    const ManhattanEstimate e =
        m.estimate({vertical_patch(T, yaw, 0.3f)}, T, compass_with_floor_line(yaw + 0.5f * deg));
    ASSERT_TRUE(e.found) << e.why;
    EXPECT_NEAR(e.yaw, yaw + 0.5f * deg, 1e-4f) << "the frame is the line's direction";
  }
  {
    ManhattanTracker m(cfg);
    const ManhattanEstimate e = m.estimate({vertical_patch(T, yaw, 0.3f)}, T,
                                           compass_with_floor_line(yaw + cfg.compass_agreement + 0.01f));
    EXPECT_FALSE(e.found) << "a line disagreeing by more than compass_agreement confirmed the plane";
  }
  {
    ManhattanTracker m(cfg);
    const ManhattanEstimate e = m.estimate({vertical_patch(T, yaw, 0.16f)}, T, compass_with_floor_line(yaw));
    EXPECT_FALSE(e.found) << "a plane narrower than compass_min_width was confirmed";
  }
  {
    // A box's side 0.3 m wide standing on the floor 2 m ahead, the floor seen beyond it.
    ManhattanTracker m(cfg);
    const std::vector<PlaneRegion> planes{floor_between(T, 0.8f, 4.4f),
                                          upright_on_floor(T, 2.f, yaw, 0.3f, 0.4f, 0.02f)};
    EXPECT_FALSE(m.estimate(planes, T).found) << "the box's side made a frame alone";
    const ManhattanEstimate e = m.estimate(planes, T, compass_with_floor_line(yaw));
    EXPECT_FALSE(e.found) << "a line confirmed a plane with floor beyond it";
  }
}

// A band along a level axis (a riser's strip 7 cm tall) fixes its plane only up to a turn about
// that axis: tilted 13 deg from vertical by its fit, its axis still gives the yaw. It joins the
// planes the image edges confirm (heading from the axis), and makes no frame without them; tilted
// beyond level_band_max_tilt, or along a sloping axis, it is no vertical plane at all.
TEST(ManhattanFrame, TiltedLevelBandJoinsOnlyConfirmedFrames) {
  const Pose T = level_camera();
  const float yaw = -0.2f;
  const ManhattanConfig cfg;
  {
    ManhattanTracker m(cfg);
    EXPECT_FALSE(m.estimate({tilted_band(T, yaw, 13.f * 3.14159265f / 180.f, 0.4f)}, T).found)
        << "a tilted band made a frame without the compass";
  }
  {
    ManhattanTracker m(cfg);
    const ManhattanEstimate e =
        m.estimate({tilted_band(T, yaw, 13.f * 3.14159265f / 180.f, 0.4f)}, T, compass_at(yaw + 0.02f));
    ASSERT_TRUE(e.found) << e.why;
    EXPECT_NEAR(e.yaw, yaw, 1e-3f) << "the band's heading is its axis's";
  }
  {
    ManhattanTracker m(cfg);
    const float too_tilted = cfg.level_band_max_tilt + 0.05f;
    EXPECT_FALSE(m.estimate({tilted_band(T, yaw, too_tilted, 0.4f)}, T, compass_at(yaw)).found)
        << "a band tilted beyond level_band_max_tilt was confirmed";
  }
}

// On the suite's seed, single_step #20 shows only a corner of the step's riser at the image's
// edge: a band 0.4 m x 7 cm whose fit is 13 deg from vertical, its yaw 0.3 deg off. With the
// image edges confirming it, it gives the frame; taken as vertical only within
// vertical_tolerance (level_band_max_tilt no larger), the view had no vertical plane at all.
TEST(ManhattanFrame, RiserCornerAtTheImageEdgeGivesTheFrame) {
  const View v = run_view("single_step_static", 20, kSuiteSeed);
  ASSERT_GE(v.truth.wall_or_riser_pixels, 200);
  EXPECT_GE(v.yaw_err, 0.f) << "single_step_static #20: no frame (" << v.sc.manhattan_why << ")";
  EXPECT_LE(v.yaw_err, 2.f) << "single_step_static #20";
  ManhattanConfig vertical_only;
  vertical_only.level_band_max_tilt = vertical_only.vertical_tolerance;
  const View w = run_view("single_step_static", 20, kSuiteSeed, vertical_only);
  EXPECT_LT(w.yaw_err, 0.f) << "without the tilted band: a frame " << w.yaw_err << " deg off";
}

// A floor refused for where it lies (it may be a tread, or something lies below it nearer the
// user) is still level: the walls and risers are upright about its normal, and the frame is
// measured about it (before, "no floor" meant no frame: these views and 23 more on the held-out
// seeds, all now within 0.61 deg). ascending_short #13 looks up a stairwell; nosing_landing #0
// seed 10 at a flight's foot; people #13 seed 6 past people at the foot of one (people #15 seed 1,
// here before, has its floor now, by the floor detector's rule for a strip of floor at the view's bottom
// edge).
TEST(ManhattanFrame, FloorRefusedStillGivesTheVertical) {
  const Case views[] = {
      {"ascending_short_static", 13, kSuiteSeed}, {"nosing_landing_static", 0, 10}, {"people_static", 13, 6}};
  ManhattanConfig off;
  off.without_floor = false;
  for (const auto& c : views) {
    const View v = run_view(c.preset, c.index, c.seed);
    ASSERT_TRUE(v.truth.floor_visible) << c.preset << " #" << c.index << " seed " << c.seed;
    ASSERT_GE(v.truth.wall_or_riser_pixels, 200) << c.preset << " #" << c.index << " seed " << c.seed;
    ASSERT_FALSE(v.sc.floor_found) << c.preset << " #" << c.index << " seed " << c.seed
                                   << ": the test does not test";
    EXPECT_EQ(v.sc.floor_region, -1);
    EXPECT_TRUE(v.sc.manhattan_without_floor)
        << c.preset << " #" << c.index << " seed " << c.seed << ": " << v.sc.manhattan_why;
    EXPECT_GE(v.yaw_err, 0.f) << c.preset << " #" << c.index << " seed " << c.seed;
    EXPECT_LE(v.yaw_err, 2.f) << c.preset << " #" << c.index << " seed " << c.seed;
    const View w = run_view(c.preset, c.index, c.seed, off);
    EXPECT_FALSE(w.sc.manhattan_found) << c.preset << " #" << c.index << " seed " << c.seed;
    EXPECT_EQ(w.sc.manhattan_why, "no floor");
  }
}

// A far wall reaching the depth cut-off (5 m): the cut-off keeps a reading only when its noise fell
// short of it, so the readings of the wall's far part are the ones pushed nearer, and its plane
// held upright turns towards the camera there. Fitted again on the readings whose plane lies
// 3 sigma clear of the cut-off (chosen by ray, which the noise does not move), the yaw is right.
// Kinect-like noise: a constant sigma in 1/z (sigma_z = 1.425e-3 z^2), over 40 draws.
TEST(ManhattanFrame, WallReachingTheCutOffIsFittedClearOfIt) {
  const float f = 570.f, cx = 320.f, cy = 240.f, cut = 5.f, coeff = 1.425e-3f;
  const float clear = cut - 3.f * coeff * cut * cut;
  const Eigen::Vector3f up(0.f, -1.f, 0.f);  // a level camera: y down
  std::mt19937 rng(7);
  std::normal_distribution<float> noise(0.f, coeff);
  double err_upright = 0, err_clear = 0;
  int refitted = 0;
  const int draws = 40;
  for (int k = 0; k < draws; ++k) {
    // An upright wall turned 35-55 deg from the optical axis, 0.5 m of it from 4.55 to 5.3 m away.
    const float yaw = (35.f + 20.f * static_cast<float>(k) / draws) * static_cast<float>(M_PI) / 180.f;
    const Eigen::Vector3f n(-std::sin(yaw), 0.f, -std::cos(yaw));  // towards the camera
    const Eigen::Vector3f p0(0.f, 0.f, 4.8f);
    const float D = n.dot(p0);
    std::vector<Eigen::Vector3f> pts;
    for (int v = 300; v < 360; v += 2)
      for (int u = 0; u < 640; u += 2) {
        const Eigen::Vector3f ray((u - cx) / f, (v - cy) / f, 1.f);
        const float z = D / n.dot(ray);  // the wall's depth along the ray
        if (!(z > 4.55f && z < 5.3f)) continue;
        const float zm = 1.f / (1.f / z + noise(rng));
        if (zm > cut) continue;  // the cut-off drops it
        pts.push_back(zm * ray);
      }
    ASSERT_GT(pts.size(), 500u);
    const Eigen::Vector3f nu = fit_upright_normal(pts, up, n);
    const Eigen::Vector3f nc = fit_upright_normal_clear_of_cutoff(pts, up, nu, clear);
    refitted += !nc.isApprox(nu);
    auto off_deg = [&](const Eigen::Vector3f& m) {
      return std::acos(std::min(1.f, m.dot(n))) * 180.0 / M_PI;
    };
    err_upright += off_deg(nu);
    err_clear += off_deg(nc);
  }
  err_upright /= draws;
  err_clear /= draws;
  std::printf("wall reaching the cut-off: mean yaw error %.2f deg held upright, %.2f fitted clear of it\n",
              err_upright, err_clear);
  EXPECT_EQ(refitted, draws);
  // Measured: 0.92 deg held upright, 0.28 clear of the cut-off (the noise of the fewer readings).
  EXPECT_GT(err_upright, 0.7) << "the cut-off no longer biases the fit: the test does not test";
  EXPECT_LT(err_clear, 0.4);
  EXPECT_LT(err_clear, 0.5 * err_upright);
}

// A wall seen mostly inside the cut-off's noise band keeps its upright fit (its clear part is too
// narrow to fix a yaw), as it does with no cut-off known; clear of the band, it is fitted again.
TEST(ManhattanFrame, WallInsideTheCutOffBandKeepsItsUprightFit) {
  const Eigen::Vector3f up(0.f, -1.f, 0.f), n(0.f, 0.f, -1.f);
  std::vector<Eigen::Vector3f> pts;
  for (int i = 0; i < 100; ++i) pts.emplace_back(0.01f * static_cast<float>(i) - 0.5f, 0.f, 4.95f);
  const Eigen::Vector3f turned = Eigen::Vector3f(0.05f, 0.f, -1.f).normalized();
  EXPECT_TRUE(fit_upright_normal_clear_of_cutoff(pts, up, turned, 4.89f).isApprox(turned));
  EXPECT_TRUE(fit_upright_normal_clear_of_cutoff(pts, up, turned, 0.f).isApprox(turned));
  // Clear of the band, the points' own plane (facing the camera) is fitted.
  EXPECT_LT((fit_upright_normal_clear_of_cutoff(pts, up, turned, 5.5f) - n).norm(), 1e-4f);
}

// Far walls fitted clear of the cut-off's noise band: the suite's sofa #0 (its far wall, 1.06 m
// wide at 4.77 m, had let the sofa's frame stand 2.01 deg off) and seed 16's people #1 (2.18 deg
// off with a staircase in view, the one such frame on seeds 1-20) come within 2 deg.
TEST(ManhattanFrame, FarWallsFittedClearOfTheCutOff) {
  const Case views[] = {{"sofa_static", 0, kSuiteSeed}, {"people_static", 1, 16}};
  for (const Case& c : views) expect_frame_within_2deg(c, 500);
}

// With the depth noise correlated as the real sensor's (synth::with_real_kinect_noise), a far
// narrow wall, the only wall in view, made these frames 2.8 to 4.3 deg off with a staircase (or a
// person on one) in view, against risers nearer and wider that agree with it within
// far_wall_agreement; the risers' frame is within 2 deg. On seeds 1-12 of the static presets so
// measured, frames off with a staircase in view went from 36 to 21 and right frames from 2628 to
// 2639 of 2906.
TEST(ManhattanFrame, FarNarrowWallsYieldWithRealLikeNoise) {
  const Case views[] = {{"single_step_static", 4, 1},
                        {"single_step_static", 17, 3},
                        {"open_risers_static", 6, 6},
                        {"single_step_static", 16, 10},
                        {"people_static", 9, 5}};
  ManhattanConfig walls_first;
  walls_first.far_wall_agreement = 0.f;
  walls_first.riser_agreement = 0.f;  // the risers' rule (below) now catches most of these views too
  for (const Case& c : views) expect_right_by_the_rule(c, walls_first, /*none_counts=*/false);
}

// With the real-like noise, a far wall (4.2 to 4.9 m away) made these frames 2.3 to 7 deg off with
// a staircase in view, or left it without a frame by its veto, against a flight's or a single
// step's risers (or open risers' tread fronts) within 0.35 deg: the risers now make the frame
// (ManhattanConfig::riser_*). The views of a sofa and of shelves whose cushion or plinth first
// passed for a riser (frames 6.3-7.8 deg off, real-like noise; 4.5 deg, white) are no more than 2
// deg off.
TEST(ManhattanFrame, RisersOverruleFarWallsWithRealLikeNoise) {
  const Case views[] = {{"handrails_open_sides_static", 18, 11},
                        {"handrails_open_sides_static", 9, 4},
                        {"handrails_open_sides_static", 21, 8},
                        {"single_step_static", 22, 5},
                        {"single_step_static", 6, 2},
                        {"ascending_short_static", 23, 12},
                        {"open_risers_static", 7, 12},
                        {"people_static", 20, 5},
                        {"descending_static", 13, 5}};
  ManhattanConfig no_risers;
  no_risers.riser_agreement = 0.f;
  for (const Case& c : views) expect_right_by_the_rule(c, no_risers, /*none_counts=*/true);
  const synth::SynthOptions real_like = synth::with_real_kinect_noise();
  const struct {
    Case c;
    bool real_like;
  } furniture[] = {{{"sofa_static", 1, kSuiteSeed}, true},
                   {{"shelves_static", 20, kSuiteSeed}, true},
                   {{"sofa_static", 3, 10}, true},
                   {{"shelves_static", 16, 2}, false}};
  for (const auto& f : furniture) {
    const View v = run_view(f.c.preset, f.c.index, f.c.seed, ManhattanConfig{},
                            f.real_like ? real_like : synth::SynthOptions{});
    EXPECT_TRUE(v.yaw_err < 0.f || v.yaw_err <= 2.f)
        << f.c.preset << " #" << f.c.index << " seed " << f.c.seed << ": frame " << v.yaw_err << " deg off";
  }
}

// A box 0.8 m wide turned 25 deg against the room, 2 m ahead with the floor going on beyond it,
// and a wall seen beyond it at the depth cut-off (5 m), 0.5 m wide: too narrow to make the frame,
// it vetoes the box's. The image edges (the room's, beyond the cut-off) agreeing with the wall
// within compass_veto_agreement, and not with the box, give the frame: their own direction, not
// the wall's (a wall at the cut-off is degrees off). Edges agreeing with the box, or off from the
// wall, or with too little support, give none; nor with the rule off.
TEST(ManhattanFrame, ImageEdgesAgreeingWithAVetoingWallGiveTheFrame) {
  const Pose T = level_camera();
  const float deg = 3.14159265f / 180.f;
  const float box_yaw = 25.f * deg, wall_yaw = 3.f * deg, room_yaw = 0.5f * deg;
  const std::vector<PlaneRegion> planes = {floor_between(T, 0.8f, 4.9f),
                                           upright_on_floor(T, 2.f, box_yaw, 0.8f, 0.7f, 0.02f),
                                           upright_on_floor(T, 4.9f, wall_yaw, 0.5f, 0.3f, 0.02f)};
  const ManhattanConfig cfg;
  auto frame = [&](const std::function<EdgeCompassResult()>& compass,
                   const ManhattanConfig& c = ManhattanConfig{}) {
    ManhattanTracker m(c, 5.f);
    return m.estimate(planes, T, compass);
  };
  const ManhattanEstimate none = frame({});
  EXPECT_FALSE(none.found) << "without the image edges, the wall vetoes the box's frame: " << none.yaw / deg
                           << " deg";
  EXPECT_NE(none.why.find("disagrees"), std::string::npos) << none.why;
  const ManhattanEstimate e = frame(compass_at(room_yaw, cfg.compass_veto_min_support + 0.01f));
  ASSERT_TRUE(e.found) << e.why;
  EXPECT_NEAR(e.yaw, room_yaw, 0.01f * deg);
  // The edges within the agreement on the wall's other side, too.
  const float near_limit = wall_yaw - cfg.compass_veto_agreement + 0.5f * deg;
  EXPECT_TRUE(frame(compass_at(near_limit, 0.1f)).found);
  EXPECT_FALSE(frame(compass_at(wall_yaw - cfg.compass_veto_agreement - 0.5f * deg, 0.1f)).found)
      << "edges off the wall by more than compass_veto_agreement";
  EXPECT_FALSE(frame(compass_at(box_yaw + 0.5f * deg, 0.5f)).found) << "edges agreeing with the box";
  EXPECT_FALSE(frame(compass_at(room_yaw, cfg.compass_veto_min_support - 0.01f)).found)
      << "edges with too little support";
  ManhattanConfig off;
  off.compass_veto_min_support = 1.f;
  EXPECT_FALSE(frame(compass_at(room_yaw, 0.5f), off).found) << "rule off";
}

// The same on the synthetic world (white noise, the suite's seed): room_clutter #6 and #10, a box
// turned against the room with slivers of the far walls at the depth cut-off beyond it (2.4 to
// 5 deg off, one of #6's 19 deg), had no frame; the image edges give it within 2 deg.
TEST(ManhattanFrame, ImageEdgesGiveTheFrameThatFarWallsVetoed) {
  ManhattanConfig off;
  off.compass_veto_min_support = 1.f;
  for (long index : {6L, 10L}) {
    const View v = run_view("room_clutter_static", index, kSuiteSeed);
    ASSERT_GE(v.truth.wall_or_riser_pixels, 500) << "#" << index;
    EXPECT_GE(v.yaw_err, 0.f) << "#" << index << ": no frame (" << v.sc.manhattan_why << ")";
    EXPECT_LE(v.yaw_err, 2.f) << "#" << index;
    const View w = run_view("room_clutter_static", index, kSuiteSeed, off);
    EXPECT_LT(w.yaw_err, 0.f) << "#" << index << " without the rule: a frame " << w.yaw_err << " deg off";
  }
}

// A strip of wall 0.29 x 0.08 m standing on the floor 2.2 m ahead with nothing beyond it (a wall's
// foot in a corner of the view) is too small to make a frame alone (min_area). Image edges too weak
// to confirm just any plane (below compass_min_support, above compass_wall_min_support) confirm
// it: the frame is the strip's yaw. They confirm no plane floating above the floor nor one with the
// floor going on beyond it (furniture), and nothing when they disagree by more than
// compass_agreement, have less support, or the rule is off.
TEST(ManhattanFrame, WeakImageEdgesConfirmOnlyAWallStrip) {
  const Pose T = level_camera();
  const float deg = 3.14159265f / 180.f;
  const float yaw = 7.f * deg;
  const ManhattanConfig cfg;
  ASSERT_LT(cfg.compass_wall_min_support, cfg.compass_min_support);
  const float weak = 0.5f * (cfg.compass_wall_min_support + cfg.compass_min_support);
  const PlaneRegion strip = upright_on_floor(T, 2.2f, yaw, 0.29f, 0.08f, 0.01f);
  ASSERT_LT(strip.area, cfg.min_area);
  const std::vector<PlaneRegion> wall = {floor_between(T, 0.8f, 2.2f), strip};
  auto frame = [&](const std::vector<PlaneRegion>& planes, const std::function<EdgeCompassResult()>& compass,
                   const ManhattanConfig& c = ManhattanConfig{}) {
    ManhattanTracker m(c);
    return m.estimate(planes, T, compass);
  };
  EXPECT_FALSE(frame(wall, {}).found) << "the strip alone made a frame";
  const ManhattanEstimate e = frame(wall, compass_at(yaw + 0.5f * deg, weak));
  ASSERT_TRUE(e.found) << e.why;
  EXPECT_NEAR(e.yaw, yaw, 0.01f * deg) << "the frame is the strip's yaw";
  EXPECT_FALSE(frame(wall, compass_at(yaw + cfg.compass_agreement + 0.5f * deg, weak)).found)
      << "edges off the strip by more than compass_agreement";
  const ManhattanEstimate none = frame(wall, compass_at(yaw, cfg.compass_wall_min_support - 0.01f));
  EXPECT_FALSE(none.found) << "edges with too little support";
  EXPECT_NE(none.why.find("no clear direction"), std::string::npos) << none.why;
  ManhattanConfig off;
  off.compass_wall_min_support = 1.f;
  EXPECT_FALSE(frame(wall, compass_at(yaw, weak), off).found) << "rule off";
  // Furniture: the same strip with the floor going on beyond it, or floating above the floor.
  const std::vector<PlaneRegion> inside = {floor_between(T, 0.8f, 3.5f), strip};
  const ManhattanEstimate f = frame(inside, compass_at(yaw, weak));
  EXPECT_FALSE(f.found) << "a strip with the floor beyond it: frame " << f.yaw / deg << " deg";
  EXPECT_NE(f.why.find("too weak"), std::string::npos) << f.why;
  const PlaneRegion floating = lowered(strip, T, -0.5f);  // 0.5 m up
  EXPECT_FALSE(frame({floor_between(T, 0.8f, 2.2f), floating}, compass_at(yaw, weak)).found)
      << "a strip floating above the floor";
  // Edges with the support to confirm any plane confirm the furniture's strip (the rule it extends).
  EXPECT_TRUE(frame(inside, compass_at(yaw, cfg.compass_min_support)).found);
}

// The same on the synthetic world (white noise, the suite's seed): people #14 sees the floor and,
// in a corner, two patches of a wall's foot (0.017 and 0.005 m^2, 0.5 and 0.9 deg off); its image
// edges are 0.9 deg off with support 0.08.
TEST(ManhattanFrame, WeakImageEdgesConfirmAWallsFootInACorner) {
  const View v = run_view("people_static", 14, kSuiteSeed);
  ASSERT_GE(v.truth.wall_or_riser_pixels, 200);
  EXPECT_GE(v.yaw_err, 0.f) << "no frame (" << v.sc.manhattan_why << ")";
  EXPECT_LE(v.yaw_err, 2.f);
  ManhattanConfig off;
  off.compass_wall_min_support = 1.f;
  const View w = run_view("people_static", 14, kSuiteSeed, off);
  EXPECT_LT(w.yaw_err, 0.f) << "without the rule: a frame " << w.yaw_err << " deg off";
}
