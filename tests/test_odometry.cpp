// Dense odometry (paper 5.1) on pairs rendered by a small ray caster with known motion.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <new>
#include <opencv2/imgproc.hpp>
#include <opencv2/rgbd.hpp>
#include <optional>

#include "stairguide/capture/dataset.hpp"
#include "stairguide/capture/synth_source.hpp"
#include "stairguide/odometry/dense_odometry.hpp"
#include "stairguide/odometry/trajectory_metrics.hpp"
#include "test_odometry_scene.hpp"

using namespace stairguide;

// Counts heap allocations of this test binary, to check that tracking allocates nothing once
// the first frame has sized the buffers.
namespace {
std::atomic<long> g_allocations{0};
}
void* operator new(std::size_t n) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }

namespace {

CameraIntrinsics vga() { return CameraIntrinsics{}; }

/// Translation (m) and rotation (deg) of the error between two relative poses.
struct Err {
  float t, r;
};
Err pose_error(const Pose& est, const Pose& truth) {
  const Pose E = truth.inverse() * est;
  return {E.translation().norm(), rad2deg(Eigen::AngleAxisf(E.linear()).angle())};
}

/// A small motion expressed in the camera frame: translation (m) and Euler angles (deg).
Pose motion(float tx, float ty, float tz, float rx_deg, float ry_deg, float rz_deg) {
  Pose T = Pose::Identity();
  T.linear() = (Eigen::AngleAxisf(deg2rad(rx_deg), Eigen::Vector3f::UnitX()) *
                Eigen::AngleAxisf(deg2rad(ry_deg), Eigen::Vector3f::UnitY()) *
                Eigen::AngleAxisf(deg2rad(rz_deg), Eigen::Vector3f::UnitZ()))
                   .toRotationMatrix();
  T.translation() = Eigen::Vector3f(tx, ty, tz);
  return T;
}

struct Pair {
  RgbdFrame a, b;
  Pose T_a_b;
};

Pair make_pair(const Pose& T_a_b, bool noise, std::uint32_t seed = 1) {
  const sgtest::Scene scene = sgtest::Scene::stairs();
  const Pose Ta = sgtest::chest_camera(0.1f, 0.3f, 1.35f, 45.f, 5.f);
  sgtest::Scene::RenderOptions o;
  o.noise = noise;
  o.seed = seed;
  Pair p;
  p.a = scene.render(Ta, vga(), o);
  o.seed = seed + 1;
  p.b = scene.render(Ta * T_a_b, vga(), o);
  p.a.timestamp = 0.0;
  p.b.timestamp = 1.0 / 30.0;
  p.b.index = 1;
  p.T_a_b = T_a_b;
  return p;
}

/// OpenCV's RgbdOdometry on a pair; returns inverse(Rt) (its Rt maps the first frame's points
/// into the second: Rt = T_b_a) and whether it reported success.
Pose reference_T_a_b(const Pair& p, bool* ok) {
  const CameraIntrinsics k = vga();
  const cv::Mat K = (cv::Mat_<double>(3, 3) << k.fx, 0, k.cx, 0, k.fy, k.cy, 0, 0, 1);
  auto odo = cv::rgbd::RgbdOdometry::create(K, 0.4f, 5.f);
  cv::Mat Rt;
  *ok = odo->compute(p.a.gray, p.a.depth, cv::Mat(), p.b.gray, p.b.depth, cv::Mat(), Rt);
  Eigen::Matrix4f M = Eigen::Matrix4f::Identity();
  if (*ok)
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) M(r, c) = static_cast<float>(Rt.at<double>(r, c));
  Pose T;
  T.matrix() = M;
  return T.inverse();
}

OdometryResult track_pair(const Pair& p, const OdometryConfig& cfg = {}) {
  DenseOdometry odo(cfg, vga());
  const OdometryResult r0 = odo.track(p.a);
  EXPECT_TRUE(r0.ok);
  EXPECT_EQ(r0.status, OdometryStatus::kFirstFrame);
  return odo.track(p.b);
}

}  // namespace

