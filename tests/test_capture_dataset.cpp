// Dataset folders (TUM layout), labels.yaml, single-frame readers (PCD, depth PNG), and the real
// 7-Scenes / PCL / FHG frames when ../shared/data is present.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "stairguide/capture/dataset.hpp"
#include "stairguide/capture/frame_source.hpp"
#include "capture_test_util.hpp"

namespace fs = std::filesystem;
using namespace stairguide;

namespace {

fs::path scratch(const std::string& name) { return test::scratch("capture_dataset", name); }

Pose make_pose(float yaw, float pitch, float x, float y, float z) {
  Pose p = Pose::Identity();
  p.linear() =
      (Eigen::AngleAxisf(yaw, Eigen::Vector3f::UnitZ()) * Eigen::AngleAxisf(pitch, Eigen::Vector3f::UnitX()))
          .toRotationMatrix();
  p.translation() = Eigen::Vector3f(x, y, z);
  return p;
}

std::vector<RgbdFrame> make_frames(int n, int w, int h, std::uint32_t seed) {
  return test::make_frames(n, w, h, seed, 6000, 12.5);
}

FrameTruth make_truth(int i) {
  FrameTruth t;
  t.index = static_cast<std::uint64_t>(i);
  t.timestamp = 12.5 + i / 30.0;
  t.scene = "ascending_static";
  t.T_world_camera = make_pose(0.1f * i, -0.7f, 0.3f * i, -0.2f, 1.37f);
  t.camera_height_m = 1.37f + 0.001f * i;
  t.camera_tilt_rad = 0.71f;
  t.camera_roll_rad = -0.0123f;
  t.floor_visible = i % 2 == 0;
  if (i != 1) {  // frame 1 has no staircase: an empty list must survive too
    StairTruth s;
    s.id = 0;
    s.kind = i == 2 ? StairKind::kDescending : StairKind::kAscending;
    s.steps = 8 + i;
    s.riser_m = 0.1734f;
    s.tread_m = 0.2987f;
    s.width_m = 1.2345f;
    s.open_risers = i == 3;
    s.T_camera_stair = make_pose(0.3f, 0.2f + i, 0.1f, 0.9f, 2.4f);
    s.visible_steps = {1, 2, 3};
    s.visible_pixels = {1200, 800, 201 + i};
    s.first_edge_visible = true;
    s.both_ends_visible = i == 0;
    s.user_step = i;
    t.stairs.push_back(s);
    StairTruth curb;
    curb.id = 1;
    curb.kind = StairKind::kCurb;
    curb.steps = 1;
    t.stairs.push_back(curb);
  }
  return t;
}

void expect_same_truth(const FrameTruth& a, const FrameTruth& b) {
  EXPECT_EQ(a.index, b.index);
  EXPECT_EQ(a.timestamp, b.timestamp);
  EXPECT_EQ(a.scene, b.scene);
  EXPECT_TRUE(a.T_world_camera.matrix() == b.T_world_camera.matrix());
  EXPECT_EQ(a.camera_height_m, b.camera_height_m);
  EXPECT_EQ(a.camera_tilt_rad, b.camera_tilt_rad);
  EXPECT_EQ(a.camera_roll_rad, b.camera_roll_rad);
  EXPECT_EQ(a.floor_visible, b.floor_visible);
  ASSERT_EQ(a.stairs.size(), b.stairs.size());
  for (std::size_t i = 0; i < a.stairs.size(); ++i) {
    const StairTruth &s = a.stairs[i], &t = b.stairs[i];
    EXPECT_EQ(s.id, t.id);
    EXPECT_EQ(s.kind, t.kind);
    EXPECT_EQ(s.steps, t.steps);
    EXPECT_EQ(s.riser_m, t.riser_m);
    EXPECT_EQ(s.tread_m, t.tread_m);
    EXPECT_EQ(s.width_m, t.width_m);
    EXPECT_EQ(s.open_risers, t.open_risers);
    EXPECT_TRUE(s.T_camera_stair.matrix() == t.T_camera_stair.matrix());
    EXPECT_EQ(s.visible_steps, t.visible_steps);
    EXPECT_EQ(s.visible_pixels, t.visible_pixels);
    EXPECT_EQ(s.first_edge_visible, t.first_edge_visible);
    EXPECT_EQ(s.both_ends_visible, t.both_ends_visible);
    EXPECT_EQ(s.user_step, t.user_step);
  }
}

double max_abs_diff(const cv::Mat& a, const cv::Mat& b) { return cv::norm(a, b, cv::NORM_INF); }

// Writes a minimal valid dataset (2 frames) for the error tests to break.
fs::path small_dataset(const std::string& name) {
  const fs::path d = scratch(name);
  const auto frames = make_frames(2, 32, 24, 5);
  DatasetWriter w(d.string(), frames[0].intrinsics);
  for (const auto& f : frames) w.write(f);
  w.close();
  return d;
}

void write_text(const fs::path& p, const std::string& s) {
  std::ofstream o(p);
  o << s;
}

using test::error_of;

bool shared_data(fs::path& root) {
  root = STAIRGUIDE_SHARED_DATA;
  return fs::is_directory(root);
}

}  // namespace

