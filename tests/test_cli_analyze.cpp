// `stairguide analyze` (issue 3, item 5) on every kind of input it names: a depth PNG with its
// camera.yaml, a dataset folder frame, an .oni frame, an organized PCD, a synthetic frame; --json,
// --png in the paper's Fig. 3 f colours, and bad input named in the message.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "cli_test_util.hpp"

namespace fs = std::filesystem;
using cli_test::CliRun;
using cli_test::run;

namespace {

std::string tmp(const std::string& name) { return cli_test::tmp("test_cli_analyze_", name); }

const std::string kKitchen = std::string(STAIRGUIDE_SHARED_DATA) + "/7scenes-redkitchen-0000-0299";

bool has(const std::string& out, const std::string& what) { return out.find(what) != std::string::npos; }

}  // namespace

TEST(CliAnalyze, SyntheticFrameAsTextAndJson) {
  // A cold view of an ascending staircase: floor, step candidates and vertical risers.
  const CliRun t = run("analyze synth:ascending_static:1:5");
  ASSERT_EQ(t.code, 0) << t.out;
  EXPECT_TRUE(has(t.out, "floor: camera height")) << t.out;
  EXPECT_TRUE(has(t.out, "manhattan: yaw")) << t.out;
  EXPECT_TRUE(has(t.out, "step_candidate")) << t.out;
  EXPECT_TRUE(has(t.out, "timings: segmentation")) << t.out;
  const CliRun j = run("analyze synth:ascending_static:1:5 --json");
  ASSERT_EQ(j.code, 0) << j.out;
  EXPECT_EQ(j.out.front(), '{') << j.out;
  for (const char* key :
       {"\"floor_found\": true", "\"camera_height_m\"", "\"manhattan_yaw_deg\"", "\"regions\": [{",
        "\"class\": \"floor\"", "\"class\": \"step_candidate\"", "\"height_m\"", "\"timings_ms\""})
    EXPECT_TRUE(has(j.out, key)) << key << " missing in " << j.out.substr(0, 400);
}

// No floor found (a cold view up a stairwell whose floor strip may be a tread): the Manhattan frame
// is still measured, about the refused plane's vertical, and both outputs say so.
TEST(CliAnalyze, ManhattanWithoutAFloorIsSaid) {
  const CliRun t = run("analyze synth:ascending_short_static:24:20261123 --frame 13");
  ASSERT_EQ(t.code, 0) << t.out;
  EXPECT_TRUE(has(t.out, "floor: not found")) << t.out;
  EXPECT_TRUE(has(t.out, "no floor: about the vertical of a floor-like plane refused as the floor")) << t.out;
  const CliRun j = run("analyze synth:ascending_short_static:24:20261123 --frame 13 --json");
  ASSERT_EQ(j.code, 0) << j.out;
  for (const char* key :
       {"\"floor_found\": false", "\"manhattan_found\": true", "\"manhattan_without_floor\": true"})
    EXPECT_TRUE(has(j.out, key)) << key << " missing in " << j.out.substr(0, 400);
}

TEST(CliAnalyze, PngDrawsTheClassificationInThePapersColours) {
  const std::string png = tmp("ascending.png");
  fs::remove(png);
  const CliRun r = run("analyze synth:ascending_static:1:5 --png " + png);
  ASSERT_EQ(r.code, 0) << r.out;
  const cv::Mat img = cv::imread(png, cv::IMREAD_COLOR);
  ASSERT_FALSE(img.empty()) << png << " not written";
  EXPECT_EQ(img.cols, 640);
  EXPECT_EQ(img.rows, 480);
  // Blended over the image: green floor, blue step candidates, yellow vertical planes (risers).
  long green = 0, blue = 0, yellow = 0;
  for (int v = 0; v < img.rows; ++v)
    for (int u = 0; u < img.cols; ++u) {
      const cv::Vec3b p = img.at<cv::Vec3b>(v, u);
      const int b = p[0], g = p[1], r_ = p[2];
      green += g > r_ + 40 && g > b + 40;
      blue += b > g + 40 && b > r_ + 40;
      yellow += r_ > b + 40 && g > b + 40;
    }
  const double n = static_cast<double>(img.total());
  std::printf("--png: green %.3f blue %.3f yellow %.3f of the pixels\n", green / n, blue / n, yellow / n);
  EXPECT_GT(green / n, 0.05) << "floor (green)";
  EXPECT_GT(blue / n, 0.05) << "step candidates (blue)";
  EXPECT_GT(yellow / n, 0.02) << "risers (yellow)";
  // An unwritable target is named.
  const CliRun bad = run("analyze synth:ascending_static:1:5 --png /nonexistent-dir/x.png");
  EXPECT_NE(bad.code, 0);
  EXPECT_TRUE(has(bad.out, "/nonexistent-dir/x.png")) << bad.out;
}