TEST(DenseOdometry, RecoversKnownMotionOnNoiseFreePair) {
  const Pair p = make_pair(motion(0.03f, -0.01f, 0.04f, 1.0f, -1.5f, 0.5f), false);
  const OdometryResult r = track_pair(p);
  ASSERT_TRUE(r.ok) << r.why;
  const Err e = pose_error(r.T_prev_curr, p.T_a_b);
  std::printf("noise-free pair: %.3f mm, %.4f deg, %d px, %d iterations, inliers %.3f\n", e.t * 1000.f, e.r,
              r.pixels_used, r.iterations, r.inlier_fraction);
  EXPECT_LE(e.t, 0.002f);
  EXPECT_LE(e.r, 0.1f);
  EXPECT_TRUE(r.converged);
  EXPECT_GT(r.pixels_used, 5000);
  // Accumulated pose of the second frame is the relative one (first camera = world).
  EXPECT_LE(pose_error(r.T_world_camera, r.T_prev_curr).t, 1e-6f);
  // The information matrix is symmetric positive definite.
  const Eigen::Matrix<float, 6, 6> H = r.information;
  EXPECT_LE((H - H.transpose()).norm(), 1e-3f * H.norm());
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix<float, 6, 6>> es(H);
  EXPECT_GT(es.eigenvalues().minCoeff(), 0.f);
  // The reference's convention, which eval-odometry relies on: Rt = T_curr_prev.
  bool ref_ok = false;
  const Pose ref = reference_T_a_b(p, &ref_ok);
  ASSERT_TRUE(ref_ok);
  EXPECT_LE(pose_error(ref, p.T_a_b).t, 0.01f);
}

TEST(DenseOdometry, TracksFastTurnOf14cmAnd7deg) {
  // 14 cm and 7 degrees in one frame: a fast turn while walking, or a dropped frame.
  const Pair p = make_pair(motion(0.05f, 0.02f, 0.128f, 1.0f, 6.9f, 0.5f), false);
  ASSERT_NEAR(p.T_a_b.translation().norm(), 0.14f, 0.002f);
  const OdometryResult r = track_pair(p);
  ASSERT_TRUE(r.ok) << r.why;
  const Err e = pose_error(r.T_prev_curr, p.T_a_b);
  std::printf("14 cm / 7 deg: %.3f mm, %.4f deg, %d iterations\n", e.t * 1000.f, e.r, r.iterations);
  EXPECT_LE(e.t, 0.005f);
  EXPECT_LE(e.r, 0.2f);
  bool ref_ok = false;
  const Err er = pose_error(reference_T_a_b(p, &ref_ok), p.T_a_b);
  std::printf("  OpenCV RgbdOdometry on the same pair: %s, %.1f mm, %.2f deg\n", ref_ok ? "ok" : "failed",
              er.t * 1000.f, er.r);
}

TEST(DenseOdometry, RobustToTenPercentOutlierPixels) {
  // A "person" in the second frame only: a near, differently textured block over 10% of the image.
  Pair p = make_pair(motion(0.02f, 0.0f, 0.03f, 0.5f, 1.0f, 0.0f), true, 7);
  const int w = p.b.depth.cols, h = p.b.depth.rows;
  const int bw = static_cast<int>(std::sqrt(0.10 * w * h * 0.6)), bh = static_cast<int>(0.10 * w * h / bw);
  const cv::Rect person(w / 2 - bw / 2 + 40, h / 2 - bh / 2, bw, bh);
  p.b.depth(person).setTo(cv::Scalar(1.1));
  cv::randu(p.b.gray(person), cv::Scalar(0), cv::Scalar(255));
  ASSERT_NEAR(static_cast<double>(person.area()) / (w * h), 0.10, 0.005);
  const OdometryResult r = track_pair(p);
  ASSERT_TRUE(r.ok) << r.why;
  const Err e = pose_error(r.T_prev_curr, p.T_a_b);
  std::printf("10%% outliers: %.3f mm, %.4f deg, inliers %.3f\n", e.t * 1000.f, e.r, r.inlier_fraction);
  EXPECT_LE(e.t, 0.003f);
  EXPECT_LE(e.r, 0.1f);
  EXPECT_LT(r.inlier_fraction, 0.95f);  // the person is seen as outliers
}