TEST(Dataset, RoundTripFramesPosesAndLabels) {
  const fs::path d = scratch("roundtrip");
  const int n = 4, w = 64, h = 48;
  const auto frames = make_frames(n, w, h, 42);
  std::vector<FrameTruth> truths;
  {
    DatasetWriter writer(d.string(), frames[0].intrinsics);
    for (int i = 0; i < n; ++i) {
      truths.push_back(make_truth(i));
      writer.write(frames[static_cast<std::size_t>(i)], &truths.back());
    }
    writer.close();
    EXPECT_EQ(writer.frames_written(), n);
  }
  DatasetSource src(d.string());
  EXPECT_EQ(src.frame_count(), n);
  EXPECT_TRUE(src.has_labels());
  EXPECT_EQ(src.intrinsics().fx, frames[0].intrinsics.fx);
  EXPECT_EQ(src.intrinsics().cy, frames[0].intrinsics.cy);
  EXPECT_EQ(src.intrinsics().width, w);
  RgbdFrame f;
  for (int i = 0; i < n; ++i) {
    ASSERT_TRUE(src.read(f).ok()) << i;
    const auto& in = frames[static_cast<std::size_t>(i)];
    EXPECT_EQ(f.index, static_cast<std::uint64_t>(i));
    EXPECT_NEAR(f.timestamp, in.timestamp, 1e-6);
    ASSERT_EQ(f.depth.type(), CV_32FC1);
    // Depth on the 1 mm grid comes back within float rounding of mm / 1000.
    EXPECT_LT(max_abs_diff(f.depth, in.depth), 1e-6) << "frame " << i;
    EXPECT_EQ(cv::countNonZero(f.depth), cv::countNonZero(in.depth));
    EXPECT_EQ(max_abs_diff(f.color, in.color), 0.0) << "frame " << i;
    EXPECT_EQ(f.gray.type(), CV_8UC1);
    const auto pose = src.pose();
    ASSERT_TRUE(pose.has_value());
    EXPECT_LT(
        (pose->matrix() - truths[static_cast<std::size_t>(i)].T_world_camera.matrix()).cwiseAbs().maxCoeff(),
        2e-6f);
    const auto t = src.truth();
    ASSERT_TRUE(t.has_value());
    expect_same_truth(*t, truths[static_cast<std::size_t>(i)]);
  }
  EXPECT_EQ(src.read(f).status, ReadStatus::kEnd);
  EXPECT_EQ(src.read(f).status, ReadStatus::kEnd);
}

