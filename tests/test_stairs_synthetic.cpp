// Stair detection and modelling end to end on the synthetic world: renderer -> perception ->
// stairs, scored against the renderer's ground truth (issue 4's figures). The real frames of
// ../shared/data are in test_stairs_real.cpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>

#include "stairguide/capture/frame_source.hpp"
#include "stairguide/capture/synthetic.hpp"
#include "stairguide/perception/perception.hpp"
#include "stairguide/stairs/stair_eval.hpp"
#include "stairguide/stairs/stairs.hpp"

namespace {

using namespace stairguide;

/// Static presets: independent views, perception reset before each. Sequences: a window of
/// consecutive frames from 40 % of the walk (the approach), perception tracking the floor as it
/// does in use, after a few frames of warm-up that are not scored.
constexpr int kStaticFrames = 16;
constexpr int kSequenceFrames = 30;
constexpr int kSequenceWarmup = 10;
constexpr std::uint32_t kSeed = 5;

struct Miss {
  std::string scene;
  long index = 0;
  StairFrameEval eval;
  StairVerdict verdict = StairVerdict::kNoCandidates;
  StairKind got = StairKind::kNone;
  int levels = 0;
};

struct Suite {
  StairEvalTable table;
  int frames = 0;
  int floor_missing_fn = 0;  ///< FNs on frames where perception found no floor (or it was doubted)
  std::vector<double> stage_ms;
  std::vector<Miss> misses;  ///< FN and FP frames and TPs of the wrong kind, for the log
};

Suite run_suite() {
  Suite out;
  const PipelineConfig cfg;
  Perception perception(cfg);
  StairStage stage(cfg);
  SceneResult scene;
  StairResult result;
  RgbdFrame frame;
  FrameTruth truth;
  const synth::SynthOptions opt;
  for (const auto& p : synth::presets()) {
    const bool sequence = p.default_frames > 1;
    const long first = sequence ? p.default_frames * 2 / 5 - kSequenceWarmup : 0;
    const long count = sequence ? kSequenceWarmup + kSequenceFrames : kStaticFrames;
    perception.reset();
    for (long i = first; i < first + count; ++i) {
      synth::render_preset_frame(p.name, i, kSeed, opt, frame, truth);
      if (!sequence) perception.reset();  // independent views
      perception.process(frame, scene);
      stage.run(scene, frame.intrinsics, result);
      if (sequence && i < first + kSequenceWarmup) continue;
      const StairFrameEval e = evaluate_stair_frame(result, truth);
      out.table.add(e, p.name);
      out.stage_ms.push_back(result.timings.total_ms);
      if (e.outcome == EvalOutcome::kFN && (result.verdict == StairVerdict::kNoFloor ||
                                            result.verdict == StairVerdict::kFloorDoubtful))
        ++out.floor_missing_fn;
      if (e.outcome == EvalOutcome::kFN || e.outcome == EvalOutcome::kFP ||
          (e.outcome == EvalOutcome::kTP && e.predicted_kind != e.truth_kind))
        out.misses.push_back({p.name, i, e, result.verdict, result.detected ? result.kind : StairKind::kNone,
                              result.levels});
      ++out.frames;
    }
  }
  return out;
}

// The whole suite is rendered and run once, in a single test: gtest_discover_tests runs every
// TEST in its own process, so checks split over several TESTs would each regenerate the suite.
TEST(StairsSynthetic, Suite) {
  const Suite s = run_suite();
  std::printf("%s", s.table.to_text().c_str());
  for (const Miss& m : s.misses)
    std::printf("miss: %-28s %4ld %-3s truth %-11s (%d treads%s) got %-11s %d levels (%s)\n", m.scene.c_str(), m.index,
                to_string(m.eval.outcome), to_string(m.eval.truth_kind), m.eval.truth_visible_steps,
                m.eval.fully_visible ? ", fully visible" : "", to_string(m.got), m.levels, to_string(m.verdict));
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
    std::printf("recall %.4f (%d TP, %d FN; %d FN where perception had no trustworthy floor), "
                "fully visible %.4f (%d frames)\n",
                a.recall(), a.tp, a.fn, s.floor_missing_fn, a.recall_fully_visible(), a.full_tp + a.full_fn);
    // Issue 4 asks for 99 % on frames with two or more steps fully visible: NOT reached (measured
    // 0.945 over fully visible stairs, 0.951 where perception gave a trustworthy floor). The bounds
    // below are the measured figures less a margin, so a regression fails. The fully visible
    // misses left are all perception's: frames without a floor (2) and a descending flight behind
    // a person whose treads show as a few pixel rows that no region is grown from (3).
    const int stage_fn = a.fn - s.floor_missing_fn;
    const double stage_recall = static_cast<double>(a.tp) / (a.tp + stage_fn);
    std::printf("recall of the stairs stage where perception found the floor: %.4f\n", stage_recall);
    EXPECT_GE(stage_recall, 0.92);
    // The overall figures depend on perception's floor too (which is still changing): a loose guard.
    EXPECT_GE(a.recall(), 0.75);
    EXPECT_GE(a.recall_fully_visible(), 0.80);
    for (const char* kind : {"ascending", "descending"}) {
      const auto it = s.table.by_kind.find(kind);
      ASSERT_NE(it, s.table.by_kind.end()) << kind;
      EXPECT_GE(it->second.tp, 15) << kind;
    }
  }

  {
    SCOPED_TRACE("single steps and curbs told apart from furniture");
    const auto& sc = s.table.by_scene;
    for (const char* name : {"table_static", "bench_static", "shelves_static", "low_platform_static", "sofa_static",
                             "corridor_static", "room_clutter_static", "floor_only_static"}) {
      const EvalSummary& e = sc.at(name);
      EXPECT_EQ(e.fp, 0) << name;
      EXPECT_EQ(e.tn, e.frames) << name;
    }
    for (const char* name : {"single_step_static", "curb_static"}) {
      const EvalSummary& e = sc.at(name);
      EXPECT_GE(e.tp, 8) << name;
      EXPECT_GE(e.recall(), 0.8) << name;
      // A platform 2.5 m wide and deep filling the view cannot be told from another floor level:
      // some single steps come out as curbs (measured 10 of 13); curbs come out as curbs.
      EXPECT_GE(4 * e.kind_correct, 3 * e.tp) << name << ": single step taken for a curb or back";
    }
  }

  {
    SCOPED_TRACE("dimensions and pose");
    std::printf("riser |err| %.2f cm sigma %.2f (n %d); tread %.2f sigma %.2f (n %d); width %.2f sigma %.2f (n %d)\n"
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

}  // namespace
