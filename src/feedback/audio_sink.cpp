#include "stairguide/feedback/audio_sink.hpp"

#include <algorithm>
#include <cmath>

namespace stairguide::feedback {

void pan_gains(float pan, float& left, float& right) {
  const double p = std::clamp(std::isfinite(pan) ? static_cast<double>(pan) : 0.0, -1.0, 1.0);
  const double a = (p + 1.0) * M_PI / 4.0;  // 0 (left) .. pi/2 (right)
  left = static_cast<float>(std::cos(a));
  right = static_cast<float>(std::sin(a));
}

}  // namespace stairguide::feedback
