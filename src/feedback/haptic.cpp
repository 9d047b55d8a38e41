#include "stairguide/feedback/haptic.hpp"

namespace stairguide::feedback {

HapticPattern haptic_pattern(const CueEvent& e) {
  switch (e.cue) {
    case Cue::kStairsAhead:
    case Cue::kStepAhead:
      if (e.direction > 0) return {{80, 120}, {250, 0}};
      return {{250, 120}, {80, 0}};
    case Cue::kTick:
    case Cue::kFirstStep:
    case Cue::kCount: return {{60, 0}};
    case Cue::kLastStep: return {{600, 0}};
    case Cue::kEndOfStairs: return {{60, 100}, {60, 0}};
    case Cue::kDropWarning: return {{70, 70}, {70, 70}, {70, 70}, {70, 70}, {70, 0}};
    case Cue::kBlind:
    case Cue::kCameraLost: return {{300, 200}, {300, 200}, {300, 0}};
    case Cue::kReady:
    case Cue::kCameraBack: return {{150, 0}};
    case Cue::kStepsLeft: return {};  // a number: spoken only
    case Cue::kApproach:
      return {{40, 0}};  // one sharp pulse, repeated faster as the edge nears (the policy's rhythm)
    case Cue::kBatteryLow: return {{200, 150}, {200, 0}};
    case Cue::kBatteryCritical: return {{200, 100}, {200, 100}, {200, 100}, {200, 0}};
    case Cue::kSlow:
    case Cue::kWhere:
    case Cue::kVerbosity: return {};                                   // spoken only
    case Cue::kMuted: return {{40, 60}, {40, 60}, {40, 60}, {40, 0}};  // a flutter: sound off
    case Cue::kUnmuted: return {{150, 0}};                             // as ready: sound on again
    case Cue::kDropAhead:
      return {{150, 60}, {150, 60}, {150, 60}, {150, 0}};  // four strong pulses: unlike any stair cue
  }
  return {};
}

}  // namespace stairguide::feedback
