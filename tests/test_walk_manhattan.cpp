// The Manhattan frame carried by the odometry (Perception::apply_odometry): walls do not turn when
// the user does, so a frame seen in one view holds, through the odometry's rotation, for the views
// after it whose own walls are too little to make one (a strip of wall while turning).
//
// This binary runs this project's own DenseOdometry with perception on every frame of the walks,
// as the daemon does: the poses are estimated, not the truth's.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <algorithm>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "stairguide/capture/dataset.hpp"
#include "stairguide/capture/frame_source.hpp"
#include "stairguide/capture/synth_source.hpp"
#include "stairguide/core/config.hpp"
#include "stairguide/odometry/dense_odometry.hpp"
#include "stairguide/perception/perception.hpp"
#include "manhattan_test_util.hpp"

using namespace stairguide;

namespace {

constexpr std::uint32_t kSeed = 20261123u;  // test_perception's seed: the same walks
constexpr int kMinWallOrRiserPixels = 200;  // as test_perception: a wall or riser "visible"

struct WalkFigures {
  int frames = 0, checked = 0, ok = 0, ok_without_carry = 0, carried = 0, carried_checked = 0;
  int odometry_failures = 0, wrong = 0;
  float worst_carried = 0.f;
};

// Our odometry and perception on a stream of frames, as the daemon runs them (in one thread).
struct OdometryAndPerception {
  PipelineConfig cfg;
  DenseOdometry odo;
  Perception perception{cfg};
  OdometryLink link;
  OdometryResult r;
  explicit OdometryAndPerception(const CameraIntrinsics& k) { odo.configure(cfg.odometry, k); }
  /// The odometry on `f` (a failure starts a new track: a failed frame's pose is a guess), and
  /// perception's own view of it into `sc`.
  void see(const RgbdFrame& f, SceneResult& sc) {
    r = odo.track(f);
    if (!r.ok) ++link.track;
    link.T_world_camera = r.T_world_camera;
    perception.process(f, sc);
  }
  /// The Manhattan frame held in the odometry's world given to `sc`, when the odometry tracked `f`.
  void hold(const RgbdFrame& f, SceneResult& sc) {
    if (r.ok) perception.apply_odometry(link, f.timestamp, sc);
  }
};

// Every frame of `preset` through DenseOdometry and Perception.
WalkFigures run_walk(const std::string& preset, long frames, const synth::SynthOptions& options = {}) {
  auto src = synth::make_source(preset, frames, kSeed, options);
  OdometryAndPerception run(src->intrinsics());
  RgbdFrame f;
  SceneResult sc;
  WalkFigures W;
  for (long i = 0; i < frames; ++i) {
    if (src->read(f).status != ReadStatus::kOk) break;
    const auto truth = src->truth();
    run.see(f, sc);
    W.odometry_failures += !run.r.ok;
    const float e_own = truth ? sg_test::manhattan_yaw_error_deg(sc, *truth) : -1.f;  // this view's own frame
    run.hold(f, sc);
    ++W.frames;
    if (!truth) continue;
    const float e = sg_test::manhattan_yaw_error_deg(sc, *truth);
    const bool wall = truth->floor_visible && truth->wall_or_riser_pixels >= kMinWallOrRiserPixels;
    if (sc.manhattan_carried) {
      ++W.carried;
      W.worst_carried = std::max(W.worst_carried, e);
    }
    if (wall) {
      ++W.checked;
      W.ok += e >= 0.f && e <= 2.f;
      W.ok_without_carry += e_own >= 0.f && e_own <= 2.f;
      W.carried_checked += sc.manhattan_carried;
    }
    if (e > 2.f && (wall || truth->any_stair_visible())) {
      ++W.wrong;
      std::printf("  %s #%ld: Manhattan yaw off by %.2f deg%s\n", preset.c_str(), i, e,
                  sc.manhattan_carried ? " (carried)" : "");
    } else if (wall && e < 0.f) {
      std::printf("  %s #%ld: no Manhattan frame, a wall or riser of %d px in view (%s)\n", preset.c_str(), i,
                  truth->wall_or_riser_pixels, sc.manhattan_why.c_str());
    }
  }
  std::printf(
      "%-28s frames %4d | odometry failures %d | Manhattan within 2 deg %d/%d (%d without the odometry) | "
      "held frame given to %d (%d where a wall is in view), worst %.2f deg | off %d\n",
      preset.c_str(), W.frames, W.odometry_failures, W.ok, W.checked, W.ok_without_carry, W.carried,
      W.carried_checked, W.worst_carried, W.wrong);
  return W;
}

}  // namespace

// Issue 3's Manhattan figure on every frame of each walk, with the odometry holding the frame:
// never a frame more than 2 deg off where a wall, a riser or a staircase is in view, and a frame
// within 2 deg on every view with a wall or riser in view but `misses`.
struct Walk {
  const char* preset;
  long frames;
  int misses;
  bool real_like_noise =
      false;  // synth::with_real_kinect_noise(): depth noise correlated as the real sensor's
};
class WalkManhattan : public ::testing::TestWithParam<Walk> {};

