#pragma once
/// \file latency.hpp
/// Fixed-memory latency histogram (0.1 ms bins up to 2 s, one overflow bin) giving percentiles
/// exact to a bin, over a run of any length. Not thread-safe.

#include <cstdint>
#include <string>
#include <vector>

namespace stairguide::runtime {

class LatencyHistogram {
 public:
  static constexpr double kBinMs = 0.1;
  static constexpr int kBins = 20000;  ///< 0 .. 2000 ms

  LatencyHistogram() : bins_(kBins + 1, 0) {}

  void add(double ms);
  void clear();
  std::uint64_t count() const { return count_; }
  /// Percentile `p` in [0, 100] in ms (the upper edge of its bin, or the maximum seen for the
  /// overflow bin); 0 when empty.
  double percentile(double p) const;
  double max() const { return max_; }
  double mean() const { return count_ ? sum_ / static_cast<double>(count_) : 0.0; }

 private:
  std::vector<std::uint32_t> bins_;
  std::uint64_t count_ = 0;
  double sum_ = 0.0;
  double max_ = 0.0;
};

/// The cue latency of one cue kind over a run: capture of the frame that warranted the cue -> its
/// first sample handed to the sound device (a cue said in one phrase with others of its frame
/// counts from the phrase's first sample; a step cue told by an earcon, from the earcon's).
struct CueKindLatency {
  std::string kind;                ///< feedback::to_string(Cue): "tick", "count", ...
  std::uint64_t given = 0;         ///< cues of this kind given by the policy
  std::uint64_t sounded = 0;       ///< of them, started on the sound device
  std::uint64_t late = 0;          ///< started after the next step's frame (its step had passed)
  std::vector<double> samples_ms;  ///< every latency measured, in the order started
  /// The feedback path's share of each: the decision on the frame -> its first sample handed
  /// (the rest is capture -> decision, the stages' time).
  std::vector<double> from_decision_ms;
};

}  // namespace stairguide::runtime