TEST(Dataset, LabelsYamlRoundTripIsBitExact) {
  std::vector<FrameTruth> truths;
  for (int i = 0; i < 5; ++i) truths.push_back(make_truth(i));
  truths[3].scene = "name with \"quotes\" and \\";
  const fs::path d = scratch("labels");
  fs::create_directories(d);
  write_text(d / "labels.yaml", labels_to_yaml(truths));
  const auto back = read_labels_yaml((d / "labels.yaml").string());
  ASSERT_EQ(back.size(), truths.size());
  for (std::size_t i = 0; i < back.size(); ++i) expect_same_truth(back[i], truths[i]);
  write_text(d / "empty.yaml", labels_to_yaml({}));
  EXPECT_TRUE(read_labels_yaml((d / "empty.yaml").string()).empty());
}

TEST(Dataset, BadLabelsNameFileLineAndKey) {
  const fs::path d = scratch("badlabels");
  fs::create_directories(d);
  std::string y = labels_to_yaml({make_truth(0)});
  write_text(d / "a.yaml", y + "    extra_key: 1\n");
  std::string e = error_of([&] { read_labels_yaml((d / "a.yaml").string()); });
  EXPECT_NE(e.find("a.yaml:"), std::string::npos) << e;
  EXPECT_NE(e.find("unknown key 'extra_key'"), std::string::npos) << e;
  std::string no_kind = y;
  no_kind.replace(no_kind.find("kind: ascending"), 15, "kind: spiral");
  write_text(d / "b.yaml", no_kind);
  e = error_of([&] { read_labels_yaml((d / "b.yaml").string()); });
  EXPECT_NE(e.find("b.yaml:16:"), std::string::npos) << e;
  EXPECT_NE(e.find("spiral"), std::string::npos) << e;
  std::string missing = y;
  missing.erase(missing.find("    camera_roll_rad"),
                missing.find("    floor_visible") - missing.find("    camera_roll_rad"));
  write_text(d / "c.yaml", missing);
  e = error_of([&] { read_labels_yaml((d / "c.yaml").string()); });
  EXPECT_NE(e.find("missing key 'camera_roll_rad'"), std::string::npos) << e;
}

TEST(Dataset, MissingFolderAndFilesNameTheFile) {
  std::string e = error_of([] { DatasetSource s("/nonexistent/stairguide/dataset"); });
  EXPECT_NE(e.find("/nonexistent/stairguide/dataset"), std::string::npos) << e;
  EXPECT_NE(e.find("missing"), std::string::npos) << e;

  fs::path d = small_dataset("nocamera");
  fs::remove(d / "camera.yaml");
  e = error_of([&] { DatasetSource s(d.string()); });
  EXPECT_NE(e.find((d / "camera.yaml").string()), std::string::npos) << e;

  d = small_dataset("nolist");
  fs::remove(d / "depth.txt");
  e = error_of([&] { DatasetSource s(d.string()); });
  EXPECT_NE(e.find((d / "depth.txt").string()), std::string::npos) << e;

  d = small_dataset("badcamera");
  write_text(d / "camera.yaml",
             "fx: 525\nfy: 525\ncx: 319.5\ncy: 239.5\nwidth: 32\nheight: abc\ndepth_scale: 1000\n");
  e = error_of([&] { DatasetSource s(d.string()); });
  EXPECT_NE(e.find("camera.yaml:6: key 'height'"), std::string::npos) << e;
  write_text(d / "camera.yaml", "fx: 525\nfy: 525\ncx: 319.5\ncy: 239.5\nwidth: 32\nheight: 24\n");
  e = error_of([&] { DatasetSource s(d.string()); });
  EXPECT_NE(e.find("missing key 'depth_scale'"), std::string::npos) << e;
}

TEST(Dataset, BadListLineNamesFileAndLine) {
  const fs::path d = small_dataset("badline");
  write_text(d / "rgb.txt", "# colour\n0.0 rgb/000000.png\nnot-a-time rgb/000001.png\n");
  const std::string e = error_of([&] { DatasetSource s(d.string()); });
  EXPECT_NE(e.find((d / "rgb.txt").string() + ":3:"), std::string::npos) << e;
}

