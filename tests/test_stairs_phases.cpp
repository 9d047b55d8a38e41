// Stair modelling's phases called one by one (stair_axes.hpp, stair_levels.hpp, stair_profile.hpp)
// on hand-built perception results (test_stairs_scene.hpp) and on hand-made edges: each asserts a
// figure that the phase decides.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <vector>

#include "stairguide/stairs/stair_axes.hpp"
#include "stairguide/stairs/stair_levels.hpp"
#include "stairguide/stairs/stair_profile.hpp"
#include "test_stairs_scene.hpp"

namespace {

using namespace stairguide;
using sgtest::SceneBuilder;
using sgtest::StairSpec;

// The hypothesis modelling would be given: the floor as level 0, each tread region one level.
StairHypothesis levels_of(const SceneResult& scene, int direction) {
  StairHypothesis h;
  h.direction = direction;
  h.levels.emplace_back();
  for (std::size_t i = 0; i < scene.regions.size(); ++i) {
    const PlaneRegion& r = scene.regions[i];
    if (r.cls == RegionClass::kFloor) {
      h.levels[0].regions.push_back(static_cast<int>(i));
    } else if (r.cls == RegionClass::kStepCandidate) {
      LevelSeed s;
      s.index = static_cast<int>(h.levels.size());
      s.regions.push_back(static_cast<int>(i));
      h.levels.push_back(s);
    }
  }
  return h;
}

// The floor's up in the camera frame, as the scene's transform gives it.
Eigen::Vector3f floor_up(const SceneResult& scene) {
  return scene.T_floor_camera.linear().row(1).transpose();
}

float angle_deg(const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
  return rad2deg(std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.f, 1.f)));
}

// `up` turned by `deg` about the camera's x axis (a pitch error of the floor's normal).
Eigen::Vector3f pitched(const Eigen::Vector3f& up, float deg) {
  return Eigen::AngleAxisf(deg2rad(deg), Eigen::Vector3f::UnitX()) * up;
}

TEST(StairsPhases, VerticalIsFittedToTheLevelsAndKeptNearTheFloors) {
  SceneBuilder b(1.3f, 45.f, 3);
  StairSpec s;
  s.steps = 5;
  b.add_stairs(s);
  const StairHypothesis hyp = levels_of(b.scene, 1);
  ASSERT_GE(hyp.step_levels(), 4);
  const Eigen::Vector3f up = floor_up(b.scene);
  // The floor's normal 2 degrees off: the levels' own points bring it back.
  const Eigen::Vector3f off = pitched(up, 2.f);
  const Eigen::Vector3f fit = fit_stair_vertical(b.scene, hyp, off);
  EXPECT_LT(angle_deg(fit, up), 0.3f);
  EXPECT_GT(angle_deg(fit, off), 1.7f);
  EXPECT_NEAR(fit.norm(), 1.f, 1e-5f);
  // On the side of the guess, whichever way it points.
  EXPECT_GT(fit_stair_vertical(b.scene, hyp, -off).dot(-off), 0.99f);
  // 5 degrees off: the levels disagree with the floor by more than 3 degrees; the floor's is kept.
  const Eigen::Vector3f far = pitched(up, 5.f);
  EXPECT_EQ(fit_stair_vertical(b.scene, hyp, far), far);
  // Too few points: the guess.
  StairHypothesis empty;
  empty.levels.resize(2);
  EXPECT_EQ(fit_stair_vertical(b.scene, empty, off), off);

  // The horizontal basis: orthonormal, normal to up, e1 the camera's forward made horizontal.
  const StairFrame f = horizontal_basis(fit);
  EXPECT_NEAR(f.e1.dot(fit), 0.f, 1e-5f);
  EXPECT_NEAR(f.e2.dot(fit), 0.f, 1e-5f);
  EXPECT_NEAR(f.e1.dot(f.e2), 0.f, 1e-5f);
  EXPECT_NEAR(f.e1.norm(), 1.f, 1e-5f);
  EXPECT_GT(f.e1.z(), 0.6f);
}

