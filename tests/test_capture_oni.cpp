// .oni recordings: our writer -> OpenNI2's own player (OniSource) round trips, truncated and
// corrupt files, and the synthetic renderer -> .oni -> OniSource path.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>

#include "capture_test_util.hpp"
#include "stairguide/capture/oni.hpp"

namespace fs = std::filesystem;
using namespace stairguide;

namespace {

fs::path scratch(const std::string& name) { return test::scratch("capture_oni", name); }

std::vector<RgbdFrame> make_frames(int n, int w, int h, std::uint32_t seed) {
  return test::make_frames(n, w, h, seed, 9000, 100.0);
}

void write_oni(const fs::path& p, const std::vector<RgbdFrame>& frames, bool color = true) {
  OniWriter w(p.string(), frames[0].intrinsics, color);
  for (const auto& f : frames) w.write(f);
  w.close();
  EXPECT_EQ(w.frames_written(), static_cast<long>(frames.size()));
}

using test::error_of;

}  // namespace

TEST(Oni, RoundTripThroughOpenNI2Player) {
  const fs::path p = scratch("roundtrip.oni");
  const int n = 12, w = 160, h = 120;
  const auto frames = make_frames(n, w, h, 3);
  write_oni(p, frames);
  OniSource src(p.string());
  EXPECT_EQ(src.frame_count(), n);
  EXPECT_TRUE(src.has_color());
  // The field of view carries the focal length; the principal point is the image centre.
  EXPECT_NEAR(src.intrinsics().fx, frames[0].intrinsics.fx, 1e-3);
  EXPECT_NEAR(src.intrinsics().fy, frames[0].intrinsics.fy, 1e-3);
  EXPECT_FLOAT_EQ(src.intrinsics().cx, (w - 1) / 2.f);
  EXPECT_EQ(src.intrinsics().width, w);
  RgbdFrame f;
  for (int i = 0; i < n; ++i) {
    const ReadResult r = src.read(f);
    ASSERT_TRUE(r.ok()) << "frame " << i << ": " << r.message;
    const auto& in = frames[static_cast<std::size_t>(i)];
    EXPECT_EQ(f.index, static_cast<std::uint64_t>(i));
    EXPECT_NEAR(f.timestamp, in.timestamp, 1e-6);
    EXPECT_LT(cv::norm(f.depth, in.depth, cv::NORM_INF), 1e-6) << "frame " << i;
    EXPECT_EQ(cv::countNonZero(f.depth), cv::countNonZero(in.depth));
    ASSERT_EQ(f.color.size(), in.color.size());
    EXPECT_EQ(cv::norm(f.color, in.color, cv::NORM_INF), 0.0) << "frame " << i;
  }
  EXPECT_EQ(src.skipped_frames(), 0);
  // Clean end, and it stays ended.
  ReadResult end = src.read(f);
  EXPECT_EQ(end.status, ReadStatus::kEnd);
  EXPECT_TRUE(end.message.empty()) << end.message;
  EXPECT_EQ(src.read(f).status, ReadStatus::kEnd);
}

TEST(Oni, FullSizeDepthOnlyRecording) {
  const fs::path p = scratch("vga_depth_only.oni");
  const auto frames = make_frames(3, 640, 480, 9);
  write_oni(p, frames, /*color=*/false);
  OniSource src(p.string());
  EXPECT_EQ(src.frame_count(), 3);
  EXPECT_FALSE(src.has_color());
  EXPECT_NEAR(src.intrinsics().fx, 525.f, 1e-3);
  RgbdFrame f;
  for (int i = 0; i < 3; ++i) {
    ASSERT_TRUE(src.read(f).ok());
    EXPECT_LT(cv::norm(f.depth, frames[static_cast<std::size_t>(i)].depth, cv::NORM_INF), 1e-6);
    EXPECT_TRUE(f.color.empty());
  }
  EXPECT_EQ(src.read(f).status, ReadStatus::kEnd);
}

TEST(Oni, TruncatedRecordingIsAnErrorAfterTheFramesItHolds) {
  const fs::path full = scratch("full.oni"), cut = scratch("truncated.oni");
  const int n = 10, w = 80, h = 60;
  const auto frames = make_frames(n, w, h, 5);
  write_oni(full, frames);
  // Keep the headers and a bit more than 4 frames (depth + colour records of ~24 kB each).
  const auto size = fs::file_size(full);
  fs::copy_file(full, cut);
  fs::resize_file(cut, size * 45 / 100);
  OniOptions o;
  o.frame_timeout = 0.5;
  OniSource src(cut.string(), o);
  EXPECT_EQ(src.frame_count(), n);  // what the header announces
  RgbdFrame f;
  int got = 0;
  ReadResult r;
  while ((r = src.read(f)).ok()) {
    EXPECT_LT(cv::norm(f.depth, frames[static_cast<std::size_t>(got)].depth, cv::NORM_INF), 1e-6);
    ++got;
    ASSERT_LT(got, n);
  }
  // Not an end: every consumer (odometry, eval, the daemon's replay) must fail on it, not exit 0.
  EXPECT_EQ(r.status, ReadStatus::kError);
  EXPECT_GE(got, 3);
  EXPECT_LE(got, 5);
  EXPECT_NE(r.message.find("truncated.oni"), std::string::npos) << r.message;
  EXPECT_NE(r.message.find("ended early after " + std::to_string(got) + " of 10"), std::string::npos)
      << r.message;
  EXPECT_EQ(src.read(f).status, ReadStatus::kEnd);
}

