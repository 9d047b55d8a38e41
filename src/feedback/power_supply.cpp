#include "stairguide/feedback/power_supply.hpp"

#include <cstdlib>
#include <filesystem>
#include <fstream>

namespace stairguide::feedback {

namespace {
// The first line of a sysfs attribute, without its newline; "" when it cannot be read.
std::string attr(const std::filesystem::path& p) {
  std::ifstream f(p);
  std::string s;
  if (!f || !std::getline(f, s)) return "";
  while (!s.empty() && (s.back() == '\n' || s.back() == '\r' || s.back() == ' ')) s.pop_back();
  return s;
}
}  // namespace

BatteryStatus read_battery(const std::string& dir) {
  namespace fs = std::filesystem;
  BatteryStatus b;
  std::error_code ec;
  bool mains = false;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const fs::path p = it->path();
    const std::string type = attr(p / "type");
    if (type == "Mains") {
      mains = mains || attr(p / "online") == "1";
      continue;
    }
    if (type != "Battery") continue;
    const std::string cap = attr(p / "capacity");
    char* end_ptr = nullptr;
    const long v = std::strtol(cap.c_str(), &end_ptr, 10);
    if (cap.empty() || *end_ptr != '\0' || v < 0 || v > 100) continue;  // not a reading
    const float charge = static_cast<float>(v) / 100.f;
    const std::string status = attr(p / "status");
    if (!b.present || charge < b.charge) {
      b.present = true;
      b.charge = charge;
      b.name = p.filename().string();
      b.charging = status == "Charging" || status == "Full" || status == "Not charging";
    }
  }
  b.charging = b.charging || (b.present && mains);
  return b;
}

}  // namespace stairguide::feedback
