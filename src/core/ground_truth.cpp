#include "stairguide/core/ground_truth.hpp"

namespace stairguide {

const char* to_string(StairKind k) {
  switch (k) {
    case StairKind::kNone: return "none";
    case StairKind::kAscending: return "ascending";
    case StairKind::kDescending: return "descending";
    case StairKind::kSingleStep: return "single_step";
    case StairKind::kCurb: return "curb";
  }
  return "none";
}

bool parse_stair_kind(const std::string& s, StairKind& out) {
  for (StairKind k : {StairKind::kNone, StairKind::kAscending, StairKind::kDescending, StairKind::kSingleStep,
                      StairKind::kCurb}) {
    if (s == to_string(k)) {
      out = k;
      return true;
    }
  }
  return false;
}

std::string down_contradiction(StairKind kind, bool down) {
  if ((kind == StairKind::kAscending || kind == StairKind::kSingleStep) && down)
    return std::string("a ") + to_string(kind) + " cannot go down ('down: true')";
  if (kind == StairKind::kDescending && !down)
    return "a descending staircase goes down ('down: false' given)";
  return "";
}

bool FrameTruth::any_stair_visible() const {
  for (const auto& s : stairs)
    if (!s.visible_steps.empty() || s.first_edge_visible) return true;
  return false;
}

}  // namespace stairguide
