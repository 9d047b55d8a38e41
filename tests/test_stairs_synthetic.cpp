// Stair detection and modelling end to end on the synthetic world: renderer -> perception ->
// stairs, scored against the renderer's ground truth (issue 4's figures). The real frames of
// ../shared/data are in test_stairs_real.cpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <map>

#include "stairguide/capture/frame_source.hpp"
#include "stairguide/synth/synth.hpp"
#include "stairguide/perception/perception.hpp"
#include "stairguide/eval/stair_eval.hpp"
#include "stairguide/stairs/stairs.hpp"
#include "synth_stairs_test_util.hpp"

namespace {

using namespace stairguide;

/// Static presets: independent views, perception reset before each. Sequences: the whole walk,
/// every frame rendered and processed (perception tracks the floor from frame to frame at the
/// sensor's 30 Hz, as in use), every kSequenceStride-th frame scored: the approach from far, the
/// arrival at the first edge and the frames on the stairs (those are the traversal's and are
/// skipped by the evaluation). Consecutive frames are nearly the same view: the stride keeps a
/// 600-frame walk from outweighing the static views without hiding any stretch of it.
constexpr int kStaticFrames = 16;
constexpr int kSequenceStride = 3;
constexpr std::uint32_t kSeed = 5;

/// Why an expected stair was missed, or something false was reported.
enum class Cause {
  kNoFloorInView,   ///< perception found no floor, and little floor is in view (truth)
  kNoFloorFound,    ///< perception found no floor although the truth has it in view
  kFloorDoubtful,   ///< the stairs stage refused the floor (a lower level nearer the user)
  kNoCandidates,    ///< perception gave no step candidate
  kStage,           ///< the stairs stage: candidates there but no validated staircase
  kWrongDirection,  ///< detected at the true edge, going the wrong way
  kElsewhere,       ///< detected, but nowhere near a true edge (false positive)
  kFloorless,       ///< the floorless route (no floor) reported a staircase off the true edge
  kKind             ///< a TP whose kind is wrong for the user (flight vs one step)
};
const char* to_string(Cause c) {
  switch (c) {
    case Cause::kNoFloorInView: return "perception: no floor (little in view)";
    case Cause::kNoFloorFound: return "perception: no floor (floor in view)";
    case Cause::kFloorDoubtful: return "stairs: floor doubtful";
    case Cause::kNoCandidates: return "perception: no step candidates";
    case Cause::kStage: return "stairs: rejected";
    case Cause::kWrongDirection: return "stairs: wrong direction";
    case Cause::kElsewhere: return "stairs: detection off the edge";
    case Cause::kFloorless: return "stairs floorless: off the edge";
    case Cause::kKind: return "stairs: kind (flight vs one step)";
  }
  return "?";
}

struct Miss {
  std::string scene;
  long first = 0, last = 0;  ///< frame range (a run of consecutive scored frames with one cause)
  int frames = 0;
  Cause cause = Cause::kStage;
  StairFrameEval eval;  ///< of the first frame of the run
  StairVerdict verdict = StairVerdict::kNoCandidates;
  StairKind got = StairKind::kNone;
  int levels = 0;
  float distance = 0.f;  ///< m, user to the first edge at the first frame of the run
};

/// Recall by the user's distance to the first edge (along the staircase's direction).
constexpr float kDistanceBins[] = {1.f, 2.f, 3.f, 1e9f};
constexpr int kBins = 4;

struct Suite {
  StairEvalTable table;
  int frames = 0;
  std::map<std::string, long> processed;  ///< frames run through perception, per preset
  std::map<Cause, int> cause_frames;      ///< FN/FP/kind-wrong frames per cause
  std::vector<double> stage_ms;
  std::vector<Miss> misses;  ///< FN and FP frames and TPs of the wrong kind, runs merged
  int bin_tp[kBins] = {}, bin_fn[kBins] = {};
  std::map<std::string, std::array<int, 2 * kBins>> kind_bins;  ///< per truth kind: TP then FN per bin
  int descending_stage_misses = 0;  ///< FN on a descending flight with a floor and candidates (stairs stage)
};

/// Distance from the user (camera) to the first edge of the expected stair with most treads in
/// view, along z_S; negative past it. NaN when no stair is expected.
float edge_distance(const FrameTruth& t) {
  const StairTruth* best = nullptr;
  for (const auto& s : t.stairs)
    if (!s.visible_steps.empty() && (!best || s.visible_steps.size() > best->visible_steps.size())) best = &s;
  if (!best) return std::nanf("");
  return -(best->T_camera_stair.inverse().translation().z());
}

Cause cause_of(const StairFrameEval& e, const StairResult& r, const SceneResult& scene, const FrameTruth& t) {
  if (e.outcome == EvalOutcome::kTP) return Cause::kKind;
  if (e.wrong_direction) return Cause::kWrongDirection;
  if (r.detected) return r.without_floor ? Cause::kFloorless : Cause::kElsewhere;
  if (!scene.floor_found) return t.floor_visible ? Cause::kNoFloorFound : Cause::kNoFloorInView;
  if (r.verdict == StairVerdict::kFloorDoubtful) return Cause::kFloorDoubtful;
  if (r.verdict == StairVerdict::kNoCandidates) return Cause::kNoCandidates;
  return Cause::kStage;
}

Suite run_suite() {
  Suite out;
  sgtest::SynthStairs pipe;
  const SceneResult& scene = pipe.scene;
  const FrameTruth& truth = pipe.truth;
  for (const auto& p : synth::presets()) {
    const bool sequence = p.default_frames > 1;
    const long count = sequence ? p.default_frames : kStaticFrames;
    // Static presets: independent views; a walk starts from nothing and is then tracked.
    for (long i = 0; i < count; ++i) {
      const StairResult& result = pipe.step(p.name, i, kSeed, /*cold=*/!sequence || i == 0);
      ++out.processed[p.name];
      if (sequence && i % kSequenceStride != 0) continue;
      const StairFrameEval e = evaluate_stair_frame(result, truth);
      out.table.add(e, p.name);
      out.stage_ms.push_back(result.timings.total_ms);
      ++out.frames;
      const float dist = edge_distance(truth);
      if (e.outcome == EvalOutcome::kTP || e.outcome == EvalOutcome::kFN) {
        int b = 0;
        while (b < kBins - 1 && !(dist < kDistanceBins[b])) ++b;
        (e.outcome == EvalOutcome::kTP ? out.bin_tp : out.bin_fn)[b]++;
        auto& kb = out.kind_bins[to_string(e.truth_kind)];
        kb[static_cast<std::size_t>(b + (e.outcome == EvalOutcome::kTP ? 0 : kBins))]++;
      }
      const bool bad = e.outcome == EvalOutcome::kFN || e.outcome == EvalOutcome::kFP || e.false_positive ||
                       (e.outcome == EvalOutcome::kTP && !e.kind_ok());
      if (!bad) continue;
      const Cause c = cause_of(e, result, scene, truth);
      ++out.cause_frames[c];
      if (e.outcome == EvalOutcome::kFN && e.truth_kind == StairKind::kDescending &&
          (c == Cause::kFloorDoubtful || c == Cause::kStage))
        ++out.descending_stage_misses;
      Miss* last = out.misses.empty() ? nullptr : &out.misses.back();
      if (sequence && last && last->scene == p.name && last->cause == c &&
          last->last + kSequenceStride == i && last->eval.outcome == e.outcome) {
        last->last = i;
        ++last->frames;
      } else {
        out.misses.push_back({p.name, i, i, 1, c, e, result.verdict,
                              result.detected ? result.kind : StairKind::kNone, result.levels, dist});
      }
    }
  }
  return out;
}

// The whole suite is rendered and run once, in a single test: gtest_discover_tests runs every
// TEST in its own process, so checks split over several TESTs would each regenerate the suite.
TEST(StairsSynthetic, Suite) {
  const Suite s = run_suite();
  std::printf("%s", s.table.to_text().c_str());
  for (const Miss& m : s.misses) {
    char range[48];
    if (m.first == m.last)
      std::snprintf(range, sizeof range, "%ld", m.first);
    else
      std::snprintf(range, sizeof range, "%ld-%ld (%d)", m.first, m.last, m.frames);
    std::printf(
        "miss: %-28s %-16s %-3s %-36s truth %-11s (%d treads%s, edge %.1f m) got %-11s %d levels (%s)\n",
        m.scene.c_str(), range, to_string(m.eval.outcome), to_string(m.cause), m.eval.truth_label(),
        m.eval.truth_visible_steps, m.eval.fully_visible ? ", fully visible" : "", m.distance,
        m.eval.predicted_label(), m.levels, to_string(m.verdict));
  }
  std::printf("frames processed per preset:");
  for (const auto& [name, n] : s.processed) std::printf(" %s %ld;", name.c_str(), n);
  std::printf("\nbad frames by cause:\n");
  for (const auto& [c, n] : s.cause_frames) std::printf("  %-40s %d\n", to_string(c), n);
  std::printf("recall by distance from the user to the first edge:");
  for (int b = 0; b < kBins; ++b)
    std::printf(" <%.0f m: %d/%d;", kDistanceBins[b] > 100 ? 99.0 : kDistanceBins[b], s.bin_tp[b],
                s.bin_tp[b] + s.bin_fn[b]);
  std::printf("\n");
  for (const auto& [kind, kb] : s.kind_bins) {
    std::printf("  %-11s", kind.c_str());
    for (int b = 0; b < kBins; ++b)
      std::printf(" <%.0f m: %d/%d;", kDistanceBins[b] > 100 ? 99.0 : kDistanceBins[b],
                  kb[static_cast<std::size_t>(b)],
                  kb[static_cast<std::size_t>(b)] + kb[static_cast<std::size_t>(b + kBins)]);
    std::printf("\n");
  }
  const EvalSummary& a = s.table.all;

  {
    SCOPED_TRACE("suite covers every preset with enough frames");
    EXPECT_GE(s.frames, 300);
    EXPECT_EQ(s.table.by_scene.size(), synth::presets().size());
  }

  {
    SCOPED_TRACE("no false positives");
    EXPECT_EQ(a.fp, 0);
    for (const auto& [name, sum] : s.table.by_scene) EXPECT_EQ(sum.fp, 0) << name;
  }

  {
    SCOPED_TRACE("detects staircases in view");
    auto count = [&](std::initializer_list<Cause> cs) {
      int n = 0;
      for (Cause c : cs) {
        const auto it = s.cause_frames.find(c);
        n += it == s.cause_frames.end() ? 0 : it->second;
      }
      return n;
    };
    const int perception_fn = count({Cause::kNoFloorInView, Cause::kNoFloorFound, Cause::kNoCandidates});
    std::printf(
        "recall %.4f (%d TP, %d FN; %d FN where perception gave no floor or no candidate), "
        "fully visible %.4f (%d frames)\n",
        a.recall(), a.tp, a.fn, perception_fn, a.recall_fully_visible(), a.full_tp + a.full_fn);
    for (const char* kind : {"ascending", "descending"}) {
      const auto it = s.table.by_kind.find(kind);
      if (it != s.table.by_kind.end())
        std::printf("  %-10s recall %.4f (%d TP, %d FN), fully visible %.4f (%d frames)\n", kind,
                    it->second.recall(), it->second.tp, it->second.fn, it->second.recall_fully_visible(),
                    it->second.full_tp + it->second.full_fn);
    }
    const double stage_recall = static_cast<double>(a.tp) / std::max(1, a.tp + a.fn - perception_fn);
    std::printf("recall where perception gave a floor and step candidates: %.4f\n", stage_recall);
    // Measured on the whole walks (stride 3, seed 5, floorless route on): recall 0.991 (327 of
    // 330), fully visible 1.000 (125 of 125; issue 4 asks >= 0.99), within 1 m of the first edge
    // 179 of 181 (descending 89 of 89). Descending: 120 of 120. Before the "lean" at the first
    // edge (floorless.hpp) the step over the edge was missed in every approach walk: 0.979, 118 of
    // 120 descending here, 48 frames on seeds 1-4 of the walks. Before that round fully visible
    // was 0.976: two cold views whose floor strip, deeper than the flight's tread, is the floor
    // (floorless.hpp), one far flight whose second tread took in a tilted crease strip
    // (segmentation now splits those), and after that fix a floor strip 5 cm deep at the foot of
    // the steps that tied the direction vote. The bounds are the measured figures less a margin,
    // so a regression fails; the fully visible one is the issue's.
    EXPECT_GE(a.recall(), 0.98);
    EXPECT_GE(a.recall_fully_visible(), 0.99);
    EXPECT_GE(stage_recall, 0.98);
    {
      const EvalSummary& d = s.table.by_kind.at("descending");
      EXPECT_GE(d.recall(), 0.99);
      EXPECT_EQ(d.full_fn, 0) << "a fully visible descending flight missed";
      EXPECT_EQ(s.descending_stage_misses, 0) << "a descending flight refused by the stairs stage";
      const auto& kb = s.kind_bins.at("descending");
      EXPECT_GE(kb[0], 87) << "descending frames detected within 1 m of the edge (measured 89 of 89)";
    }
    EXPECT_GE(s.bin_tp[0], 175) << "frames detected within 1 m of the first edge (measured 179 of 181)";
    const int far_tp = s.bin_tp[1] + s.bin_tp[2] + s.bin_tp[3],
              far_fn = s.bin_fn[1] + s.bin_fn[2] + s.bin_fn[3];
    std::printf("recall from 1 m out: %.4f (%d frames)\n",
                static_cast<double>(far_tp) / std::max(1, far_tp + far_fn), far_tp + far_fn);
    EXPECT_GE(far_tp + far_fn, 100);
    EXPECT_GE(far_tp, 0.95 * (far_tp + far_fn));
    // Every walk is scored from end to end (stairs skipped only while the user is on them).
    for (const auto& p : synth::presets())
      if (p.default_frames > 1) {
        EXPECT_EQ(s.processed.at(p.name), p.default_frames) << p.name;
        EXPECT_EQ(s.table.by_scene.at(p.name).frames,
                  (p.default_frames + kSequenceStride - 1) / kSequenceStride)
            << p.name;
        EXPECT_GE(s.table.by_scene.at(p.name).tp, 10) << p.name;
      }
    for (const char* kind : {"ascending", "descending"}) {
      const auto it = s.table.by_kind.find(kind);
      ASSERT_NE(it, s.table.by_kind.end()) << kind;
      EXPECT_GE(it->second.tp, 15) << kind;
    }
  }

  {
    SCOPED_TRACE("single steps and curbs told apart from furniture");
    const auto& sc = s.table.by_scene;
    for (const char* name : {"table_static", "bench_static", "shelves_static", "low_platform_static",
                             "sofa_static", "corridor_static", "room_clutter_static", "floor_only_static"}) {
      const EvalSummary& e = sc.at(name);
      EXPECT_EQ(e.fp, 0) << name;
      EXPECT_EQ(e.tn, e.frames) << name;
    }
    for (const char* name : {"single_step_static", "curb_static"}) {
      const EvalSummary& e = sc.at(name);
      EXPECT_GE(e.tp, 8) << name;
      EXPECT_GE(e.recall(), 0.8) << name;
      // What the user needs of one step: up or down, one step, where its edge is. All of them right.
      EXPECT_EQ(e.kind_ok, e.tp) << name;
      EXPECT_EQ(e.wrong_direction, 0) << name;
    }
    // A platform 1.7-2.5 m wide filling the view (far end and both sides out of the image) cannot
    // be told from another floor level in one frame: it is reported as a curb up (measured 4 of
    // 14, right in direction, count and edge; the confusion table shows them). Curbs, up and
    // down, come out as curbs going the right way.
    EXPECT_GE(3 * sc.at("single_step_static").kind_correct, 2 * sc.at("single_step_static").tp);
    EXPECT_EQ(sc.at("curb_static").kind_correct, sc.at("curb_static").tp);
    EXPECT_EQ(a.wrong_direction, 0) << "a detection at a true edge going the wrong way";
    EXPECT_GE(a.confusion.at("curb_up").at("curb_up") + 0, 3);
    EXPECT_GE(a.confusion.at("curb_down").at("curb_down") + 0, 3);
  }

  {
    SCOPED_TRACE("dimensions and pose");
    std::printf(
        "riser |err| %.2f cm sigma %.2f (n %d); tread %.2f sigma %.2f (n %d); width %.2f sigma %.2f (n %d)\n"
        "edge position %.2f cm (n %d), edge line %.2f cm (n %d), yaw %.2f deg sigma %.2f\n",
        100 * a.riser.mean_abs(), 100 * a.riser.sigma(), a.riser.n, 100 * a.tread.mean_abs(),
        100 * a.tread.sigma(), a.tread.n, 100 * a.width.mean_abs(), 100 * a.width.sigma(), a.width.n,
        100 * a.edge_pos.mean_abs(), a.edge_pos.n, 100 * a.edge_line.mean_abs(), a.edge_line.n,
        a.yaw.mean_abs(), a.yaw.sigma());
    EXPECT_GE(a.riser.n, 80);
    EXPECT_GE(a.tread.n, 50);
    EXPECT_LE(a.riser.mean_abs(), 0.01);
    EXPECT_LE(a.riser.sigma(), 0.01);
    EXPECT_LE(a.tread.mean_abs(), 0.01);
    EXPECT_LE(a.tread.sigma(), 0.01);
    EXPECT_LE(a.width.mean_abs(), 0.05);
    EXPECT_LE(a.edge_pos.mean_abs(), 0.03);
    EXPECT_LE(a.edge_line.mean_abs(), 0.03);
    EXPECT_LE(a.yaw.mean_abs(), 2.0);
    // Far, grazing views of ascending flights: the treads' near rows are lost, the risers facing
    // the camera place the steps (measured 0.27 cm; 0.65 cm from the treads alone).
    EXPECT_LE(s.table.by_kind.at("ascending").tread.mean_abs(), 0.005);
  }

  {
    SCOPED_TRACE("stage is fast");
    // Not a benchmark (that is `stairguide bench stairs`): a guard against a gross regression only.
    std::vector<double> t = s.stage_ms;
    ASSERT_FALSE(t.empty());
    std::sort(t.begin(), t.end());
    const double median = t[t.size() / 2];
    std::printf("stairs stage median %.3f ms, p95 %.3f ms (debug guard, not the benchmark)\n", median,
                t[t.size() * 95 / 100]);
    EXPECT_LT(median, 20.0);
  }
}

// Other seeds than the suite's, on the single-level cases: a single step whose platform runs out
// of view at the far side (its depth seen is only where the view ends) is a step, a shelf's bottom
// board at a step's height is not (a side panel rises above it), and a curb down seen far away as
// the strip past its edge's shadow is placed on its edge. Every view of the single-step, curb,
// shelves and low-platform presets of seeds 6 and 7, taken cold.
TEST(StairsSynthetic, SingleLevelsOnOtherSeeds) {
  sgtest::SynthStairs p;
  std::map<std::string, std::array<int, 4>> tally;  // tp, fn, fp (incl. off the edge), wrong way
  for (std::uint32_t seed : {6u, 7u}) {
    for (const char* preset :
         {"single_step_static", "curb_static", "shelves_static", "low_platform_static"}) {
      for (long i = 0; i < kStaticFrames; ++i) {
        const StairResult& r = p.step(preset, i, seed, /*cold=*/true);
        const StairFrameEval e = evaluate_stair_frame(r, p.truth);
        auto& t = tally[preset];
        t[0] += e.outcome == EvalOutcome::kTP;
        t[1] += e.outcome == EvalOutcome::kFN;
        t[2] += e.outcome == EvalOutcome::kFP || e.false_positive;
        t[3] += e.wrong_direction;
        if (e.outcome == EvalOutcome::kFN || e.outcome == EvalOutcome::kFP || e.false_positive)
          std::printf("seed %u %s %ld: %s (%s)\n", seed, preset, i, to_string(e.outcome),
                      to_string(r.verdict));
      }
    }
  }
  for (const auto& [preset, t] : tally)
    std::printf("%-20s seeds 6-7: TP %d FN %d FP %d wrong direction %d\n", preset.c_str(), t[0], t[1], t[2],
                t[3]);
  // Measured: single steps 27 of 27, curbs 28 of 28, no shelf nor box reported.
  EXPECT_EQ(tally["single_step_static"][1], 0);
  EXPECT_EQ(tally["curb_static"][1], 0);
  for (const auto& [preset, t] : tally) {
    EXPECT_EQ(t[2], 0) << preset;
    EXPECT_EQ(t[3], 0) << preset;
  }
  EXPECT_GE(tally["single_step_static"][0], 25);
  EXPECT_GE(tally["curb_static"][0], 25);
}

}  // namespace
