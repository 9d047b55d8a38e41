// The live OpenNI2 camera source. There is no camera on the build machines: opening one must
// fail with a clear message naming the device (skipped where a camera is attached).
#include <OpenNI.h>
#include <gtest/gtest.h>

#include <filesystem>

#include "capture_test_util.hpp"
#include "stairguide/capture/device.hpp"

using namespace stairguide;

namespace {

bool camera_attached() {
  if (openni::OpenNI::initialize() != openni::STATUS_OK) return false;
  openni::Array<openni::DeviceInfo> devices;
  openni::OpenNI::enumerateDevices(&devices);
  for (int i = 0; i < devices.getSize(); ++i) {
    std::error_code ec;
    if (!std::filesystem::exists(devices[i].getUri(), ec)) return true;  // a recording is not a camera
  }
  return false;
}

using test::error_of;

}  // namespace

TEST(Device, FirstCameraFailsClearlyWithoutCamera) {
  if (camera_attached()) GTEST_SKIP() << "a camera is attached; this test checks the no-camera message";
  CaptureConfig c;
  const std::string e = error_of([&] { DeviceSource s(c); });
  EXPECT_NE(e.find("OpenNI2 device"), std::string::npos) << e;
  EXPECT_NE(e.find("first camera"), std::string::npos) << e;
  EXPECT_NE(e.find("no camera found"), std::string::npos) << e;
}

TEST(Device, NamedUriFailsNamingTheUri) {
  if (camera_attached()) GTEST_SKIP() << "a camera is attached; this test checks the no-camera message";
  CaptureConfig c;
  c.device_uri = "1d27/0601@3/7";
  std::string e = error_of([&] { DeviceSource s(c); });
  EXPECT_NE(e.find("'1d27/0601@3/7'"), std::string::npos) << e;
  EXPECT_NE(e.find("cannot open"), std::string::npos) << e;
  // An explicit URI argument wins over the config's.
  e = error_of([&] { DeviceSource s(c, "2bc5/0401@1/2"); });
  EXPECT_NE(e.find("'2bc5/0401@1/2'"), std::string::npos) << e;
  EXPECT_EQ(e.find("1d27/0601"), std::string::npos) << e;
}