TEST(StairsPhases, LevelsLieAtTheirHeightsAndTheirTreadsKeepTheirDepth) {
  // Heavy depth noise along the camera ray (3.5 cm at 2 m): moved along their rays onto the
  // level's plane, the points keep the tread's depth; dropped straight down they would not.
  SceneBuilder b(1.3f, 45.f, 5, 0.009f);
  StairSpec s;
  s.steps = 4;
  s.riser = 0.18f;
  s.tread = 0.30f;
  s.width = 1.0f;
  s.yaw_deg = 0.f;  // z_S along e1
  b.add_stairs(s);
  const StairHypothesis hyp = levels_of(b.scene, 1);
  ASSERT_EQ(static_cast<std::size_t>(hyp.step_levels()), b.truth.visible_steps.size());
  const StairFrame f = horizontal_basis(floor_up(b.scene));
  StairLevel2d floor, level;
  project_level(b.scene, hyp.levels[0], f.up, f.e1, f.e2, 3000, floor);
  ASSERT_GT(floor.pts.size(), 100u);
  std::vector<Eigen::Vector2f> sub;
  for (int k = 1; k <= hyp.step_levels(); ++k) {
    const int step = b.truth.visible_steps[static_cast<std::size_t>(k - 1)];
    project_level(b.scene, hyp.levels[static_cast<std::size_t>(k)], f.up, f.e1, f.e2, 4000, level);
    ASSERT_GT(level.pts.size(), 100u) << k;
    EXPECT_NEAR(level.plane - floor.plane, s.riser * static_cast<float>(step), 0.004f) << k;
    float lo = 1e9f, hi = -1e9f;
    for (const auto& p : level.pts) {
      lo = std::min(lo, p.x());
      hi = std::max(hi, p.x());
    }
    EXPECT_NEAR(hi - lo, s.tread, 0.03f) << k;
    // A whole tread is a rectangle: its hull fills its PCA rectangle, its major axis across (e2).
    level_shape(level, 600, sub);
    EXPECT_GT(level.extent, 0.9f) << k;
    EXPECT_GT(std::fabs(std::sin(level.pca_angle)), 0.99f) << k;
  }
}

TEST(StairsPhases, TreadLineByConsensusLeavesAnOddEdgeOut) {
  // Edges one 28 cm tread apart, the fifth 15 cm off the line (a landing's piece, a nosing hidden
  // by a person).
  std::vector<float> k, e;
  for (int i = 0; i < 6; ++i) {
    k.push_back(static_cast<float>(i));
    e.push_back(0.3f + 0.28f * static_cast<float>(i) + (i == 4 ? 0.15f : 0.f));
  }
  std::vector<char> in;
  std::vector<float> k_in, e_in;
  const EdgeLineFit fit = fit_edge_line(k, e, 0.03f, in, k_in, e_in);
  ASSERT_TRUE(fit.line.ok);
  EXPECT_NEAR(fit.line.slope, 0.28f, 1e-4f);
  EXPECT_NEAR(fit.line.intercept, 0.3f, 1e-4f);
  EXPECT_TRUE(fit.consistent);
  EXPECT_LT(fit.max_residual, 1e-4f);
  ASSERT_EQ(in.size(), 6u);
  for (int i = 0; i < 6; ++i) EXPECT_EQ(in[static_cast<std::size_t>(i)] != 0, i != 4) << i;
  EXPECT_EQ(k_in.size(), 5u);
  // A plain least-squares line through all of them is pulled off the tread.
  EXPECT_GT(std::fabs(fit_line(k, e).slope - 0.28f), 0.005f);

  // Half the edges off the line (three of six): no longer consistent.
  e[1] += 0.12f;
  e[5] -= 0.10f;
  const EdgeLineFit bad = fit_edge_line(k, e, 0.03f, in, k_in, e_in);
  EXPECT_FALSE(bad.consistent);
  EXPECT_EQ(k_in.size(), 3u);
}

}  // namespace
