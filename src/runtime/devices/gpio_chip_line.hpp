#pragma once
// A line of a GPIO chip through libgpiod's C++ API, opened the same way for the buzzer's output
// and the button's input (haptic_player.cpp, button_reader.cpp): what failed is named with the
// device, the chip and the line.
#include <gpiod.hpp>
#include <stdexcept>
#include <string>

namespace stairguide::runtime::devices::detail {

struct GpioChipLine {
  gpiod::chip chip;
  gpiod::line line;  ///< taken from the chip, not yet requested

  /// "<device>: GPIO chip '<chip>' line <line>: ", the start of every message about it.
  static std::string what(const std::string& device, const std::string& chip, int line) {
    return device + ": GPIO chip '" + chip + "' line " + std::to_string(line) + ": ";
  }

  /// Opens `chip` (a name, path, label or number) and takes its line `line`. Throws
  /// std::runtime_error starting with what(device, chip, line).
  void open(const std::string& device, const std::string& chip_name, int line_no) {
    try {
      chip.open(chip_name, gpiod::chip::OPEN_LOOKUP);
    } catch (const std::exception& e) {
      throw std::runtime_error(what(device, chip_name, line_no) + "cannot open the chip (" + e.what() + ")");
    }
    try {
      line = chip.get_line(static_cast<unsigned>(line_no));
    } catch (const std::exception& e) {
      throw std::runtime_error(what(device, chip_name, line_no) + "no such line (" + e.what() + ")");
    }
  }

  /// Releases the line when it was requested; a failure is ignored (the chip's closing releases it).
  void release() noexcept {
    try {
      if (line) line.release();
    } catch (const std::exception&) {
    }
  }
};

}  // namespace stairguide::runtime::devices::detail