TEST(DenseOdometry, FlagsTexturelessDepthlessPairAndHoldsConstantVelocity) {
  // After two good frames the velocity is known; then the camera is covered: flat grey, no depth.
  const sgtest::Scene scene = sgtest::Scene::stairs();
  const Pose T0 = sgtest::chest_camera(0.f, 0.f, 1.35f, 45.f);
  const Pose step = motion(0.f, 0.f, 0.03f, 0.f, 0.5f, 0.f);
  sgtest::Scene::RenderOptions o;
  DenseOdometry odo(OdometryConfig{}, vga());
  RgbdFrame f0 = scene.render(T0, vga(), o), f1 = scene.render(T0 * step, vga(), o);
  f1.timestamp = 1.0 / 30.0;
  ASSERT_TRUE(odo.track(f0).ok);
  const OdometryResult r1 = odo.track(f1);
  ASSERT_TRUE(r1.ok) << r1.why;
  RgbdFrame blank;
  blank.intrinsics = vga();
  blank.depth = cv::Mat(480, 640, CV_32FC1, cv::Scalar(0));
  blank.gray = cv::Mat(480, 640, CV_8UC1, cv::Scalar(128));
  for (int i = 0; i < 2; ++i) {
    blank.timestamp = (2 + i) / 30.0;
    const OdometryResult r = odo.track(blank);
    EXPECT_FALSE(r.ok);
    EXPECT_EQ(r.status, OdometryStatus::kTooFewPixels);
    EXPECT_STRNE(r.why, "");
    EXPECT_EQ(r.consecutive_failures, i + 1);
    EXPECT_TRUE(r.information.isZero());
    // The pose is the constant-velocity guess: the last measured step again.
    EXPECT_LE(pose_error(r.T_prev_curr, r1.T_prev_curr).t, 1e-5f);
    EXPECT_LE(pose_error(r.T_world_camera,
                         r1.T_prev_curr * r1.T_prev_curr * (i ? r1.T_prev_curr : Pose::Identity()))
                  .t,
              1e-4f);
  }
  // A fresh odometry on a textureless, depthless pair flags both frames.
  DenseOdometry fresh(OdometryConfig{}, vga());
  EXPECT_FALSE(fresh.track(blank).ok);
  const OdometryResult r = fresh.track(blank);
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.status, OdometryStatus::kTooFewPixels);
  EXPECT_LE(r.T_world_camera.translation().norm(), 1e-6f);
}

TEST(DenseOdometry, RecoversAfterDepthlessFramesAgainstTheLastGoodOne) {
  // Frames 0, 1 good; 2 covered; 3 good again: 3 is tracked against 1 (two steps) and lands on
  // the truth although the guess for 2 was only a guess.
  const sgtest::Scene scene = sgtest::Scene::stairs();
  const Pose T0 = sgtest::chest_camera(0.f, 0.f, 1.35f, 45.f);
  const Pose step = motion(0.01f, 0.f, 0.03f, 0.f, 0.8f, 0.f);
  sgtest::Scene::RenderOptions o;
  DenseOdometry odo(OdometryConfig{}, vga());
  ASSERT_TRUE(odo.track(scene.render(T0, vga(), o)).ok);
  ASSERT_TRUE(odo.track(scene.render(T0 * step, vga(), o)).ok);
  RgbdFrame blank = scene.render(T0 * step * step, vga(), o);
  blank.depth.setTo(cv::Scalar(0));
  EXPECT_FALSE(odo.track(blank).ok);
  const OdometryResult r = odo.track(scene.render(T0 * step * step * step, vga(), o));
  ASSERT_TRUE(r.ok) << r.why;
  const Err e = pose_error(r.T_world_camera, step * step * step);
  EXPECT_LE(e.t, 0.002f);
  EXPECT_LE(e.r, 0.1f);
}

TEST(DenseOdometry, FlagsJumpBeyondWalkingMotion) {
  OdometryConfig cfg;
  cfg.max_translation = 0.05f;  // a 6 cm step is then implausible
  const Pair p = make_pair(motion(0.f, 0.f, 0.06f, 0.f, 0.f, 0.f), false);
  const OdometryResult r = track_pair(p, cfg);
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.status, OdometryStatus::kJump);
  EXPECT_LE(r.T_prev_curr.translation().norm(), 1e-6f);  // held the (zero) velocity guess
}