TEST_P(WalkManhattan, FrameHeldByOurOdometry) {
  const Walk walk = GetParam();
  const WalkFigures W =
      run_walk(walk.preset, walk.frames,
               walk.real_like_noise ? synth::with_real_kinect_noise() : synth::SynthOptions{});
  EXPECT_EQ(W.wrong, 0) << "a Manhattan frame more than 2 deg off";
  EXPECT_EQ(W.odometry_failures, 0);
  EXPECT_LE(W.worst_carried, 2.f);
  EXPECT_GE(W.ok, W.checked - walk.misses) << "a view with a wall or riser in view and no frame within 2 deg";
  if (walk.misses > 0) {
    EXPECT_GT(W.carried_checked, 0) << "nothing was carried: the test does not test";
  }
}

INSTANTIATE_TEST_SUITE_P(
    Walks, WalkManhattan,
    ::testing::Values(
        // Walking toward a staircase with a fast turn (up to 10 deg between frames), during which
        // the wall shows only as a strip too narrow to make a frame of its own. Measured 122/123
        // (95/123 view by view): frame 33, facing the side wall at the start, sees a 515 px strip
        // of it before any view has made a frame to hold.
        Walk{"ascending_turn_fast", 300, 1}, Walk{"ascending_approach_climb", 600, 0},  // 374/374
        // No wall or riser face in view on the way down: no frame may be off with the flight in view.
        Walk{"descending_approach_descend", 600, 0}, Walk{"descending_people_approach", 300, 0}),
    [](const ::testing::TestParamInfo<Walk>& info) { return std::string(info.param.preset); });

// The same walks with the depth noise correlated in space as the real sensor's, where a view's own
// frame is off or missing more often (static views: 200/222 against 217/222 on white noise): the
// odometry still tracks every frame, and the frame it holds is never more than 2 deg off.
// Measured: the fast turn 121/123 (91 view by view), the approach and climb 374/374 (not run
// here: 12 s); no frame off on either or on the walk down past a person (7 views given the held
// frame there, within 1.36 deg).
INSTANTIATE_TEST_SUITE_P(WalksRealLikeNoise, WalkManhattan,
                         ::testing::Values(Walk{"ascending_turn_fast", 300, 2, true},
                                           Walk{"descending_people_approach", 300, 0, true}),
                         [](const ::testing::TestParamInfo<Walk>& info) {
                           return std::string(info.param.preset);
                         });

// The real 7-Scenes kitchen, hand-held, every frame: perception alone (the frame each view makes,
// tracked from frame to frame), then with our odometry holding the frame in the world. Its walls
// and cupboards do not move: the frames reported, put in the world by the sequence's ground-truth
// poses, must hold one direction; holding the frame must not make them spread more.
TEST(WalkManhattanReal, KitchenFrameHeldByOurOdometryHoldsStillInTheWorld) {
  const std::string dir = std::string(STAIRGUIDE_SHARED_DATA) + "/7scenes-redkitchen-0000-0299";
  if (!std::filesystem::exists(dir + "/groundtruth.txt")) GTEST_SKIP() << "no shared data at " << dir;
  PipelineConfig cfg;
  const std::vector<TimedPose> truth_poses = read_groundtruth(dir + "/groundtruth.txt");
  struct Spread {
    std::size_t views = 0, held = 0;
    float p95 = 0.f, worst = 0.f;
  };
  float mean = 0.f;  // the world direction of the frames seen without the odometry
  auto run = [&](bool with_odometry) {
    auto src = open_frame_source(dir, cfg.capture);  // as the daemon reads it (range gate included)
    OdometryAndPerception run(src->intrinsics());
    RgbdFrame f;
    SceneResult sc;
    sg_test::WorldManhattan world;
    Spread S;
    while (src->read(f).ok()) {
      run.see(f, sc);
      if (with_odometry) run.hold(f, sc);
      const TimedPose* truth = nullptr;
      for (const TimedPose& t : truth_poses)
        if (std::fabs(t.timestamp - f.timestamp) < 0.005) truth = &t;
      // Frames measured without a floor (about a floor-like plane refused as the floor) count too:
      // taking the largest floor-like plane when none was chosen gave 47 views frames up to 8.9 deg
      // off here (p95 3.1 deg held), while no synthetic view was off.
      if (!truth || !sc.manhattan_found) continue;
      world.add(sc, truth->T_world_camera.linear());
      S.held += sc.manhattan_carried;
    }
    if (!with_odometry) mean = world.mean_yaw();
    std::vector<float> dev;
    for (const float a : world.yaws())
      dev.push_back(std::fabs(sg_test::wrap45(a - mean)) / sg_test::kManhattanDeg);
    std::sort(dev.begin(), dev.end());
    S.views = dev.size();
    if (!dev.empty()) {
      S.p95 = dev[static_cast<std::size_t>(0.95 * static_cast<double>(dev.size() - 1))];
      S.worst = dev.back();
    }
    return S;
  };
  const Spread alone = run(false), held = run(true);
  std::printf(
      "kitchen, 300 frames: frame on %zu views, p95 %.2f, worst %.2f deg from their mean in the world; held "
      "by our odometry: %zu views (%zu given the held frame), p95 %.2f, worst %.2f deg\n",
      alone.views, alone.p95, alone.worst, held.views, held.held, held.p95, held.worst);
  ASSERT_GE(alone.views, 150u) << "the kitchen's floor and walls are seen on 198 of its 300 frames";
  // Measured: alone p95 1.93, worst 6.15 deg (198 views); held p95 1.14, worst 2.24 deg (198).
  EXPECT_GE(held.views, alone.views);
  EXPECT_LE(held.p95, 1.75f) << "the frame held in the world spreads";
  EXPECT_LE(held.worst, 3.f);
  EXPECT_LT(held.p95, alone.p95);
}