TEST(Oni, MissingCorruptAndTruncatedHeaderNameTheFile) {
  std::string e = error_of([] { OniSource s("/nonexistent/stairguide/rec.oni"); });
  EXPECT_NE(e.find("/nonexistent/stairguide/rec.oni"), std::string::npos) << e;
  EXPECT_NE(e.find("missing"), std::string::npos) << e;

  const fs::path dir = scratch("dir.oni");
  fs::create_directories(dir);
  e = error_of([&] { OniSource s(dir.string()); });
  EXPECT_NE(e.find("dir.oni"), std::string::npos) << e;
  EXPECT_NE(e.find("not a regular file"), std::string::npos) << e;

  const fs::path junk = scratch("junk.oni");
  {
    std::ofstream o(junk, std::ios::binary);
    std::mt19937 rng(1);
    for (int i = 0; i < 4096; ++i) o.put(static_cast<char>(rng() & 0xff));
  }
  e = error_of([&] { OniSource s(junk.string()); });
  EXPECT_NE(e.find("junk.oni"), std::string::npos) << e;
  EXPECT_NE(e.find("cannot open"), std::string::npos) << e;

  // A real header cut inside the stream descriptions.
  const fs::path full = scratch("for_header.oni"), cut = scratch("header_cut.oni");
  write_oni(full, make_frames(2, 32, 24, 1));
  fs::copy_file(full, cut);
  fs::resize_file(cut, 100);
  e = error_of([&] { OniSource s(cut.string()); });
  EXPECT_NE(e.find("header_cut.oni"), std::string::npos) << e;

  const fs::path tiny = scratch("tiny.oni");
  std::ofstream(tiny) << "NI10";
  e = error_of([&] { OniSource s(tiny.string()); });
  EXPECT_NE(e.find("tiny.oni"), std::string::npos) << e;
}

TEST(Oni, WriterRejectsWrongFrames) {
  const fs::path p = scratch("wrong.oni");
  OniWriter w(p.string(), CameraIntrinsics{}.scaled(0.125f));
  RgbdFrame f;
  f.depth = cv::Mat(10, 10, CV_32FC1, cv::Scalar(1.0));
  const std::string e = error_of([&] { w.write(f); });
  EXPECT_NE(e.find("wrong.oni"), std::string::npos) << e;
  EXPECT_NE(e.find("expected 32-bit float 80x60"), std::string::npos) << e;
}

#include "stairguide/capture/synth_source.hpp"

TEST(Oni, SyntheticSceneThroughOniKeepsDepth) {
  const fs::path p = scratch("synth.oni");
  auto synth_src = synth::make_source("ascending_approach_climb", 4, 11);
  std::vector<RgbdFrame> frames;
  {
    OniWriter w(p.string(), synth_src->intrinsics());
    RgbdFrame f;
    while (synth_src->read(f).ok()) {
      w.write(f);
      frames.push_back(f.clone());
    }
    w.close();
  }
  ASSERT_EQ(frames.size(), 4u);
  OniSource src(p.string());
  EXPECT_EQ(src.frame_count(), 4);
  EXPECT_NEAR(src.intrinsics().fx, synth_src->intrinsics().fx, 1e-3);
  RgbdFrame f;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    ASSERT_TRUE(src.read(f).ok()) << i;
    const cv::Mat& d0 = frames[i].depth;
    ASSERT_EQ(f.depth.size(), d0.size());
    // Same depth up to the recording's 1 mm quantisation, same holes.
    double worst = 0.0;
    long valid0 = 0, valid1 = 0;
    for (int r = 0; r < d0.rows; ++r)
      for (int c = 0; c < d0.cols; ++c) {
        const float a = d0.at<float>(r, c), b = f.depth.at<float>(r, c);
        valid0 += a > 0.f;
        valid1 += b > 0.f;
        if (a > 0.f) worst = std::max(worst, static_cast<double>(std::abs(a - b)));
      }
    EXPECT_LE(worst, 0.0005 + 1e-6) << "frame " << i;
    EXPECT_EQ(valid0, valid1) << "frame " << i;
    EXPECT_GT(valid0, d0.total() / 2) << "frame " << i;
    EXPECT_EQ(cv::norm(f.color, frames[i].color, cv::NORM_INF), 0.0) << "frame " << i;
  }
  EXPECT_EQ(src.read(f).status, ReadStatus::kEnd);
}
