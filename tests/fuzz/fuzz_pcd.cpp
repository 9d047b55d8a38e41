// read_pcd_frame on arbitrary bytes: a SourceError naming the file is the expected answer to bad input;
// any other exception, a crash, a leak or a hang is a bug.
#include <cstdint>

#include "fuzz_util.hpp"
#include "stairguide/capture/dataset.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    (void)stairguide::read_pcd_frame(stairguide_fuzz::as_file(data, size, ".pcd"));
  } catch (const stairguide::SourceError&) {
  }
  return 0;
}
