// The battery read from a fake sysfs power-supply folder (the layout of /sys/class/power_supply).
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "stairguide/feedback/power_supply.hpp"

using namespace stairguide::feedback;
namespace fs = std::filesystem;

namespace {
const fs::path kDir = fs::path(STAIRGUIDE_BINARY_DIR) / ("feedback_power." + std::to_string(getpid()));
void supply(const std::string& name, const std::string& type, const std::string& capacity,
            const std::string& status, const std::string& online = "") {
  const fs::path d = kDir / name;
  fs::create_directories(d);
  std::ofstream(d / "type") << type << "\n";
  if (!capacity.empty()) std::ofstream(d / "capacity") << capacity << "\n";
  if (!status.empty()) std::ofstream(d / "status") << status << "\n";
  if (!online.empty()) std::ofstream(d / "online") << online << "\n";
}
}  // namespace

TEST(FeedbackPower, BatteryFromAFakeSysfsFolder) {
  fs::remove_all(kDir);
  EXPECT_FALSE(read_battery((kDir / "absent").string()).present);  // no folder: nothing to tell
  supply("AC", "Mains", "", "", "0");
  supply("hidpp_battery_0", "Battery", "", "Discharging");  // a mouse: no capacity, not a reading
  EXPECT_FALSE(read_battery(kDir.string()).present);
  supply("BAT0", "Battery", "12", "Discharging");
  BatteryStatus b = read_battery(kDir.string());
  ASSERT_TRUE(b.present);
  EXPECT_FLOAT_EQ(b.charge, 0.12f);
  EXPECT_FALSE(b.charging);
  EXPECT_EQ(b.name, "BAT0");
  supply("BAT1", "Battery", "4", "Discharging");  // two: the lowest is what runs out first
  b = read_battery(kDir.string());
  EXPECT_FLOAT_EQ(b.charge, 0.04f);
  EXPECT_EQ(b.name, "BAT1");
  supply("AC", "Mains", "", "", "1");  // on mains: charging
  EXPECT_TRUE(read_battery(kDir.string()).charging);
  supply("AC", "Mains", "", "", "0");
  supply("BAT1", "Battery", "garbage", "Discharging");  // unreadable: left out
  EXPECT_FLOAT_EQ(read_battery(kDir.string()).charge, 0.12f);
  supply("BAT0", "Battery", "12", "Charging");
  EXPECT_TRUE(read_battery(kDir.string()).charging);
  fs::remove_all(kDir);
}
