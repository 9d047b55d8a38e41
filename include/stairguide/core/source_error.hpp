#pragma once
/// \file source_error.hpp
/// The error of an input that cannot be opened or read: a recording, a dataset folder, a device, a
/// synthetic scene. In core so that every room that makes frames (capture, synth) can throw it.

#include <stdexcept>

namespace stairguide {

/// Thrown when a source cannot be opened; the message names the file or device and the problem.
class SourceError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace stairguide
