#pragma once
/// \file stair_eval.hpp
/// Scoring of stair results against ground truth (FrameTruth from the synthetic world or a
/// labelled dataset): the figures `stairguide eval` prints and the tests assert.
///
/// Per frame:
///  - a truth stair is *expected* when it has at least two visible treads (one for a single step or
///    curb): those frames make the recall;
///  - a detection *matches* a truth stair when it goes the same way (up: ascending, single step,
///    curb up; down: descending, curb down; StairResult::direction() against StairTruth::goes_down()) and
///    its first edge lies within `match_distance` of the true first edge (perpendicular distance to
///    the true edge line). A detection at a true edge going the other way matches nothing and is
///    counted in `wrong_direction` as well (a curb down reported as a step up is a fall);
///  - the kind is scored apart from detection: `kind_correct` counts TPs of exactly the true kind
///    (a curb in the true direction), `kind_ok` those right as far as the user is concerned: the
///    same direction and the same count class, one step (single step, curb) or a flight. A single
///    step reported as a curb up (a platform filling the view is another floor level for all one
///    frame shows) is kind_ok but not kind_correct; the confusion table shows every such case;
///  - TP: an expected stair detected and matched; FN: an expected stair not matched; FP: a
///    detection that matches no visible truth stair; TN: no visible stair, nothing detected. A
///    frame whose only stair is visible but not expected (one tread in view) and is not detected
///    counts in none of them (`skipped`); if it is detected and matched it is a TP. Recall is also
///    given over the *fully visible* stairs: expected, with the first edge and both its ends in view.
///  - frames where the user stands on a step (StairTruth::user_step > 0) are skipped: the first
///    edge is behind the user and the steps are the traversal's business (paper section 5).
///  - errors on TPs: riser and tread (signed, est - truth); width where both ends of the first edge
///    are visible; first-edge position (distance of the centres) where both ends are visible, and
///    distance of the true centre to the estimated edge line where the first edge is visible; yaw
///    (angle of z_S about the vertical).

#include <map>
#include <string>
#include <vector>

#include "stairguide/core/ground_truth.hpp"
#include "stairguide/stairs/stair_result.hpp"
#include "stairguide/stairs/traversal_result.hpp"

namespace stairguide {

/// Outcome of one frame.
enum class EvalOutcome { kTP, kFP, kTN, kFN, kSkipped };
const char* to_string(EvalOutcome o);

struct StairFrameEval {
  EvalOutcome outcome = EvalOutcome::kTN;
  bool false_positive = false;                  ///< also true for an FN frame with a detection somewhere else
  StairKind truth_kind = StairKind::kNone;      ///< kind of the matched (or main visible) truth stair
  StairKind predicted_kind = StairKind::kNone;  ///< kNone when nothing was detected
  bool truth_down = false;                      ///< StairTruth::goes_down() of that truth stair
  int predicted_direction = 0;                  ///< StairResult::direction() of the detection, 0 when none
  bool wrong_direction = false;  ///< a detection at a true stair's edge but going the other way
  int truth_visible_steps = 0;
  bool fully_visible = false;  ///< an expected stair whose first edge is in view with both ends
  bool on_stairs = false;      ///< the user stands on a step (not scored: traversal's frames)
  int predicted_levels = 0;
  StairVerdict verdict = StairVerdict::kNoCandidates;  ///< the stage's verdict (why not, or kDetected)
  bool has_riser = false, has_tread = false, has_width = false, has_edge = false, has_edge_line = false;
  float riser_err = 0.f, tread_err = 0.f, width_err = 0.f;  ///< m, estimate - truth
  float edge_pos_err = 0.f;   ///< m, distance between estimated and true first-edge centres
  float edge_line_err = 0.f;  ///< m, distance from the true centre to the estimated edge line
  float yaw_err_deg = 0.f;    ///< deg, |angle| between estimated and true z_S about the vertical