TEST(Dataset, MissingCorruptAndWrongImagesAreReadErrorsNamingTheFile) {
  const fs::path d = small_dataset("badimages");
  DatasetSource s(d.string());
  RgbdFrame f;
  // Frame 0: missing depth PNG.
  fs::remove(d / "depth" / "000000.png");
  ReadResult r = s.read(f);
  EXPECT_EQ(r.status, ReadStatus::kError);
  EXPECT_NE(r.message.find("depth/000000.png"), std::string::npos) << r.message;
  EXPECT_NE(r.message.find("missing"), std::string::npos) << r.message;
  // Frame 1: corrupt (truncated) depth PNG.
  {
    std::ifstream in(d / "depth" / "000001.png", std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), {});
    write_text(d / "depth" / "000001.png", bytes.substr(0, bytes.size() / 3));
  }
  r = s.read(f);
  EXPECT_EQ(r.status, ReadStatus::kError);
  EXPECT_NE(r.message.find("depth/000001.png"), std::string::npos) << r.message;
  EXPECT_EQ(s.read(f).status, ReadStatus::kEnd);

  // Wrong size and wrong type.
  const fs::path d2 = small_dataset("wrongimages");
  cv::imwrite((d2 / "depth" / "000000.png").string(), cv::Mat(10, 10, CV_16UC1, cv::Scalar(1000)));
  cv::imwrite((d2 / "depth" / "000001.png").string(), cv::Mat(24, 32, CV_8UC1, cv::Scalar(100)));
  DatasetSource s2(d2.string());
  r = s2.read(f);
  EXPECT_EQ(r.status, ReadStatus::kError);
  EXPECT_NE(r.message.find("10x10"), std::string::npos) << r.message;
  r = s2.read(f);
  EXPECT_EQ(r.status, ReadStatus::kError);
  EXPECT_NE(r.message.find("16-bit"), std::string::npos) << r.message;
  // Missing colour image.
  const fs::path d3 = small_dataset("nocolour");
  fs::remove(d3 / "rgb" / "000000.png");
  DatasetSource s3(d3.string());
  r = s3.read(f);
  EXPECT_EQ(r.status, ReadStatus::kError);
  EXPECT_NE(r.message.find("rgb/000000.png"), std::string::npos) << r.message;
  EXPECT_TRUE(s3.read(f).ok());
}

TEST(Dataset, PairsByNearestTimestampAndSkipsUnpaired) {
  const fs::path d = small_dataset("pairing");
  // Depth at 12.5 s and 12.5333 s; colour 5 ms after the first and 47 ms after the second (the
  // first colour is 28 ms from the second depth): only the first pairs.
  write_text(d / "depth.txt", "12.500000 depth/000000.png\n12.533333 depth/000001.png\n");
  write_text(d / "rgb.txt", "12.580000 rgb/000001.png\n12.505000 rgb/000000.png\n");
  DatasetSource s(d.string());
  EXPECT_EQ(s.frame_count(), 1);
  EXPECT_EQ(s.skipped_frames(), 1);
  RgbdFrame f;
  ASSERT_TRUE(s.read(f).ok());
  EXPECT_NEAR(f.timestamp, 12.5, 1e-9);
  cv::Mat c0 = cv::imread((d / "rgb" / "000000.png").string());
  EXPECT_EQ(max_abs_diff(f.color, c0), 0.0);
}

TEST(Dataset, DepthPngWithCameraYamlInParent) {
  const fs::path d = small_dataset("singlepng");
  const RgbdFrame f = read_depth_png_frame((d / "depth" / "000001.png").string());
  const auto frames = make_frames(2, 32, 24, 5);
  EXPECT_LT(max_abs_diff(f.depth, frames[1].depth), 1e-6);
  EXPECT_EQ(f.intrinsics.width, 32);
  const std::string e = error_of([] { read_depth_png_frame("/tmp/stairguide-no-such-depth.png"); });
  EXPECT_NE(e.find("/tmp/stairguide-no-such-depth.png"), std::string::npos) << e;
}

