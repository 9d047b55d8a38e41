#pragma once
/// \file stair_checks.hpp
/// The last phase of stair modelling: can what was modelled be walked, and how does it compare
/// with a building code?
///
/// Two questions kept apart on purpose (issue 39): a staircase is *silenced* only by physical
/// evidence that it cannot be walked (a level too shallow to hold a foot, a rise higher than a
/// step, too narrow for a body); building codes only *describe* what was found (steep, low steps,
/// 2R+T off the code), for the log, `detect`/`eval` and the cue. A carpeted flight with 9 cm
/// risers, a cellar stair with 20 cm goings or a garden flight with 45 cm goings is told.

#include <cstdint>
#include <string>

#include "stairguide/core/config.hpp"
#include "stairguide/stairs/stair_result.hpp"

namespace stairguide {

/// What a human foot and leg can walk (physics, not a code, so not in the config). The ranges are
/// the physical range: risers 5-25 cm, goings 15-60 cm, width from 0.5 m (an adult's shoulders;
/// 0.4 m let a shoe bench's 40 cm boards through as a flight on held-out seed 801).
struct WalkableLimits {
  float riser_min = 0.05f;      ///< m, lower than this is no step (a threshold, a rug)
  float riser_max = 0.25f;      ///< m, higher than this is no step one climbs (a ledge, a seat)
  float tread_min = 0.15f;      ///< m, a level shallower than this cannot hold a foot
  float tread_max = 0.60f;      ///< m, levels farther apart than a stride are no flight's consecutive steps
  float width_min = 0.50f;      ///< m, narrower than shoulders (a ladder, a shoe bench's 40 cm boards)
  float width_cut_min = 0.30f;  ///< m, a width cut by the view (a lower bound) must still reach this
};

/// The highest rise taken for one step when levels are stacked into a flight: the physical limit
/// (WalkableLimits::riser_max, 25 cm) or the configured H_max when that is higher. The building
/// code's H_max (22 cm) only describes a flight (describe_against_code): a cellar or attic stair
/// with 24 cm risers is walked every day, and stacking it on the code's limit left every level
/// but the floor unconnected ("no first step connected to the floor", 4 of 6 steep misses on
/// world2 seeds 912-913).
inline float step_rise_max(const ClassificationConfig& cls) {
  return cls.step_height_max > WalkableLimits{}.riser_max ? cls.step_height_max : WalkableLimits{}.riser_max;
}

/// Measured dimensions of a modelled staircase, as the checks need them.
struct StairDimensions {
  float riser = 0.f;            ///< m
  float tread = 0.f;            ///< m; meaningful only when `tread_known`
  bool tread_known = false;     ///< two or more step edges seen
  float width = 0.f;            ///< m, widest step seen
  bool width_complete = false;  ///< both lateral ends in view (else `width` is a lower bound)
  float range = 0.f;            ///< m, camera to the first edge (the slack grows with it)
};

/// Physical walkability: kDetected, or the physical reason it cannot be walked
/// (kRiserOutOfRange: not a step's rise; kTreadTooShort: cannot hold a foot; kTreadTooLong:
/// farther apart than a stride; kTooNarrow).
/// `tolerance` is the measurement slack (m), `tolerance_per_m2` its growth with the range.
StairVerdict check_walkable(const StairDimensions& d, float tolerance, float tolerance_per_m2,
                            const WalkableLimits& limits = WalkableLimits{});

/// Bits of StairCodeNotes: how a staircase compares with the configured building code.
enum StairCodeNote : std::uint32_t {
  kCodeWithin = 0,
  kCodeLowRisers = 1u << 0,    ///< riser under the code's lowest
  kCodeHighRisers = 1u << 1,   ///< riser over the code's highest (steep)
  kCodeShortTreads = 1u << 2,  ///< tread under the code's shortest (steep)
  kCodeBlondelLow = 1u << 3,   ///< 2R+T under the code's range (shallow, long strides)
  kCodeBlondelHigh = 1u << 4,  ///< 2R+T over the code's range
  kCodeNarrow = 1u << 5,       ///< narrower than the code's narrowest
};

/// The code notes (bits of StairCodeNote) of a staircase against `code`, with the same slack as
/// the checks. Single steps and curbs are described by their riser only.
std::uint32_t describe_against_code(const StairDimensions& d, bool flight, const StairModellingConfig& code);

/// "within code", or the notes joined by ", " ("steep: riser over the code, tread under the code").
std::string code_notes_text(std::uint32_t notes);

}  // namespace stairguide
