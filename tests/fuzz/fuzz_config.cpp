// The config loader on arbitrary text: a ConfigError is the expected answer to bad input; any
// other exception, a crash, a leak or a hang is a bug.
#include <cstdint>
#include <string>

#include "stairguide/config/config_loader.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    stairguide::load_config_text(std::string(reinterpret_cast<const char*>(data), size), "fuzz.yaml");
  } catch (const stairguide::ConfigError&) {
  }
  return 0;
}
