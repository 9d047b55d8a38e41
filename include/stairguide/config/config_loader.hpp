#pragma once
/// \file config_loader.hpp
/// The only code that touches YAML: loads and validates `stairguide.yaml`, and writes it back.

#include <stdexcept>
#include <string>
#include <vector>

#include "stairguide/core/config.hpp"

namespace stairguide {

/// A config problem. `what()` is one line: "FILE:LINE: key 'section.key': what is wrong".
class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// What a successful load saw besides the values.
struct ConfigLoadReport {
  std::vector<std::string> missing_keys;  ///< keys absent from the file (their defaults were kept)
};

/// Loads and validates a config file: unknown key, wrong type, out-of-range value, missing or
/// unreadable file, YAML syntax error and inconsistent pairs (min > max) each throw ConfigError.
/// Keys absent from the file keep their defaults (listed in `report`).
PipelineConfig load_config(const std::string& path, ConfigLoadReport* report = nullptr);

/// Same, from text; `name` stands for the file name in messages.
PipelineConfig load_config_text(const std::string& text, const std::string& name,
                                ConfigLoadReport* report = nullptr);

/// The config as commented YAML in file units; loading it gives back an equal config.
std::string dump_config_yaml(const PipelineConfig& config);

/// Default config path: $STAIRGUIDE_CONFIG, else /etc/stairguide/stairguide.yaml when it exists,
/// else the source tree's config/stairguide.yaml when it exists, else empty (built-in defaults).
/// Existence is checked with stat alone (never by opening: a FIFO there would block); a FIFO or
/// device there is chosen, and load_config refuses it by name.
std::string default_config_path();

/// The first of `candidates` that exists and is not a directory (stat only), else "".
std::string first_config_path(const std::vector<std::string>& candidates);

}  // namespace stairguide
