// The live `device:` source on the virtual OpenNI2 camera (src/vcam): OpenNI2 loads the build's
// driver, the source opens "sgvcam://0" through the real openni::Device API and reads the served
// dataset's frames, exact, at 30 Hz; an unplug fires OpenNI2's device-disconnected event, stops the
// frames, and the source reports it at once; after a replug a new source reads again.
#include <OpenNI.h>
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <fstream>
#include <set>
#include <thread>

#include "stairguide/capture/dataset.hpp"
#include "stairguide/capture/device.hpp"
#include "vcam_test_util.hpp"

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using namespace stairguide;

namespace {

__attribute__((constructor)) void reexec() { test::reexec_with_vcam_drivers(); }

constexpr long kFrames = 6;
const fs::path kDir = fs::path(STAIRGUIDE_BINARY_DIR) / "vcam_test_files";

double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

bool enumerated(const std::string& uri) {
  openni::Array<openni::DeviceInfo> found;
  openni::OpenNI::enumerateDevices(&found);
  for (int i = 0; i < found.getSize(); ++i)
    if (uri == found[i].getUri()) return true;
  return false;
}

struct Listener : openni::OpenNI::DeviceDisconnectedListener, openni::OpenNI::DeviceConnectedListener {
  std::atomic<int> disconnected{0}, connected{0};
  void onDeviceDisconnected(const openni::DeviceInfo* i) override {
    if (std::string(i->getUri()) == "sgvcam://0") ++disconnected;
  }
  void onDeviceConnected(const openni::DeviceInfo* i) override {
    if (std::string(i->getUri()) == "sgvcam://0") ++connected;
  }
};

class VirtualCamera : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dataset_ = kDir / "ascending_640";
    test::write_vcam_dataset(dataset_, "ascending_static", kFrames, 3);
    control_ = kDir / ("control." + std::to_string(getpid()));
    test::set_plugged(control_, true);
    // Read by the driver when OpenNI2 initializes, i.e. at the first source opened in this process.
    setenv("SGVCAM_DATASET", dataset_.c_str(), 1);
    setenv("SGVCAM_CONTROL", control_.c_str(), 1);
  }
  static void TearDownTestSuite() { fs::remove(control_); }
  void SetUp() override {
    ASSERT_EQ(test::loaded_openni2().rfind(test::vcam_dir() + "/", 0), 0u)
        << "OpenNI2 must come from " << test::vcam_dir() << " (LD_LIBRARY_PATH), got '"
        << test::loaded_openni2() << "'";
    test::set_plugged(control_, true);
  }
  static CaptureConfig config() {
    CaptureConfig c;
    c.read_timeout = 5.0;  // longer than any wait below: an unplug must not wait it out
    return c;
  }
  static fs::path dataset_, control_;
};
fs::path VirtualCamera::dataset_, VirtualCamera::control_;

}  // namespace

TEST_F(VirtualCamera, DeviceSourceReadsTheDatasetsFramesExactlyAt30Hz) {
  DeviceSource src(config(), "sgvcam://0");
  EXPECT_NE(src.describe().find("sgvcam://0"), std::string::npos) << src.describe();
  EXPECT_NE(src.describe().find("stairguide virtual camera"), std::string::npos) << src.describe();
  EXPECT_TRUE(src.registered());

  // The reference: the same folder through the dataset reader.
  DatasetSource ref(dataset_.string());
  std::vector<RgbdFrame> want;
  for (RgbdFrame f; ref.read(f).ok();) want.push_back(f.clone());
  ASSERT_EQ(want.size(), static_cast<std::size_t>(kFrames));
  // The intrinsics come from the fields of view the driver reports (from camera.yaml).
  EXPECT_NEAR(src.intrinsics().fx, ref.intrinsics().fx, 0.01f);
  EXPECT_NEAR(src.intrinsics().fy, ref.intrinsics().fy, 0.01f);
  EXPECT_EQ(src.intrinsics().width, 640);

  RgbdFrame f;
  ASSERT_TRUE(src.read(f).ok());
  const double ts0 = f.timestamp;
  const auto t0 = Clock::now();
  long read = 0, valid_pixels = 0;
  std::set<long> seen;
  for (; read < 45; ++read) {
    const ReadResult r = src.read(f);
    ASSERT_TRUE(r.ok()) << r.message;
    ASSERT_EQ(f.depth.cols, 640);
    ASSERT_EQ(f.depth.rows, 480);
    ASSERT_EQ(f.depth.type(), CV_32FC1);
    ASSERT_FALSE(f.color.empty()) << "colour arrives with depth (frame sync)";
    // The driver's frame n is the folder's frame n mod kFrames, at n / 30 s.
    const long tick = std::lround(f.timestamp * 30.0);
    EXPECT_NEAR(f.timestamp * 30.0, static_cast<double>(tick), 1e-3);
    const RgbdFrame& w = want[static_cast<std::size_t>(tick % kFrames)];
    seen.insert(tick % kFrames);
    EXPECT_EQ(cv::countNonZero(f.depth != w.depth), 0) << "depth of tick " << tick;
    cv::Mat diff;
    cv::absdiff(f.color, w.color, diff);
    EXPECT_EQ(cv::countNonZero(diff.reshape(1)), 0) << "colour of tick " << tick;
    valid_pixels += cv::countNonZero(f.depth > 0.f);
  }
  const double wall = since(t0), sensor = f.timestamp - ts0;
  EXPECT_EQ(seen.size(), static_cast<std::size_t>(kFrames)) << "the loop goes through every frame";
  EXPECT_GT(valid_pixels, 45L * 640 * 480 / 2) << "real depth images, mostly valid";
  // 30 Hz on the wall clock: the sensor clock keeps step with it, no frame comes twice or early
  // (45 reads span at least 45 ticks), and a reader that keeps up loses few (at most a fifth, for
  // a loaded machine; none on a quiet one).
  EXPECT_NEAR(wall, sensor, 0.25);
  EXPECT_GE(sensor, 45.0 / 30.0 - 1e-3) << "a frame came twice or faster than 30 Hz";
  EXPECT_LE(sensor, 45.0 / 30.0 / 0.8) << "more than a fifth of the frames were lost";
  EXPECT_EQ(src.frames_without_color(), 0);
}

