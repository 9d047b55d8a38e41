#pragma once
/// \file logging.hpp
/// spdlog set-up of the daemon: the systemd journal when stderr is connected to it
/// ($JOURNAL_STREAM matches stderr), stderr otherwise; level from the config.

#include <string>

namespace stairguide::runtime {

/// True when stderr is the journal stream systemd gave this process ($JOURNAL_STREAM names
/// stderr's device and inode).
bool stderr_is_journal();

/// Installs the default logger "stairguided" with the journal or stderr sink and `level`
/// ("trace" ... "off"). Safe to call again (replaces the logger).
void setup_logging(const std::string& level);

/// Changes the level of the default logger; false (level unchanged) on an unknown name.
bool set_log_level(const std::string& level);

}  // namespace stairguide::runtime