  /// Kind names with a curb's direction: "ascending", "descending", "single_step", "curb_up",
  /// "curb_down", "none".
  const char* truth_label() const;
  const char* predicted_label() const;
  /// The reported kind is the true one (a curb in the right direction).
  bool kind_exact() const;
  /// The reported kind is right for the user: same direction, and one step (single step or curb)
  /// against a flight (ascending or descending) told right.
  bool kind_ok() const;
};

/// "ascending", "descending", "single_step", "curb_up", "curb_down" or "none".
const char* kind_label(StairKind kind, bool down);

struct StairEvalOptions {
  float match_distance = 0.25f;  ///< m, first edges farther apart than this do not match
  /// Labels without a pose (e.g. labels.csv: stair / none and a kind): a detection matches a
  /// visible truth stair going the same way, wherever it is; no pose errors are computed (riser
  /// and tread errors are, where the truth gives them: a whole-folder label measured by hand).
  bool ignore_pose = false;
};

/// Scores one frame.
StairFrameEval evaluate_stair_frame(const StairResult& result, const FrameTruth& truth,
                                    const StairEvalOptions& options = {});

/// Mean, sigma and mean absolute value of a set of errors.
struct ErrorStats {
  int n = 0;
  double sum = 0, sum_sq = 0, sum_abs = 0, max_abs = 0;
  void add(double e);
  double mean() const { return n ? sum / n : 0.0; }
  double mean_abs() const { return n ? sum_abs / n : 0.0; }
  double sigma() const;  ///< standard deviation of the signed errors
};

/// Counts and error statistics over many frames.
struct EvalSummary {
  int frames = 0, tp = 0, fp = 0, tn = 0, fn = 0, skipped = 0;
  int kind_correct = 0;     ///< TPs whose predicted kind equals the truth kind (a curb's direction too)
  int kind_ok = 0;          ///< TPs whose kind is right for the user (StairFrameEval::kind_ok)
  int wrong_direction = 0;  ///< frames with a detection at a true edge going the wrong way
  /// Scored (not skipped) frames by truth label then reported label (kind_label; "none" when
  /// nothing was detected or no stair was in view).
  std::map<std::string, std::map<std::string, int>> confusion;
  /// The table of why-nots: scored frames by outcome ("tp", "fn", "fp", "tn") then the stage's
  /// verdict (to_string(StairVerdict)), so a miss is counted with the reason the software gave.
  std::map<std::string, std::map<std::string, int>> verdicts;
  int full_tp = 0,
      full_fn = 0;  ///< TP / FN among frames whose stair is fully visible (first edge, both ends)
  ErrorStats riser, tread, width, edge_pos, edge_line, yaw;
  void add(const StairFrameEval& e);
  double precision() const { return tp + fp ? static_cast<double>(tp) / (tp + fp) : 1.0; }
  double recall() const { return tp + fn ? static_cast<double>(tp) / (tp + fn) : 1.0; }
  double recall_fully_visible() const {
    return full_tp + full_fn ? static_cast<double>(full_tp) / (full_tp + full_fn) : 1.0;
  }
};

/// A summary overall, by truth kind and by scene (preset) name.
struct StairEvalTable {
  EvalSummary all;
  std::map<std::string, EvalSummary> by_kind;   ///< key: to_string(StairKind) of the truth ("none" too)
  std::map<std::string, EvalSummary> by_scene;  ///< key: FrameTruth::scene
  void add(const StairFrameEval& e, const std::string& scene);

  /// One JSON object: tp, fp, tn, fn, precision, recall, kind_correct, kind_ok, wrong_direction,
  /// riser/tread/width/edge/yaw statistics, the overall `confusion` (truth label -> reported
  /// label -> frames), the overall `verdicts` (outcome -> verdict -> frames), by_kind and by_scene
  /// objects with the same keys (no confusion, with verdicts).
  std::string to_json() const;
  /// A human-readable table.
  std::string to_text() const;
};

/// Drop-offs (issue 42 item 4) told per frame, scored against the synthetic truth's drop_* fields.
struct DropEvalSummary {
  int frames = 0;
  int near = 0, near_told = 0;      ///< a drop in view within DropEvalTable::near_m, and of them told
  int near_no_floor = 0;            ///< ... of the near ones missed, those where perception found no floor
  int far = 0, far_told = 0;        ///< a drop in view beyond it (within reach of the sensor or not)
  int none = 0, none_told = 0;      ///< no drop in the scene (and no descent in view): told is a false alarm
  int hidden = 0, hidden_told = 0;  ///< a drop in the scene but too little of its edge in view
  /// A descending staircase (or step down) in view: told as a drop; a drop found there that the
  /// stair cue took over (DropSummary::by_stairs).
  int descent = 0, descent_told = 0, descent_by_stairs = 0;
  ErrorStats distance, bearing_deg;  ///< of the near frames told: m and deg, told minus truth
  double near_rate() const { return near ? static_cast<double>(near_told) / near : 1.0; }
};

struct DropEvalTable {
  float near_m = 2.f;  ///< m, the edge within this of the wearer: must be told
  DropEvalSummary all;
  std::map<std::string, DropEvalSummary> by_scene;
  void add(const DropSummary& told, const FrameTruth& truth, const std::string& scene,
           bool floor_found = true);
  std::string to_json() const;  ///< one object: the overall counts and by_scene
  std::string to_text() const;  ///< a table, one line per scene with any frame of interest
};

}  // namespace stairguide