// The rules of the held frame on the fast turn with the truth's poses (no odometry error): a view
// seen before its pose came is held when it comes; nothing is carried across a change of the
// odometry's track, nor after carry_s; a late view from an old track is dropped.
TEST(WalkManhattanRules, HeldFrameRulesOnKnownPoses) {
  PipelineConfig cfg;
  const std::string preset = "ascending_turn_fast";
  RgbdFrame f;
  FrameTruth truth;
  // The last view before the turn that makes a frame of its own, and frame 100, a strip of wall.
  ManhattanSighting seen;
  FrameTruth seen_truth;
  float seen_error = -1.f;
  {
    Perception P(cfg);
    SceneResult sc;
    for (long i = 0; i < 97; ++i) {
      synth::render_preset_frame(preset, i, kSeed, synth::SynthOptions{}, f, truth);
      P.reset();
      P.process(f, sc);
      const ManhattanSighting s = P.manhattan_sighting(sc, f.timestamp);
      if (s.valid) seen = s, seen_truth = truth, seen_error = sg_test::manhattan_yaw_error_deg(sc, truth);
    }
  }
  ASSERT_TRUE(seen.valid) << "no view of frames 0-96 makes a frame";
  synth::render_preset_frame(preset, 100, kSeed, synth::SynthOptions{}, f, truth);
  auto link_of = [](const FrameTruth& t, std::uint64_t track) {
    OdometryLink l;
    l.T_world_camera = t.T_world_camera;
    l.track = track;
    return l;
  };
  // What frame 100 reports after `hold` (with the held view), given its link and time.
  auto frame_100 = [&](const std::function<void(Perception&)>& hold, std::uint64_t track, double t) {
    Perception P(cfg);
    hold(P);
    SceneResult sc;
    P.process(f, sc);
    EXPECT_FALSE(sc.manhattan_found) << "frame 100 made a frame of its own: the test does not test";
    P.apply_odometry(link_of(truth, track), t, sc);
    return sc;
  };
  const SceneResult carried =
      frame_100([&](Perception& P) { P.hold_manhattan(seen, link_of(seen_truth, 1)); }, 1, f.timestamp);
  ASSERT_TRUE(carried.manhattan_carried);
  // Carried by exact poses, the frame keeps the error the view that saw it made, nothing more.
  EXPECT_NEAR(sg_test::manhattan_yaw_error_deg(carried, truth), seen_error, 0.05f);
  EXPECT_LE(seen_error, 2.f);
  EXPECT_NEAR(carried.manhattan_carried_age, f.timestamp - seen.timestamp, 1e-3);
  EXPECT_FALSE(
      frame_100([&](Perception& P) { P.hold_manhattan(seen, link_of(seen_truth, 1)); }, 2, f.timestamp)
          .manhattan_found)
      << "carried across a change of the odometry's track";
  EXPECT_FALSE(frame_100([&](Perception& P) { P.hold_manhattan(seen, link_of(seen_truth, 1)); }, 1,
                         seen.timestamp + cfg.manhattan.carry_seconds + 0.1)
                   .manhattan_found)
      << "carried longer than carry_s";
  // Held on track 2 first (newer), then a late view of track 1: the late one is dropped.
  ManhattanSighting newer = seen;
  newer.timestamp += 0.1;
  newer.k_camera = Eigen::Vector3f(1.f, 0.f, 0.f);  // any direction: only its track matters here
  const SceneResult late = frame_100(
      [&](Perception& P) {
        P.hold_manhattan(newer, link_of(seen_truth, 2));
        P.hold_manhattan(seen, link_of(seen_truth, 1));
      },
      1, f.timestamp);
  EXPECT_FALSE(late.manhattan_found) << "a late view of the old track was held";
}
