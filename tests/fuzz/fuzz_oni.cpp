// OniSource (OpenNI2's own player behind our checks) on arbitrary bytes: open, then read up to
// three frames. A SourceError at open and a kError/kEnd read are the expected answers to bad
// input; a crash, a hang or any other exception is a bug (ours, or OpenNI2's to guard against).
#include <cstdint>

#include "fuzz_util.hpp"
#include "stairguide/capture/oni.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    stairguide::OniOptions o;
    o.frame_timeout = 0.2;
    stairguide::OniSource src(stairguide_fuzz::as_file(data, size, ".oni"), o);
    stairguide::RgbdFrame f;
    for (int i = 0; i < 3 && src.read(f).ok(); ++i) {
    }
  } catch (const stairguide::SourceError&) {
  }
  return 0;
}
