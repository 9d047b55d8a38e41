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
#include "stairguide/capture/synthetic.hpp"
#include "stairguide/core/config.hpp"
#include "stairguide/odometry/dense_odometry.hpp"
#include "stairguide/perception/perception.hpp"
#include "manhattan_test_util.hpp"

using namespace stairguide;

namespace {

constexpr std::uint32_t kSeed = 20261123u;  // test_perception's seed: the same walks
constexpr int kMinWallOrRiserPixels = 200;   // as test_perception: a wall or riser "visible"

struct WalkFigures {
  int frames = 0, checked = 0, ok = 0, ok_without_carry = 0, carried = 0, carried_checked = 0;
  int odometry_failures = 0, wrong = 0;
  float worst_carried = 0.f;
};

// Every frame of `preset` through DenseOdometry and Perception, as the daemon runs them.
WalkFigures run_walk(const std::string& preset, long frames) {
  PipelineConfig cfg;
  auto src = synth::make_source(preset, frames, kSeed);
  DenseOdometry odo;
  odo.configure(cfg.odometry, src->intrinsics());
  Perception P(cfg);
  OdometryLink link;
  RgbdFrame f;
  SceneResult sc;
  WalkFigures W;
  for (long i = 0; i < frames; ++i) {
    if (src->read(f).status != ReadStatus::kOk) break;
    const auto truth = src->truth();
    const OdometryResult r = odo.track(f);
    if (!r.ok) {
      ++W.odometry_failures;
      ++link.track;  // a failed frame's pose is a guess: the world before it is not carried
    }
    link.T_world_camera = r.T_world_camera;
    P.process(f, sc);
    const float e_own = truth ? sg_test::manhattan_yaw_error_deg(sc, *truth) : -1.f;  // this view's own frame
    if (r.ok) P.apply_odometry(link, f.timestamp, sc);
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
  std::printf("%-28s frames %4d | odometry failures %d | Manhattan within 2 deg %d/%d (%d without the odometry) | "
              "held frame given to %d (%d where a wall is in view), worst %.2f deg | off %d\n",
              preset.c_str(), W.frames, W.odometry_failures, W.ok, W.checked, W.ok_without_carry, W.carried,
              W.carried_checked, W.worst_carried, W.wrong);
  return W;
}

}  // namespace

// Issue 3's Manhattan figure on the walks, every frame, with the odometry carrying the frame.
TEST(WalkManhattan, FastTurnCarriedByOurOdometry) {
  // 300 frames: walking toward a staircase with a fast turn (up to 10 deg between frames), during
  // which the wall shows only as a strip too narrow to make a frame of its own.
  const WalkFigures W = run_walk("ascending_turn_fast", 300);
  EXPECT_EQ(W.wrong, 0) << "a Manhattan frame more than 2 deg off";
  EXPECT_EQ(W.odometry_failures, 0);
  EXPECT_GT(W.carried_checked, 0) << "nothing was carried: the test does not test";
  EXPECT_LE(W.worst_carried, 2.f);
  // Measured 122/123: frame 33, facing the side wall at the start, sees a 515 px strip of it
  // before any view has made a frame to hold (97/123 without the odometry).
  EXPECT_GE(W.ok, W.checked - 1) << "a view with a wall or riser in view and no frame within 2 deg";
}

TEST(WalkManhattan, ApproachAndClimbCarriedByOurOdometry) {
  const WalkFigures W = run_walk("ascending_approach_climb", 600);
  EXPECT_EQ(W.wrong, 0) << "a Manhattan frame more than 2 deg off";
  EXPECT_LE(W.worst_carried, 2.f);
  EXPECT_EQ(W.ok, W.checked) << "a view with a wall or riser in view and no frame within 2 deg";
}

TEST(WalkManhattan, ApproachAndDescendCarriedByOurOdometry) {
  const WalkFigures W = run_walk("descending_approach_descend", 600);
  EXPECT_EQ(W.wrong, 0) << "a Manhattan frame more than 2 deg off";
  EXPECT_LE(W.worst_carried, 2.f);
  EXPECT_EQ(W.ok, W.checked) << "a view with a wall or riser in view and no frame within 2 deg";
}

TEST(WalkManhattan, DescentWithAPersonCarriedByOurOdometry) {
  const WalkFigures W = run_walk("descending_people_approach", 300);
  EXPECT_EQ(W.wrong, 0) << "a Manhattan frame more than 2 deg off";
  EXPECT_LE(W.worst_carried, 2.f);
  EXPECT_EQ(W.ok, W.checked) << "a view with a wall or riser in view and no frame within 2 deg";
}

// The real 7-Scenes kitchen, hand-held, every frame: perception alone (the frame each view makes,
// tracked from frame to frame), then with our odometry holding the frame in the world. Its walls
// and cupboards do not move: the frames reported, put in the world by the sequence's ground-truth
// poses, must hold one direction; holding the frame must not make them spread more.
TEST(WalkManhattan, KitchenFrameHeldByOurOdometryHoldsStillInTheWorld) {
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
    DenseOdometry odo;
    odo.configure(cfg.odometry, src->intrinsics());
    Perception P(cfg);
    OdometryLink link;
    RgbdFrame f;
    SceneResult sc;
    sg_test::WorldManhattan world;
    Spread S;
    while (src->read(f).ok()) {
      P.process(f, sc);
      if (with_odometry) {
        const OdometryResult r = odo.track(f);
        if (!r.ok) ++link.track;
        link.T_world_camera = r.T_world_camera;
        if (r.ok) P.apply_odometry(link, f.timestamp, sc);
      }
      const TimedPose* truth = nullptr;
      for (const TimedPose& t : truth_poses)
        if (std::fabs(t.timestamp - f.timestamp) < 0.005) truth = &t;
      if (!truth || !sc.floor_found || !sc.manhattan_found) continue;
      world.add(sc, truth->T_world_camera.linear());
      S.held += sc.manhattan_carried;
    }
    if (!with_odometry) mean = world.mean_yaw();
    std::vector<float> dev;
    for (const float a : world.yaws()) dev.push_back(std::fabs(sg_test::wrap45(a - mean)) / sg_test::kManhattanDeg);
    std::sort(dev.begin(), dev.end());
    S.views = dev.size();
    if (!dev.empty()) {
      S.p95 = dev[static_cast<std::size_t>(0.95 * static_cast<double>(dev.size() - 1))];
      S.worst = dev.back();
    }
    return S;
  };
  const Spread alone = run(false), held = run(true);
  std::printf("kitchen, 300 frames: frame on %zu views, p95 %.2f, worst %.2f deg from their mean in the world; held "
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
TEST(WalkManhattan, HeldFrameRulesOnKnownPoses) {
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
  const SceneResult carried = frame_100([&](Perception& P) { P.hold_manhattan(seen, link_of(seen_truth, 1)); }, 1,
                                        f.timestamp);
  ASSERT_TRUE(carried.manhattan_carried);
  // Carried by exact poses, the frame keeps the error the view that saw it made, nothing more.
  EXPECT_NEAR(sg_test::manhattan_yaw_error_deg(carried, truth), seen_error, 0.05f);
  EXPECT_LE(seen_error, 2.f);
  EXPECT_NEAR(carried.manhattan_carried_age, f.timestamp - seen.timestamp, 1e-3);
  EXPECT_FALSE(frame_100([&](Perception& P) { P.hold_manhattan(seen, link_of(seen_truth, 1)); }, 2, f.timestamp)
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
