#include "stairguide/stairs/stair_checks.hpp"

namespace stairguide {

StairVerdict check_walkable(const StairDimensions& d, float tolerance, float tolerance_per_m2,
                            const WalkableLimits& limits) {
  // Far edges are measured less well (depth noise grows with the square of the distance): the
  // tread's slack grows with the range, as the riser's does not (it is a fit over all levels).
  const float tread_tol = tolerance + tolerance_per_m2 * d.range * d.range;
  if (d.riser < limits.riser_min - tolerance || d.riser > limits.riser_max + tolerance)
    return StairVerdict::kRiserOutOfRange;
  if (d.tread_known && d.tread < limits.tread_min - tread_tol) return StairVerdict::kTreadTooShort;
  if (d.tread_known && d.tread > limits.tread_max + tread_tol) return StairVerdict::kTreadTooLong;
  // A width cut by the image border is a lower bound: less is asked of it.
  const float width_min = d.width_complete ? limits.width_min : limits.width_cut_min;
  if (d.width < width_min - tolerance) return StairVerdict::kTooNarrow;
  return StairVerdict::kDetected;
}

std::uint32_t describe_against_code(const StairDimensions& d, bool flight, const StairModellingConfig& code) {
  const float tol = code.dimension_tolerance;
  const float tread_tol = tol + code.tread_tolerance_per_m2 * d.range * d.range;
  std::uint32_t notes = kCodeWithin;
  if (d.riser < code.riser_min - tol) notes |= kCodeLowRisers;
  if (d.riser > code.riser_max + tol) notes |= kCodeHighRisers;
  if (flight && d.width_complete && d.width < code.width_min - tol) notes |= kCodeNarrow;
  if (!flight || !d.tread_known) return notes;
  if (d.tread < code.tread_min - tread_tol) notes |= kCodeShortTreads;
  const float blondel = 2.f * d.riser + d.tread;
  if (blondel < code.blondel_min - tread_tol) notes |= kCodeBlondelLow;
  if (blondel > code.blondel_max + tread_tol) notes |= kCodeBlondelHigh;
  return notes;
}

std::string code_notes_text(std::uint32_t notes) {
  if (notes == kCodeWithin) return "within code";
  std::string s;
  auto add = [&](std::uint32_t bit, const char* text) {
    if (!(notes & bit)) return;
    if (!s.empty()) s += ", ";
    s += text;
  };
  add(kCodeLowRisers, "low risers");
  add(kCodeHighRisers, "steep: risers over the code");
  add(kCodeShortTreads, "steep: treads under the code");
  add(kCodeBlondelLow, "2R+T under the code");
  add(kCodeBlondelHigh, "2R+T over the code");
  add(kCodeNarrow, "narrower than the code");
  return s;
}

}  // namespace stairguide
