#pragma once
// libFuzzer harnesses (tools/fuzz): the input as a file, for readers that take a path.
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <string>

namespace stairguide_fuzz {

/// Writes the input to a file of this process (same name every time) and returns its path.
inline std::string as_file(const std::uint8_t* data, std::size_t size, const char* ext) {
  static const std::string path = "/tmp/stairguide-fuzz-" + std::to_string(getpid()) + ext;
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) std::abort();
  if (size && std::fwrite(data, 1, size, f) != size) std::abort();
  std::fclose(f);
  return path;
}

}  // namespace stairguide_fuzz