TEST(DenseOdometry, AllocatesNothingPerFrameAfterTheFirst) {
  const sgtest::Scene scene = sgtest::Scene::stairs();
  const Pose T0 = sgtest::chest_camera(0.f, 0.f, 1.35f, 45.f);
  const Pose step = motion(0.01f, 0.f, 0.03f, 0.f, 0.8f, 0.f);
  sgtest::Scene::RenderOptions o;
  std::vector<RgbdFrame> frames;
  Pose T = T0;
  for (int i = 0; i < 5; ++i, T = T * step) {
    frames.push_back(scene.render(T, vga(), o));
    frames.back().timestamp = i / 30.0;
  }
  // A colour-only frame exercises the grey conversion too.
  cv::cvtColor(frames[3].gray, frames[3].color, cv::COLOR_GRAY2BGR);
  frames[3].gray.release();
  // OpenCV's own worker pool (cvtColor of the colour-only frame may hand rows to it) allocates
  // its per-thread data the first time a worker happens to take part, which made this count
  // flaky (about 1 run in 20). Run OpenCV on the calling thread: what is counted is then the
  // stage's own work.
  const int cv_threads = cv::getNumThreads();
  cv::setNumThreads(0);
  DenseOdometry odo(OdometryConfig{}, vga());
  ASSERT_TRUE(odo.track(frames[0]).ok);
  ASSERT_TRUE(odo.track(frames[1]).ok);
  const long before = g_allocations.load();
  bool all_ok = true;
  for (int i = 2; i < 5; ++i) all_ok = odo.track(frames[static_cast<std::size_t>(i)]).ok && all_ok;
  const long after = g_allocations.load();
  cv::setNumThreads(cv_threads);
  EXPECT_TRUE(all_ok);
  EXPECT_EQ(after - before, 0);
}

TEST(DenseOdometry, RejectsFrameOfAnotherSize) {
  DenseOdometry odo(OdometryConfig{}, vga());
  RgbdFrame f;
  f.depth = cv::Mat(240, 320, CV_32FC1, cv::Scalar(1.0));
  f.gray = cv::Mat(240, 320, CV_8UC1, cv::Scalar(100));
  const OdometryResult r = odo.track(f);
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.status, OdometryStatus::kBadInput);
}

TEST(DenseOdometry, WorksAtOtherResolutions) {
  // No size is hard-coded: a QVGA camera with its own intrinsics.
  const CameraIntrinsics qvga = vga().scaled(0.5f);
  const sgtest::Scene scene = sgtest::Scene::stairs();
  const Pose Ta = sgtest::chest_camera(0.1f, 0.3f, 1.35f, 45.f, 5.f);
  const Pose m = motion(0.02f, 0.f, 0.04f, 0.f, 1.5f, 0.f);
  sgtest::Scene::RenderOptions o;
  DenseOdometry odo(OdometryConfig{}, qvga);
  ASSERT_TRUE(odo.track(scene.render(Ta, qvga, o)).ok);
  const OdometryResult r = odo.track(scene.render(Ta * m, qvga, o));
  ASSERT_TRUE(r.ok) << r.why;
  EXPECT_LE(pose_error(r.T_prev_curr, m).t, 0.002f);
}

namespace {

/// Runs ours and the reference over `frames` frames of a source (as eval-odometry does);
/// trajectories index-aligned with the ground truth.
struct SequenceRun {
  std::vector<StampedPose> ours, ref, truth;
  int failures = 0;
};

SequenceRun run_sequence(FrameSource& src, long frames, bool truth_from_source,
                         const std::vector<TimedPose>& groundtruth = {}) {
  SequenceRun run;
  const CameraIntrinsics k = src.intrinsics();
  DenseOdometry odo(OdometryConfig{}, k);
  const cv::Mat K = (cv::Mat_<double>(3, 3) << k.fx, 0, k.cx, 0, k.fy, k.cy, 0, 0, 1);
  auto ref = cv::rgbd::RgbdOdometry::create(K, 0.4f, 5.f);
  cv::Ptr<cv::rgbd::OdometryFrame> prev;
  Eigen::Isometry3d ref_pose = Eigen::Isometry3d::Identity(), ref_velocity = Eigen::Isometry3d::Identity();
  RgbdFrame f;
  for (long i = 0; i < frames; ++i) {
    const ReadResult rr = src.read(f);
    if (!rr.ok()) break;
    if (f.gray.empty()) cv::cvtColor(f.color, f.gray, cv::COLOR_BGR2GRAY);
    const OdometryResult r = odo.track(f);
    run.failures += r.ok ? 0 : 1;
    cv::Ptr<cv::rgbd::OdometryFrame> of = cv::rgbd::OdometryFrame::create(f.gray.clone(), f.depth.clone());
    if (prev) {
      // Same policy as ours: constant-velocity initial guess, held when the reference fails.
      cv::Mat init(4, 4, CV_64FC1), Rt;
      for (int a = 0; a < 4; ++a)
        for (int b = 0; b < 4; ++b) init.at<double>(a, b) = ref_velocity(a, b);
      if (ref->compute(prev, of, Rt, init))
        for (int a = 0; a < 4; ++a)
          for (int b = 0; b < 4; ++b) ref_velocity.matrix()(a, b) = Rt.at<double>(a, b);
      ref_pose = ref_pose * ref_velocity.inverse();
    }
    prev = of;
    std::optional<Pose> g;
    if (truth_from_source) {
      if (auto t = src.truth()) g = t->T_world_camera;
    } else {
      for (const auto& p : groundtruth)
        if (std::fabs(p.timestamp - f.timestamp) < 0.005) g = p.T_world_camera;
    }
    if (!g) continue;
    run.truth.push_back({f.timestamp, *g});
    run.ours.push_back({f.timestamp, r.T_world_camera});
    run.ref.push_back({f.timestamp, ref_pose.cast<float>()});
  }
  return run;
}

}  // namespace