TEST(Dataset, CorruptAndUnorganizedPcdNameTheFile) {
  const fs::path d = scratch("pcd");
  fs::create_directories(d);
  write_text(d / "garbage.pcd", "this is not a point cloud\n");
  std::string e = error_of([&] { read_pcd_frame((d / "garbage.pcd").string()); });
  EXPECT_NE(e.find("garbage.pcd"), std::string::npos) << e;
  write_text(d / "flat.pcd",
             "VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2\nHEIGHT 1\n"
             "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA ascii\n0 0 1\n0.1 0 1\n");
  e = error_of([&] { read_pcd_frame((d / "flat.pcd").string()); });
  EXPECT_NE(e.find("not an organized point cloud"), std::string::npos) << e;
}

TEST(Dataset, WriterRefusesToOverwrite) {
  const fs::path d = small_dataset("overwrite");
  const std::string e = error_of([&] { DatasetWriter w(d.string(), CameraIntrinsics{}); });
  EXPECT_NE(e.find("refusing"), std::string::npos) << e;
}

TEST(OpenFrameSource, DepthOutsideTheConfiguredRangeIsNoReading) {
  const fs::path d = small_dataset("range");
  const std::string png = (d / "depth" / "000000.png").string();
  const RgbdFrame raw = read_depth_png_frame(png);
  double lo = 0, hi = 0;
  cv::minMaxLoc(raw.depth, &lo, &hi, nullptr, nullptr, raw.depth > 0);
  ASSERT_GT(hi - lo, 0.1) << "the test frame needs a spread of depths";
  CaptureConfig c;
  c.min_range = static_cast<float>(lo + 0.25 * (hi - lo));
  c.max_range = static_cast<float>(hi - 0.25 * (hi - lo));
  auto src = open_frame_source(png, c);
  RgbdFrame f;
  ASSERT_TRUE(src->read(f).ok());
  int dropped = 0, kept = 0;
  for (int v = 0; v < raw.depth.rows; ++v)
    for (int u = 0; u < raw.depth.cols; ++u) {
      const float z = raw.depth.at<float>(v, u), g = f.depth.at<float>(v, u);
      if (z >= c.min_range && z <= c.max_range) {
        EXPECT_EQ(g, z);
        ++kept;
      } else {
        EXPECT_EQ(g, 0.f) << "depth " << z << " outside " << c.min_range << ".." << c.max_range;
        dropped += z > 0.f;
      }
    }
  EXPECT_GT(kept, 0);
  EXPECT_GT(dropped, 0);
  // The same through a dataset folder.
  auto ds = open_frame_source(d.string(), c);
  ASSERT_TRUE(ds->read(f).ok());
  double flo = 0, fhi = 0;
  cv::minMaxLoc(f.depth, &flo, &fhi, nullptr, nullptr, f.depth > 0);
  EXPECT_GE(flo, c.min_range);
  EXPECT_LE(fhi, c.max_range);
}

TEST(OpenFrameSource, PicksTheSourceByInputName) {
  const fs::path d = small_dataset("factory");
  CaptureConfig c;
  auto ds = open_frame_source(d.string(), c);
  EXPECT_EQ(ds->frame_count(), 2);
  EXPECT_NE(ds->describe().find("dataset"), std::string::npos);
  auto png = open_frame_source((d / "depth" / "000000.png").string(), c);
  EXPECT_EQ(png->frame_count(), 1);
  RgbdFrame f;
  EXPECT_TRUE(png->read(f).ok());
  EXPECT_EQ(png->read(f).status, ReadStatus::kEnd);
  auto syn = open_frame_source("synth:ascending_static:2:5", c);
  EXPECT_EQ(syn->frame_count(), 2);
  ASSERT_TRUE(syn->read(f).ok());
  EXPECT_TRUE(syn->truth().has_value());
  std::string e = error_of([&] { open_frame_source("/nonexistent/stairguide/x.bag", c); });
  EXPECT_NE(e.find("/nonexistent/stairguide/x.bag"), std::string::npos) << e;
  e = error_of([&] { open_frame_source("/nonexistent/stairguide/rec.oni", c); });
  EXPECT_NE(e.find("rec.oni"), std::string::npos) << e;
  e = error_of([&] { open_frame_source("synth:no_such_scene", c); });
  EXPECT_NE(e.find("no_such_scene"), std::string::npos) << e;
  e = error_of([&] { open_frame_source("synth:ascending_static:many", c); });
  EXPECT_NE(e.find("FRAMES"), std::string::npos) << e;
  // NOISE: white (the default) or kinect, correlated in space as the real sensor's.
  RgbdFrame w, k;
  ASSERT_TRUE(open_frame_source("synth:ascending_static:1:5:white", c)->read(w).ok());
  ASSERT_TRUE(open_frame_source("synth:ascending_static:1:5", c)->read(f).ok());
  ASSERT_TRUE(open_frame_source("synth:ascending_static:1:5:kinect", c)->read(k).ok());
  EXPECT_EQ(cv::norm(w.depth, f.depth, cv::NORM_INF), 0.0) << "white is the default";
  EXPECT_GT(cv::norm(w.depth, k.depth, cv::NORM_INF), 0.0) << "kinect noise differs";
  e = error_of([&] { open_frame_source("synth:ascending_static:1:5:pink", c); });
  EXPECT_NE(e.find("NOISE"), std::string::npos) << e;
  EXPECT_NE(e.find("pink"), std::string::npos) << e;
}

