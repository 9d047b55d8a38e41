// Stair detection on the real frames of ../shared/data (labels.csv): what their labels allow.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "stairguide/capture/frame_source.hpp"
#include "stairguide/perception/perception.hpp"
#include "stairguide/stairs/stairs.hpp"

namespace {

using namespace stairguide;

// ---- real frames: ../shared/data/labels.csv ----

std::vector<std::vector<std::string>> read_labels(const std::string& path) {
  std::vector<std::vector<std::string>> rows;
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line)) {
    std::vector<std::string> f(1);
    bool q = false;
    for (char c : line) {
      if (c == '"') q = !q;
      else if (c == ',' && !q) f.emplace_back();
      else f.back() += c;
    }
    if (f.size() >= 2) rows.push_back(f);
  }
  return rows;
}

TEST(StairsReal, LabelledFrames) {
  const std::string dir = STAIRGUIDE_SHARED_DATA;
  const std::string labels = dir + "/labels.csv";
  if (!std::filesystem::exists(labels)) GTEST_SKIP() << "no shared data at " << dir;
  const PipelineConfig cfg;
  Perception perception(cfg);
  StairStage stage(cfg);
  int none_frames = 0, none_detected = 0, stair_frames = 0, stair_detected = 0, wrong_direction = 0;
  for (const auto& row : read_labels(labels)) {
    std::unique_ptr<FrameSource> src;
    try {
      src = open_frame_source(dir + "/" + row[0], cfg.capture);
    } catch (const SourceError& e) {
      ADD_FAILURE() << e.what();
      continue;
    }
    RgbdFrame frame;
    ASSERT_TRUE(src->read(frame).ok()) << row[0];
    perception.reset();
    const SceneResult scene = perception.process(frame);
    StairResult r;
    stage.run(scene, frame.intrinsics, r);
    std::printf("%-75s %-6s -> %s%s%s (%s)\n", row[0].c_str(), row[1].c_str(), r.detected ? to_string(r.kind) : "none",
                scene.floor_found ? "" : ", no floor", "", to_string(r.verdict));
    if (row[1] == "none") {
      ++none_frames;
      none_detected += r.detected;
    } else {
      ++stair_frames;
      stair_detected += r.detected;
      // Every stair frame of the set is ascending: a detection must not say descending.
      if (r.detected && (r.kind == StairKind::kDescending || r.kind == StairKind::kCurb)) ++wrong_direction;
    }
  }
  std::printf("real frames: 'none' %d of %d detected; 'stair' %d of %d detected\n", none_detected, none_frames,
              stair_detected, stair_frames);
  EXPECT_EQ(none_frames, 7);
  EXPECT_EQ(none_detected, 0) << "a staircase reported in a frame without one";
  EXPECT_EQ(wrong_direction, 0);
}

}  // namespace