TEST(CliAnalyze, OniRecordingFrame) {
  const std::string dir = tmp("oni_set"), oni = tmp("rec.oni");
  fs::remove_all(dir);
  fs::remove(oni);
  // Consecutive frames of a walk: the frames before the one asked for go through perception
  // too, as in a live run (a recording of unrelated static views would jump the tracked floor).
  const CliRun s =
      run("synth --scene ascending_approach_climb --frames 3 --seed 5 --out " + dir + " --oni " + oni);
  ASSERT_EQ(s.code, 0) << s.out;
  const CliRun r = run("analyze " + oni + " --frame 2 --json");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_TRUE(has(r.out, "\"floor_found\": true")) << r.out.substr(0, 400);
  EXPECT_TRUE(has(r.out, "\"class\": \"floor\"")) << r.out.substr(0, 400);
  // The recording holds 3 frames: asking for a fourth is named, with the count.
  const CliRun past = run("analyze " + oni + " --frame 3");
  EXPECT_NE(past.code, 0);
  EXPECT_TRUE(has(past.out, "out of range")) << past.out;
  // So is the dataset folder written beside it.
  const CliRun d = run("analyze " + dir + " --frame 2");
  EXPECT_EQ(d.code, 0) << d.out;
  EXPECT_TRUE(has(d.out, "floor: camera height")) << d.out;
}

TEST(CliAnalyze, RealDepthPngDatasetFrameAndOrganizedPcd) {
  if (!fs::exists(kKitchen + "/camera.yaml"))
    GTEST_SKIP() << "no 7-Scenes kitchen under " << STAIRGUIDE_SHARED_DATA;
  // A depth PNG finds camera.yaml in its parent folder.
  const CliRun png = run("analyze " + kKitchen + "/depth/0.000000.png");
  ASSERT_EQ(png.code, 0) << png.out;
  EXPECT_TRUE(has(png.out, "floor: camera height")) << png.out;
  EXPECT_TRUE(has(png.out, "regions")) << png.out;
  // The dataset folder, frame 10 (the frames before it go through perception too).
  const CliRun set = run("analyze " + kKitchen + " --frame 10 --json");
  ASSERT_EQ(set.code, 0) << set.out;
  EXPECT_TRUE(has(set.out, "\"floor_found\": true")) << set.out.substr(0, 400);
  EXPECT_TRUE(has(set.out, "\"class\": \"floor\"")) << set.out.substr(0, 400);
  // An organized PCD from PCL's data: a level camera, so no chest-camera floor; the planes are
  // still segmented and the reason is given.
  const std::string pcd =
      std::string(STAIRGUIDE_SHARED_DATA) + "/pcl-kinect-clouds/tutorials_pairwise/capture0001.pcd";
  if (fs::exists(pcd)) {
    const CliRun c = run("analyze " + pcd + " --json");
    ASSERT_EQ(c.code, 0) << c.out;
    EXPECT_TRUE(has(c.out, "\"regions\": [{")) << c.out.substr(0, 400);
    EXPECT_TRUE(has(c.out, "\"why\": \"no floor")) << c.out.substr(0, 400);
  }
}

TEST(CliAnalyze, BadInputIsNamed) {
  const CliRun missing = run("analyze /nonexistent/stairguide/frame.png");
  EXPECT_NE(missing.code, 0);
  EXPECT_TRUE(has(missing.out, "/nonexistent/stairguide/frame.png")) << missing.out;
  // A PNG with no camera.yaml beside it or in its parent folder.
  const std::string lone = tmp("lone_dir");
  fs::create_directories(lone + "/sub");
  cv::imwrite(lone + "/sub/d.png", cv::Mat(48, 64, CV_16UC1, cv::Scalar(1000)));
  const CliRun nocam = run("analyze " + lone + "/sub/d.png");
  EXPECT_NE(nocam.code, 0);
  EXPECT_TRUE(has(nocam.out, "camera.yaml")) << nocam.out;
  const CliRun unknown = run("analyze " + lone);
  EXPECT_NE(unknown.code, 0);
  EXPECT_TRUE(has(unknown.out, lone)) << unknown.out;
}