TEST(RealData, SevenScenesRedkitchen) {
  fs::path root;
  if (!shared_data(root)) GTEST_SKIP() << "no shared data at " << STAIRGUIDE_SHARED_DATA;
  const fs::path d = root / "7scenes-redkitchen-0000-0299";
  DatasetSource s(d.string());
  EXPECT_EQ(s.frame_count(), 300);
  EXPECT_EQ(s.skipped_frames(), 0);
  const CameraIntrinsics k = s.intrinsics();
  EXPECT_EQ(k.fx, 585.f);
  EXPECT_EQ(k.fy, 585.f);
  EXPECT_EQ(k.cx, 320.f);
  EXPECT_EQ(k.cy, 240.f);
  EXPECT_EQ(s.groundtruth().size(), 300u);
  RgbdFrame f;
  long n = 0;
  double min_median = 1e9, max_median = 0, min_valid = 1;
  while (true) {
    const ReadResult r = s.read(f);
    if (r.status == ReadStatus::kEnd) break;
    ASSERT_TRUE(r.ok()) << r.message;
    ASSERT_EQ(f.color.size(), f.depth.size());
    ASSERT_TRUE(s.pose().has_value()) << "frame " << n;
    if (n % 30 == 0) {  // depth statistics on every 30th frame (decoding all is the slow part)
      std::vector<float> v;
      for (int r2 = 0; r2 < f.depth.rows; ++r2)
        for (int c = 0; c < f.depth.cols; ++c)
          if (f.depth.at<float>(r2, c) > 0.f) v.push_back(f.depth.at<float>(r2, c));
      std::nth_element(v.begin(), v.begin() + static_cast<long>(v.size() / 2), v.end());
      const double med = v[v.size() / 2];
      min_median = std::min(min_median, med);
      max_median = std::max(max_median, med);
      min_valid = std::min(min_valid, static_cast<double>(v.size()) / static_cast<double>(f.depth.total()));
      double mx = 0;
      cv::minMaxLoc(f.depth, nullptr, &mx);
      EXPECT_LT(mx, 8.0);
    }
    ++n;
  }
  EXPECT_EQ(n, 300);
  // A kitchen seen from a hand-held Kinect: medians between 0.5 and 3.5 m, most pixels valid.
  EXPECT_GT(min_median, 0.5);
  EXPECT_LT(max_median, 3.5);
  EXPECT_GT(min_valid, 0.5);
  RecordProperty("depth_median_range_m", std::to_string(min_median) + ".." + std::to_string(max_median));
}

