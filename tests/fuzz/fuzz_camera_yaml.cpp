// read_camera_yaml on arbitrary bytes: a SourceError naming the file is the expected answer to bad input;
// any other exception, a crash, a leak or a hang is a bug.
#include <cstdint>

#include "fuzz_util.hpp"
#include "stairguide/capture/dataset.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    (void)stairguide::read_camera_yaml(stairguide_fuzz::as_file(data, size, ".yaml"));
  } catch (const stairguide::SourceError&) {
  }
  return 0;
}
