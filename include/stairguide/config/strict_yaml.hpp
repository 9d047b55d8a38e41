#pragma once
/// \file strict_yaml.hpp
/// Reading YAML from outside (the config, camera.yaml, labels.yaml) within bounds: the file must be
/// a regular file no bigger than a limit (a FIFO, a device or /dev/zero is refused at once, never
/// read), and its text must be exactly one YAML document, no deeper and with no more nodes than a
/// limit, and with no key given twice in a mapping (yaml-cpp keeps the first and drops the later
/// value unseen). Every refusal names the file, and the line where the text says where.

#include <yaml-cpp/yaml.h>

#include <cstddef>
#include <stdexcept>
#include <string>

namespace stairguide {

/// A refused input. `what()` is "FILE: what is wrong" or "FILE:LINE: what is wrong".
class InputFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The whole of a regular file of at most `max_bytes` bytes. `what` names the kind of file in
/// messages ("config file", "camera.yaml"). Throws InputFileError when the file is missing,
/// unreadable, a directory, not a regular file (FIFO, socket, device) or bigger than `max_bytes`.
std::string read_small_file(const std::string& path, std::size_t max_bytes, const char* what);

struct YamlLimits {
  std::size_t max_nodes = 100000;  ///< scalars, sequences and mappings together
  int max_depth = 32;              ///< nesting of sequences and mappings
};

/// Parses `text` (named `name` in messages) as one YAML document. Throws InputFileError on a
/// syntax error, a second document, a key given twice in one mapping ("NAME:LINE: key 'a.b'
/// given twice (first on line N)"), more nodes or deeper nesting than `limits`. Keys are named by
/// their path: mapping keys joined by '.', list items as [i].
YAML::Node load_strict_yaml(const std::string& text, const std::string& name, const YamlLimits& limits);

}  // namespace stairguide