TEST(RealData, KinectPcdFramesAndEstimatedIntrinsics) {
  fs::path root;
  if (!shared_data(root)) GTEST_SKIP() << "no shared data at " << STAIRGUIDE_SHARED_DATA;
  const std::vector<std::string> kinect = {
      "pcl-kinect-clouds/tutorials_pairwise/capture0001.pcd", "pcl-kinect-clouds/test/five_people.pcd",
      "pcl-kinect-clouds/test/office1.pcd",
      "pcl-kinect-clouds/grabber_sequences/pcd/frame_20121214T142255.814212.pcd"};
  for (const auto& rel : kinect) {
    const RgbdFrame f = read_pcd_frame((root / rel).string());
    EXPECT_EQ(f.depth.cols, 640) << rel;
    EXPECT_EQ(f.depth.rows, 480) << rel;
    // Kinect/OpenNI: f = 525, principal point near the centre.
    EXPECT_NEAR(f.intrinsics.fx, 525.f, 5.f) << rel;
    EXPECT_NEAR(f.intrinsics.fy, 525.f, 5.f) << rel;
    EXPECT_NEAR(f.intrinsics.cx, 320.f, 3.f) << rel;
    EXPECT_NEAR(f.intrinsics.cy, 240.f, 3.f) << rel;
    const double valid = cv::countNonZero(f.depth) / static_cast<double>(f.depth.total());
    EXPECT_GT(valid, 0.3) << rel;
    double mx = 0;
    cv::minMaxLoc(f.depth, nullptr, &mx);
    EXPECT_LT(mx, 12.0) << rel;
  }
  // The FHG close-up: 320x240 ASCII with packed rgb, f about 262 px, nosings at 0.59-0.80 m.
  const RgbdFrame c = read_pcd_frame((root / "stair-perception-fhg/1347691665.301914845.pcd").string());
  EXPECT_EQ(c.depth.cols, 320);
  EXPECT_EQ(c.depth.rows, 240);
  EXPECT_NEAR(c.intrinsics.fx, 262.f, 8.f);
  EXPECT_NEAR(c.intrinsics.fy, 262.f, 8.f);
  ASSERT_FALSE(c.color.empty());
  EXPECT_GT(cv::norm(c.color, cv::NORM_L1), 0.0);
  std::vector<float> v;
  for (int r = 0; r < c.depth.rows; ++r)
    for (int col = 0; col < c.depth.cols; ++col)
      if (c.depth.at<float>(r, col) > 0.f) v.push_back(c.depth.at<float>(r, col));
  ASSERT_GT(v.size(), 1000u);
  std::nth_element(v.begin(), v.begin() + static_cast<long>(v.size() / 2), v.end());
  EXPECT_GT(v[v.size() / 2], 0.45f);
  EXPECT_LT(v[v.size() / 2], 1.0f);

  const std::string e = error_of([&] { read_pcd_frame((root / "no-such.pcd").string()); });
  EXPECT_NE(e.find("no-such.pcd"), std::string::npos) << e;
}

// Issue 41: with a clock that jumps back 5 s, frame 300's time was frame 150's and nearest-time
// pairing gave it frame 150's colour; with equal times every depth image took the first colour
// image. Lists whose times do not grow are paired in file order.
TEST(Dataset, ListsWhoseClockJumpsBackOrStandsStillArePairedInFileOrder) {
  const auto frames = make_frames(8, 16, 12, 9);
  for (const char* kind : {"back", "equal"}) {
    const fs::path d = scratch(std::string("clock_") + kind);
    {
      DatasetWriter w(d.string(), frames[0].intrinsics);
      for (std::size_t i = 0; i < frames.size(); ++i) {
        RgbdFrame f = frames[i];
        f.timestamp =
            std::string(kind) == "equal" ? 3.0 : 1.0 + 0.1 * static_cast<double>(i) - (i >= 4 ? 0.4 : 0.0);
        w.write(f);
      }
      w.close();
    }
    DatasetSource s(d.string());
    RgbdFrame f;
    for (std::size_t i = 0; i < frames.size(); ++i) {
      ASSERT_TRUE(s.read(f).ok()) << kind << " " << i;
      ASSERT_FALSE(f.color.empty()) << kind << " " << i;
      EXPECT_EQ(cv::norm(f.color, frames[i].color, cv::NORM_INF), 0.0)
          << kind << ": frame " << i << " got another frame's colour";
    }
  }
}
