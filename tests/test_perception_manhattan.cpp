// Manhattan frame (paper 3.2.2, issue 3) on single synthetic views named in the issue's notes.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "stairguide/capture/synthetic.hpp"
#include "stairguide/perception/perception.hpp"
#include "manhattan_test_util.hpp"

using namespace stairguide;

namespace {

struct View {
  SceneResult sc;
  FrameTruth truth;
  float yaw_err = -1.f;  // degrees; < 0: no frame
};

View run_view(const std::string& preset, long index, std::uint32_t seed) {
  View v;
  RgbdFrame frame;
  synth::render_preset_frame(preset, index, seed, synth::SynthOptions{}, frame, v.truth);
  Perception P;
  P.process(frame, v.sc);
  v.yaw_err = sg_test::manhattan_yaw_error_deg(v.sc, v.truth);
  return v;
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
  EXPECT_TRUE(v.yaw_err < 0.f || v.yaw_err <= 2.f) << "descending_static #12 seed 6: frame " << v.yaw_err << " deg off";
}

// Narrow strips of one riser (0.13 and 0.15 m, 1.1 m apart on one line) and of one wall (0.13 and
// 0.12 m, 1.4 m apart) were refused as too narrow: together they are as wide as they span.
TEST(ManhattanFrame, StripsOfOnePlaneMakeAFrame) {
  const struct {
    const char* preset;
    long index;
  } views[] = {{"ascending_static", 17}, {"people_static", 17}};
  for (const auto& c : views) {
    const View v = run_view(c.preset, c.index, kSuiteSeed);
    ASSERT_GE(v.truth.wall_or_riser_pixels, 1000) << c.preset << " #" << c.index;
    EXPECT_GE(v.yaw_err, 0.f) << c.preset << " #" << c.index << ": no frame (" << v.sc.manhattan_why << ")";
    EXPECT_LE(v.yaw_err, 2.f) << c.preset << " #" << c.index;
  }
}

// A strip of wall 0.23 to 0.29 m wide seen past shelves or a sofa turned against the room has only
// 0.014 to 0.016 m^2 in view: half of it beyond the furniture's plane vetoes the furniture's frame
// (14 degrees off before).
TEST(ManhattanFrame, SmallWallBeyondFurnitureVetoesItsFrame) {
  const struct {
    const char* preset;
    long index;
    std::uint32_t seed;
  } views[] = {{"sofa_static", 6, 12}, {"shelves_static", 19, 11}};
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
  const struct {
    const char* preset;
    long index;
    std::uint32_t seed;
  } views[] = {{"sofa_static", 23, kSuiteSeed}, {"sofa_static", 13, 1}, {"shelves_static", 13, 3}};
  for (const auto& c : views) {
    const View v = run_view(c.preset, c.index, c.seed);
    ASSERT_GE(v.truth.wall_or_riser_pixels, 1000) << c.preset << " #" << c.index << " seed " << c.seed;
    EXPECT_GE(v.yaw_err, 0.f) << c.preset << " #" << c.index << " seed " << c.seed << ": no frame ("
                              << v.sc.manhattan_why << ")";
    EXPECT_LE(v.yaw_err, 2.f) << c.preset << " #" << c.index << " seed " << c.seed;
  }
}

// A wall standing on the floor with no floor beyond it, 0.29 m wide between shelves turned 17 deg
// against the room: trusted from ManhattanConfig::min_bounding_width (0.2 m, as wide as a wall
// that may veto a frame) it gives the room's frame (before, at 0.3 m: it only vetoed the
// shelves' frame, and there was none).
TEST(ManhattanFrame, NarrowWallOnTheFloorGivesTheFrame) {
  const View v = run_view("shelves_static", 18, kSuiteSeed);
  ASSERT_GE(v.truth.wall_or_riser_pixels, 500);
  EXPECT_GE(v.yaw_err, 0.f) << "shelves_static #18: no frame (" << v.sc.manhattan_why << ")";
  EXPECT_LE(v.yaw_err, 2.f) << "shelves_static #18";
}

// A handrail beside an open-sided descent, seen against the floor below, comes out as a vertical
// band a few centimetres thick along the flight's slope, 0.85-1.6 m long: its plane is fixed only
// up to a turn about that sloping axis, which turns its yaw. It made frames 4.4-5.5 deg off with
// the staircase in view; it makes none now.
TEST(ManhattanFrame, SlopedHandrailMakesNoFrame) {
  const struct {
    const char* preset;
    long index;
    std::uint32_t seed;
  } views[] = {{"descending_static", 16, 1}, {"descending_static", 7, 7}, {"descending_static", 20, 11},
               {"people_static", 6, 9}};
  for (const auto& c : views) {
    const View v = run_view(c.preset, c.index, c.seed);
    ASSERT_TRUE(v.truth.any_stair_visible()) << c.preset << " #" << c.index << " seed " << c.seed;
    EXPECT_TRUE(v.yaw_err < 0.f || v.yaw_err <= 2.f)
        << c.preset << " #" << c.index << " seed " << c.seed << ": frame " << v.yaw_err << " deg off";
  }
}