TEST(DenseOdometrySequence, SyntheticFastTurnBeatsReference) {
  // 90 frames (3 s) of the fast-turn preset: up to 10 deg between frames, rendered noise.
  auto src = synth::make_source("ascending_turn_fast", 90, 1);
  const SequenceRun run = run_sequence(*src, 90, true);
  ASSERT_GE(run.truth.size(), 85u);
  const RpeResult ours = relative_pose_error(run.ours, run.truth),
                  ref = relative_pose_error(run.ref, run.truth);
  const double ate = absolute_trajectory_error(run.ours, run.truth).rmse();
  std::printf(
      "fast turn, 90 frames: RPE ours %.4f m/s %.3f deg/s, reference %.4f m/s %.3f deg/s; ATE ours %.4f m\n",
      ours.translation_m_s.rmse(), ours.rotation_deg_s.rmse(), ref.translation_m_s.rmse(),
      ref.rotation_deg_s.rmse(), ate);
  EXPECT_EQ(run.failures, 0);
  EXPECT_GT(ours.translation_m_s.count, 20u);
  EXPECT_LE(ours.translation_m_s.rmse(), 0.5 * ref.translation_m_s.rmse());
  EXPECT_LE(ours.translation_m_s.rmse(), 0.01);
  EXPECT_LE(ours.rotation_deg_s.rmse(), 0.5);
  EXPECT_LE(ate, 0.01);
}

TEST(DenseOdometrySequence, RealKitchenNotWorseThanReference) {
  // The whole 300-frame sequence (not a window chosen where we win): RPE over 1 s and ATE must
  // not be worse than OpenCV RgbdOdometry's on the same frames. Measured (keyframes on):
  // ours 0.0286 m/s, 1.33 deg/s, ATE 22.7 mm; reference 0.0302 m/s, 1.77 deg/s, ATE 24.8 mm.
  const std::string dir = std::string(STAIRGUIDE_SHARED_DATA) + "/7scenes-redkitchen-0000-0299";
  if (!std::filesystem::exists(dir + "/groundtruth.txt")) GTEST_SKIP() << "no shared data at " << dir;
  DatasetSource src(dir);
  const SequenceRun run = run_sequence(src, 300, false, read_groundtruth(dir + "/groundtruth.txt"));
  ASSERT_GE(run.truth.size(), 295u);
  const RpeResult ours = relative_pose_error(run.ours, run.truth),
                  ref = relative_pose_error(run.ref, run.truth);
  const double ate_ours = absolute_trajectory_error(run.ours, run.truth).rmse(),
               ate_ref = absolute_trajectory_error(run.ref, run.truth).rmse();
  std::printf(
      "7-Scenes kitchen, 300 frames: RPE ours %.4f m/s %.3f deg/s ATE %.4f m, reference %.4f m/s %.3f "
      "deg/s ATE %.4f m\n",
      ours.translation_m_s.rmse(), ours.rotation_deg_s.rmse(), ate_ours, ref.translation_m_s.rmse(),
      ref.rotation_deg_s.rmse(), ate_ref);
  EXPECT_EQ(run.failures, 0);
  EXPECT_LE(ours.translation_m_s.rmse(), ref.translation_m_s.rmse());
  EXPECT_LE(ours.rotation_deg_s.rmse(), ref.rotation_deg_s.rmse());
  EXPECT_LE(ate_ours, ate_ref);
  EXPECT_LE(ours.translation_m_s.rmse(), 0.032);  // frame to frame only, it was 0.0353 m/s
}
