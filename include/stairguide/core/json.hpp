#pragma once
/// \file json.hpp
/// The two pieces of JSON text formatting the result printers share (no I/O).

#include <cmath>
#include <cstdio>
#include <string>

namespace stairguide {

/// A JSON string literal: quotes and backslashes escaped, control characters dropped.
inline std::string json_quote(const std::string& s) {
  std::string o = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') o += '\\';
    if (static_cast<unsigned char>(c) < 0x20) continue;
    o += c;
  }
  return o + "\"";
}

/// A JSON number with 6 significant digits; NaN and infinities (not JSON) become 0.
inline std::string json_number(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.6g", std::isfinite(v) ? v : 0.0);
  return b;
}

}  // namespace stairguide
