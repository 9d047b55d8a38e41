// A real staircase from its foot (../shared/data/7scenes-stairs-seq04: a straight UK flight,
// Kinect v1, hand-held), its partial neighbour seq-01, and the building codes the detector accepts:
// the world's range by default, the paper's Spanish code as a profile (config/profiles/paper.yaml).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include "stairguide/capture/dataset.hpp"
#include "stairguide/capture/frame_source.hpp"
#include "stairguide/config/config_loader.hpp"
#include "stairguide/perception/perception.hpp"
#include "stairguide/stairs/stair_checks.hpp"
#include "stairguide/eval/stair_eval.hpp"
#include "stairguide/stairs/stairs.hpp"

namespace {

using namespace stairguide;
namespace fs = std::filesystem;

const std::string kData = STAIRGUIDE_SHARED_DATA;
const std::string kPaperProfile = std::string(STAIRGUIDE_SOURCE_DIR) + "/config/profiles/paper.yaml";

struct FrameOut {
  StairResult result;
  bool floor_found = false;
  std::optional<FrameTruth> truth;
};

/// Every frame of a dataset folder through perception and the stairs stage as `stairguide eval`
/// and `detect` run them: perception reset on the first frame, then tracking.
std::vector<FrameOut> run_folder(const std::string& dir, const PipelineConfig& cfg) {
  std::vector<FrameOut> out;
  auto src = open_frame_source(dir, cfg.capture);
  Perception perception(cfg);
  StairStage stage(cfg);
  RgbdFrame frame;
  SceneResult scene;
  for (;;) {
    const ReadResult rr = src->read(frame);
    if (rr.status == ReadStatus::kEnd) break;
    EXPECT_TRUE(rr.ok()) << rr.message;
    if (!rr.ok()) break;
    if (out.empty()) perception.reset();
    perception.process(frame, scene);
    FrameOut& f = out.emplace_back();
    stage.run(scene, frame.intrinsics, f.result);
    f.floor_found = scene.floor_found;
    f.truth = src->truth();
    const StairResult& r = f.result;
    std::printf("%s frame %zu: %s %s (%s) levels %d riser %.1f cm tread %.1f cm width %.2f m%s\n",
                dir.c_str(), out.size() - 1, r.detected ? "detected" : "refused", to_string(r.kind),
                to_string(r.verdict), r.levels, 100.f * r.riser_m, 100.f * r.tread_m, r.width_m,
                r.without_floor ? ", without floor" : "");
  }
  return out;
}

float median(std::vector<float> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.f : (v.size() % 2 ? v[v.size() / 2] : 0.5f * (v[v.size() / 2 - 1] + v[v.size() / 2]));
}

bool have(const std::string& dir) { return fs::exists(dir + "/depth.txt"); }

// The whole flight in view from its foot: every frame detected going up, riser and tread the same
// on every frame (within 1.5 cm of the frames' median). Before the world's codes were the
// defaults, two of three frames were refused as "tread shorter than the building code" (24.3 cm
// measured against the paper's 28 cm minimum).
TEST(StairsRealFlight, WholeFlightFromItsFootOnEveryFrame) {
  const std::string dir = kData + "/7scenes-stairs-seq04";
  if (!have(dir)) GTEST_SKIP() << "no shared data at " << dir;
  const auto frames = run_folder(dir, PipelineConfig{});
  ASSERT_EQ(frames.size(), 3u);
  std::vector<float> risers, treads;
  for (const auto& f : frames) {
    EXPECT_TRUE(f.result.detected) << to_string(f.result.verdict);
    EXPECT_EQ(f.result.kind, StairKind::kAscending);
    EXPECT_GE(f.result.levels, 5) << "a whole flight in view, not a piece of it";
    if (f.result.detected) {
      risers.push_back(f.result.riser_m);
      treads.push_back(f.result.tread_m);
    }
  }
  ASSERT_EQ(risers.size(), 3u);
  const float mr = median(risers), mt = median(treads);
  std::printf("median riser %.2f cm, tread %.2f cm\n", 100.f * mr, 100.f * mt);
  for (std::size_t i = 0; i < risers.size(); ++i) {
    EXPECT_NEAR(risers[i], mr, 0.015f) << "frame " << i;
    EXPECT_NEAR(treads[i], mt, 0.015f) << "frame " << i;
  }
  // What SOURCES.md says of this flight (measured on the frames, not published): risers about
  // 15 cm, treads about 24-26 cm.
  EXPECT_NEAR(mr, 0.15f, 0.01f);
  EXPECT_NEAR(mt, 0.25f, 0.015f);
}

// The paper's profile loads and holds the Spanish code; this flight's 24 cm treads are under it.
// Issue 39: the code describes the flight ("steep: treads under the code"), it does not silence it.
TEST(StairsRealFlight, PaperProfileDescribesTheShortTreads) {
  const PipelineConfig paper = load_config(kPaperProfile);
  EXPECT_FLOAT_EQ(paper.stair_modelling.tread_min, 0.28f);
  EXPECT_FLOAT_EQ(paper.stair_modelling.riser_min, 0.13f);
  EXPECT_FLOAT_EQ(paper.stair_modelling.riser_max, 0.185f);
  const std::string dir = kData + "/7scenes-stairs-seq04";
  if (!have(dir)) GTEST_SKIP() << "no shared data at " << dir;
  const auto frames = run_folder(dir, paper);
  ASSERT_EQ(frames.size(), 3u);
  int detected = 0, short_tread = 0;
  for (const auto& f : frames) {
    detected += f.result.detected;
    short_tread += f.result.detected && (f.result.code_notes & kCodeShortTreads) != 0;
  }
  // Frames 0 and 1 measure 24.3 cm treads, under the code's 28 cm with its slack; frame 2 (25.8
  // cm, farther) is within the slack.
  EXPECT_EQ(detected, 3);
  EXPECT_GE(short_tread, 2);
}

// seq-01: a landing and walls with steps only partly in view. Reported as it comes out (printed);
// what is asserted is what must hold of any answer: nothing going down, and a detection measures
// this stairwell's risers (about 15 cm).
TEST(StairsRealFlight, PartialStepsAreReportedHonestly) {
  const std::string dir = kData + "/7scenes-stairs-seq01";
  if (!have(dir)) GTEST_SKIP() << "no shared data at " << dir;
  const auto frames = run_folder(dir, PipelineConfig{});
  ASSERT_EQ(frames.size(), 3u);
  int detected = 0;
  for (const auto& f : frames) {
    if (!f.result.detected) continue;
    ++detected;
    EXPECT_EQ(f.result.direction(), 1) << "the steps of seq-01 go up from the landing";
    EXPECT_NEAR(f.result.riser_m, 0.15f, 0.02f);
  }
  std::printf("seq-01: %d of %zu frames detected\n", detected, frames.size());
}

// A folder of real frames labelled as a whole by a hand-written labels.yaml (dataset.hpp,
// read_folder_label_yaml): every frame carries the label, without a pose, and the evaluation
// scores each detection by its direction and the label's riser and tread.
TEST(StairsRealFlight, WholeFolderLabelScoresEveryFrame) {
  const std::string src = kData + "/7scenes-stairs-seq04";
  if (!have(src)) GTEST_SKIP() << "no shared data at " << src;
  const fs::path dir = fs::path(STAIRGUIDE_BINARY_DIR) / "test_stairs_real_flight_seq04";
  fs::remove_all(dir);
  fs::create_directories(dir);
  for (const char* name : {"camera.yaml", "depth.txt", "rgb.txt", "depth", "rgb", "groundtruth.txt"})
    if (fs::exists(fs::path(src) / name)) fs::create_symlink(fs::path(src) / name, dir / name);
  std::ofstream(dir / "labels.yaml")
      << "# Written by hand: every frame of 7-Scenes stairs seq-04 sees the whole flight\n"
         "# from its foot. Riser and tread as SOURCES.md measured them on these frames.\n"
         "format: stairguide-labels-1\n"
         "folder:\n"
         "  scene: \"7scenes-stairs-seq04\"\n"
         "  stairs:\n"
         "    - kind: ascending\n"
         "      riser_m: 0.15\n"
         "      tread_m: 0.25\n"
         "      visible_steps: [1, 2, 3, 4, 5]\n";
  PipelineConfig cfg;
  const auto frames = run_folder(dir.string(), cfg);
  ASSERT_EQ(frames.size(), 3u);
  EvalSummary sum;
  StairEvalOptions opt;
  for (const auto& f : frames) {
    ASSERT_TRUE(f.truth.has_value());
    EXPECT_FALSE(f.truth->pose_known);
    EXPECT_EQ(f.truth->scene, "7scenes-stairs-seq04");
    ASSERT_EQ(f.truth->stairs.size(), 1u);
    opt.ignore_pose = !f.truth->pose_known;
    sum.add(evaluate_stair_frame(f.result, *f.truth, opt));
  }
  EXPECT_EQ(sum.tp, 3);
  EXPECT_EQ(sum.fn, 0);
  EXPECT_EQ(sum.fp, 0);
  EXPECT_EQ(sum.riser.n, 3);
  EXPECT_EQ(sum.tread.n, 3);
  EXPECT_LE(sum.riser.max_abs, 0.01);
  EXPECT_LE(sum.tread.max_abs, 0.015);
  fs::remove_all(dir);
}

}  // namespace
