// Logging set-up: journal sink when stderr is the journal stream, stderr otherwise.
#include "stairguide/runtime/logging.hpp"

#include <spdlog/sinks/stdout_sinks.h>
#include <spdlog/sinks/systemd_sink.h>
#include <spdlog/spdlog.h>
#include <sys/stat.h>

#include <cinttypes>
#include <cstdio>
#include <cstdlib>

namespace stairguide::runtime {

bool stderr_is_journal() {
  // systemd sets JOURNAL_STREAM=DEV:INODE for the stream it connected; checking it against
  // stderr avoids using the journal when stderr was redirected (e.g. a child with a pipe).
  const char* js = std::getenv("JOURNAL_STREAM");
  if (!js || !*js) return false;
  std::uintmax_t dev = 0, ino = 0;
  if (std::sscanf(js, "%" SCNuMAX ":%" SCNuMAX, &dev, &ino) != 2) return false;
  struct stat st {};
  if (fstat(2, &st) != 0) return false;
  return static_cast<std::uintmax_t>(st.st_dev) == dev && static_cast<std::uintmax_t>(st.st_ino) == ino;
}

bool set_log_level(const std::string& level) {
  const auto lv = spdlog::level::from_str(level);
  // from_str maps unknown names to "off"; only accept "off" when asked for.
  if (lv == spdlog::level::off && level != "off") return false;
  spdlog::set_level(lv);
  return true;
}

void setup_logging(const std::string& level) {
  std::shared_ptr<spdlog::logger> logger;
  if (stderr_is_journal()) {
    // The journal adds its own time stamp and the unit name; priorities map from the levels.
    auto sink = std::make_shared<spdlog::sinks::systemd_sink_mt>("stairguided");
    logger = std::make_shared<spdlog::logger>("stairguided", sink);
    logger->set_pattern("%v");
  } else {
    auto sink = std::make_shared<spdlog::sinks::stderr_sink_mt>();
    logger = std::make_shared<spdlog::logger>("stairguided", sink);
    logger->set_pattern("%Y-%m-%d %H:%M:%S.%e stairguided %l: %v");
  }
  logger->flush_on(spdlog::level::trace);  // nothing may be lost on a crash or a kill
  spdlog::set_default_logger(logger);
  if (!set_log_level(level)) {
    spdlog::set_level(spdlog::level::info);
    spdlog::warn("unknown log level '{}', using info", level);
  }
}

}  // namespace stairguide::runtime
