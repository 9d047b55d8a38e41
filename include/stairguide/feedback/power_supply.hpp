#pragma once
/// \file power_supply.hpp
/// The laptop's battery, read from the kernel's power-supply class in sysfs
/// (/sys/class/power_supply/NAME/{type,capacity,status}); tests point it at a fake folder of the
/// same layout.

#include <string>

namespace stairguide::feedback {

struct BatteryStatus {
  bool present = false;   ///< a supply of type "Battery" with a readable capacity was found
  float charge = 1.0f;    ///< fraction of full (capacity / 100); the lowest of several batteries
  bool charging = false;  ///< on mains: status "Charging" or "Full" or "Not charging", or an online AC supply
  std::string name;       ///< the battery read ("BAT0")
};

/// Reads every entry of `dir` whose `type` is "Battery" (the lowest charge wins); mains ("Mains"
/// type with `online` 1) counts as charging. A folder that is missing or holds no battery gives
/// `present` false (a desktop, a machine on mains only): nothing to tell.
BatteryStatus read_battery(const std::string& dir);

}  // namespace stairguide::feedback