TEST_F(VirtualCamera, UnplugFiresTheDisconnectEventStopsFramesAndReplugOpensAgain) {
  Listener events;
  auto src = std::make_unique<DeviceSource>(config(), "sgvcam://0");
  openni::OpenNI::addDeviceDisconnectedListener(&events);
  openni::OpenNI::addDeviceConnectedListener(&events);
  RgbdFrame f;
  ASSERT_TRUE(src->read(f).ok());
  ASSERT_TRUE(enumerated("sgvcam://0"));

  // Unplug: the event fires, the open source says so at once (not after read_timeout, 5 s), the
  // device leaves the enumeration and cannot be opened.
  test::set_plugged(control_, false);
  const auto t0 = Clock::now();
  ReadResult r;
  for (int i = 0; i < 100 && (r = src->read(f)).ok(); ++i) {
  }
  const double noticed = since(t0);
  EXPECT_EQ(r.status, ReadStatus::kError) << r.message;
  EXPECT_NE(r.message.find("unplugged"), std::string::npos) << r.message;
  EXPECT_NE(r.message.find("sgvcam://0"), std::string::npos) << r.message;
  EXPECT_LT(noticed, 1.0) << "the disconnect event, not the read timeout, tells of the unplug";
  EXPECT_EQ(events.disconnected.load(), 1);
  EXPECT_FALSE(enumerated("sgvcam://0"));
  EXPECT_EQ(src->read(f).status, ReadStatus::kError) << "an unplugged source stays dead";
  try {
    DeviceSource again(config(), "sgvcam://0");
    ADD_FAILURE() << "an unplugged camera opened";
  } catch (const SourceError& e) {
    EXPECT_NE(std::string(e.what()).find("cannot open"), std::string::npos) << e.what();
  }
  src.reset();

  // Replug: enumerable again (the driver polls its control file each frame period), a new source
  // reads the frames; the connect event fired once.
  test::set_plugged(control_, true);
  const auto t1 = Clock::now();
  while (!enumerated("sgvcam://0") && since(t1) < 3.0)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  EXPECT_LT(since(t1), 1.0);
  EXPECT_EQ(events.connected.load(), 1);
  DeviceSource back(config(), "sgvcam://0");
  for (int i = 0; i < 10; ++i) {
    const ReadResult rr = back.read(f);
    ASSERT_TRUE(rr.ok()) << rr.message;
    EXPECT_EQ(f.depth.cols, 640);
  }
  openni::OpenNI::removeDeviceDisconnectedListener(&events);
  openni::OpenNI::removeDeviceConnectedListener(&events);
}

TEST_F(VirtualCamera, BadControlFileContentIsIgnoredAndTheCameraKeepsServing) {
  DeviceSource src(config(), "sgvcam://0");
  testing::internal::CaptureStderr();
  {
    std::ofstream c(control_);
    c << "maybe\n";
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find("expected 'plugged' or 'unplugged', got 'maybe'; the camera stays plugged"),
            std::string::npos)
      << err;
  EXPECT_NE(err.find(control_.string()), std::string::npos) << "the message names the file: " << err;
  RgbdFrame f;
  for (int i = 0; i < 5; ++i) ASSERT_TRUE(src.read(f).ok());
  EXPECT_TRUE(enumerated("sgvcam://0"));
}
