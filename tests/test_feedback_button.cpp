// The wearer's button: edges decoded into presses (debounce, short, long, double). Its lines and
// the reader's thread are tested in test_runtime_devices_button.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>
#include <vector>

#include "stairguide/feedback/button.hpp"

using namespace stairguide::feedback;

namespace {

/// Feeds (time, down) edges, then advances to `until`; the presses as "kind@t".
std::vector<std::string> decode(const std::vector<std::pair<double, bool>>& edges, double until,
                                PressTiming tm = {}) {
  PressDecoder d(tm);
  std::vector<PressEvent> out;
  for (const auto& [t, down] : edges) d.edge({t, down}, out);
  // Advanced as the reader does: to each deadline in turn, then to the end.
  for (double t = d.next_deadline(); t <= until; t = d.next_deadline()) d.advance(t, out);
  d.advance(until, out);
  std::vector<std::string> s;
  for (const auto& p : out) {
    char b[48];
    std::snprintf(b, sizeof b, "%s@%.2f", to_string(p.press), p.t);
    s.push_back(b);
  }
  return s;
}

}  // namespace

TEST(ButtonDecoder, ShortLongAndDouble) {
  // Short: pressed 0.15 s; told once the double-press gap (0.4 s) has passed without a second.
  EXPECT_EQ(decode({{1.0, true}, {1.15, false}}, 3.0), (std::vector<std::string>{"short@1.55"}));
  // Long: told when held 1 s, not at the release.
  EXPECT_EQ(decode({{1.0, true}, {3.5, false}}, 5.0), (std::vector<std::string>{"long@2.00"}));
  EXPECT_EQ(decode({{1.0, true}}, 1.99), (std::vector<std::string>{}));
  // Double: the second press 0.2 s after the first's release, told at its release.
  EXPECT_EQ(decode({{1.0, true}, {1.1, false}, {1.3, true}, {1.4, false}}, 3.0),
            (std::vector<std::string>{"double@1.40"}));
  // Two presses 0.6 s apart: two short presses.
  EXPECT_EQ(decode({{1.0, true}, {1.1, false}, {1.7, true}, {1.8, false}}, 3.0),
            (std::vector<std::string>{"short@1.50", "short@2.20"}));
  // A short press then a long one: a long press.
  EXPECT_EQ(decode({{1.0, true}, {1.1, false}, {1.3, true}, {2.6, false}}, 3.0),
            (std::vector<std::string>{"long@2.30"}));
}

TEST(ButtonDecoder, BouncesAreNotPresses) {
  // Contact bounce of a few ms on the press and on the release: one short press, its release timed
  // from the edge that settled (1.25 s).
  EXPECT_EQ(
      decode({{1.0, true}, {1.004, false}, {1.006, true}, {1.2, false}, {1.22, true}, {1.25, false}}, 3.0),
      (std::vector<std::string>{"short@1.65"}));
  // A spike shorter than the debounce: nothing.
  EXPECT_EQ(decode({{1.0, true}, {1.01, false}}, 3.0), (std::vector<std::string>{}));
  // The same level reported twice changes nothing.
  EXPECT_EQ(decode({{1.0, true}, {1.05, true}, {1.2, false}, {1.25, false}}, 3.0),
            (std::vector<std::string>{"short@1.60"}));
}
