#include "stairguide/eval/stair_eval.hpp"

#include "stairguide/core/json.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace stairguide {

const char* to_string(EvalOutcome o) {
  switch (o) {
    case EvalOutcome::kTP: return "TP";
    case EvalOutcome::kFP: return "FP";
    case EvalOutcome::kTN: return "TN";
    case EvalOutcome::kFN: return "FN";
    case EvalOutcome::kSkipped: return "skipped";
  }
  return "?";
}

namespace {

// Which way the truth goes: its kind says it, a curb's label (StairTruth::down) for a curb.
bool truth_goes_up(const StairTruth& s) { return !s.goes_down(); }

bool result_goes_up(const StairResult& r) { return r.direction() > 0; }

bool expected(const StairTruth& s) {
  const std::size_t need = (s.kind == StairKind::kSingleStep || s.kind == StairKind::kCurb) ? 1 : 2;
  return s.visible_steps.size() >= need;
}

bool visible(const StairTruth& s) { return !s.visible_steps.empty() || s.first_edge_visible; }

float line_distance(const Eigen::Vector3f& p, const Eigen::Vector3f& o, const Eigen::Vector3f& dir) {
  const Eigen::Vector3f d = p - o;
  return (d - d.dot(dir) * dir).norm();
}

}  // namespace

const char* kind_label(StairKind kind, bool down) {
  if (kind == StairKind::kCurb) return down ? "curb_down" : "curb_up";
  return to_string(kind);
}

static const char* kind_class(StairKind kind, bool down) {
  switch (kind) {
    case StairKind::kAscending: return "flight_up";
    case StairKind::kDescending: return "flight_down";
    case StairKind::kSingleStep: return "one_step_up";
    case StairKind::kCurb: return down ? "one_step_down" : "one_step_up";
    default: return "none";
  }
}

const char* StairFrameEval::truth_label() const { return kind_label(truth_kind, truth_down); }
const char* StairFrameEval::predicted_label() const {
  return kind_label(predicted_kind, predicted_direction < 0);
}
bool StairFrameEval::kind_exact() const { return std::string(truth_label()) == predicted_label(); }
bool StairFrameEval::kind_ok() const {
  return std::string(kind_class(truth_kind, truth_down)) ==
         kind_class(predicted_kind, predicted_direction < 0);
}

StairFrameEval evaluate_stair_frame(const StairResult& r, const FrameTruth& f, const StairEvalOptions& opt) {
  StairFrameEval e;
  e.predicted_kind = r.detected ? r.kind : StairKind::kNone;
  e.predicted_levels = r.detected ? r.levels : 0;
  e.verdict = r.verdict;
  e.predicted_direction = r.detected ? r.direction() : 0;
  // On the stairs (climbing or descending) the steps are the traversal's business (paper 5), and
  // the first edge lies behind the user: such frames are not scored.
  for (const auto& s : f.stairs)
    if (s.user_step > 0) {
      e.outcome = EvalOutcome::kSkipped;
      e.truth_kind = s.kind;
      e.on_stairs = true;
      return e;
    }
  const StairTruth* main = nullptr;  // the expected (else visible) stair with most visible treads
  bool any_expected = false;
  for (const auto& s : f.stairs) {
    if (!visible(s)) continue;
    any_expected = any_expected || expected(s);
    if (!main || (expected(s) && !expected(*main)) ||
        (expected(s) == expected(*main) && s.visible_steps.size() > main->visible_steps.size()))
      main = &s;
  }
  const StairTruth* match = nullptr;
  if (r.detected) {
    const Eigen::Vector3f o = r.T_camera_stair.translation();
    float best = opt.match_distance;
    for (const auto& s : f.stairs) {
      if (!visible(s)) continue;
      const float d = opt.ignore_pose ? 0.f
                                      : line_distance(o, s.T_camera_stair.translation(),
                                                      s.T_camera_stair.linear().col(0));
      if (d > opt.match_distance) continue;
      // At the right edge but the wrong way (a curb down reported as a step up): no match, and
      // counted apart, since it is the answer that makes someone fall.
      if (truth_goes_up(s) != result_goes_up(r)) {
        e.wrong_direction = true;
        continue;
      }
      if (d <= best) {
        best = d;
        match = &s;
      }
    }
  }
  if (match) e.wrong_direction = false;
  if (match) main = match;
  e.truth_kind = main ? main->kind : StairKind::kNone;
  e.truth_down = main && main->goes_down();
  e.truth_visible_steps = main ? static_cast<int>(main->visible_steps.size()) : 0;
  e.fully_visible = main && expected(*main) && main->first_edge_visible && main->both_ends_visible;
  if (!r.detected) {
    e.outcome = any_expected ? EvalOutcome::kFN : (main ? EvalOutcome::kSkipped : EvalOutcome::kTN);
    return e;
  }
  if (!match) {
    e.false_positive = true;
    e.outcome = any_expected ? EvalOutcome::kFN : EvalOutcome::kFP;
    return e;
  }
  e.outcome = EvalOutcome::kTP;
  const StairTruth& t = *match;
  if (opt.ignore_pose) {
    // No pose to score against; a label may still give the riser and tread (measured by hand).
    if (t.riser_m > 0.f) {
      e.has_riser = true;
      e.riser_err = r.riser_m - t.riser_m;
    }
    if (t.tread_m > 0.f && (t.kind == StairKind::kAscending || t.kind == StairKind::kDescending) &&
        r.levels >= 2 && r.tread_m > 0.f) {
      e.has_tread = true;
      e.tread_err = r.tread_m - t.tread_m;
    }
    return e;
  }
  const Eigen::Vector3f ot = t.T_camera_stair.translation(), op = r.T_camera_stair.translation();
  if (t.riser_m > 0.f) {
    e.has_riser = true;
    e.riser_err = r.riser_m - t.riser_m;
  }
  if ((t.kind == StairKind::kAscending || t.kind == StairKind::kDescending) && r.levels >= 2 &&
      r.tread_m > 0.f) {
    e.has_tread = true;
    e.tread_err = r.tread_m - t.tread_m;
  }
  if (t.both_ends_visible) {
    e.has_width = true;
    e.width_err = r.width_m - t.width_m;
    e.has_edge = true;
    e.edge_pos_err = (op - ot).norm();
  }
  if (t.first_edge_visible) {
    e.has_edge_line = true;
    e.edge_line_err = line_distance(ot, op, r.T_camera_stair.linear().col(0));
  }
  const Eigen::Vector3f yt = t.T_camera_stair.linear().col(1), zt = t.T_camera_stair.linear().col(2);
  Eigen::Vector3f zp = r.T_camera_stair.linear().col(2);
  zp = (zp - zp.dot(yt) * yt).normalized();
  e.yaw_err_deg = rad2deg(std::acos(std::clamp(zp.dot(zt), -1.f, 1.f)));
  return e;
}

void ErrorStats::add(double e) {
  ++n;
  sum += e;
  sum_sq += e * e;
  sum_abs += std::fabs(e);
  max_abs = std::max(max_abs, std::fabs(e));
}

double ErrorStats::sigma() const {
  if (n < 2) return 0.0;
  const double m = mean();
  return std::sqrt(std::max(0.0, (sum_sq - n * m * m) / (n - 1)));
}

void EvalSummary::add(const StairFrameEval& e) {
  ++frames;
  switch (e.outcome) {
    case EvalOutcome::kTP: ++tp; break;
    case EvalOutcome::kTN: ++tn; break;
    case EvalOutcome::kFN: ++fn; break;
    case EvalOutcome::kFP: break;
    case EvalOutcome::kSkipped: ++skipped; break;
  }
  if (e.outcome == EvalOutcome::kFP || e.false_positive) ++fp;
  if (e.wrong_direction) ++wrong_direction;
  // The confusion covers the scored frames (not those skipped): truth kind -> what was reported.
  if (e.outcome != EvalOutcome::kSkipped) ++confusion[e.truth_label()][e.predicted_label()];
  if (e.outcome != EvalOutcome::kSkipped) ++verdicts[to_string(e.outcome)][to_string(e.verdict)];
  if (e.fully_visible && e.outcome == EvalOutcome::kTP) ++full_tp;
  if (e.fully_visible && e.outcome == EvalOutcome::kFN) ++full_fn;
  if (e.outcome != EvalOutcome::kTP) return;
  if (e.kind_exact()) ++kind_correct;
  if (e.kind_ok()) ++kind_ok;
  if (e.has_riser) riser.add(e.riser_err);
  if (e.has_tread) tread.add(e.tread_err);
  if (e.has_width) width.add(e.width_err);
  if (e.has_edge) edge_pos.add(e.edge_pos_err);
  if (e.has_edge_line) edge_line.add(e.edge_line_err);
  yaw.add(e.yaw_err_deg);
}

void StairEvalTable::add(const StairFrameEval& e, const std::string& scene) {
  all.add(e);
  by_kind[to_string(e.truth_kind)].add(e);
  by_scene[scene.empty() ? std::string("unnamed") : scene].add(e);
}

namespace {

std::string summary_json(const EvalSummary& s) {
  std::string o = "{";
  auto kv = [&](const char* k, const std::string& v) {
    if (o.size() > 1) o += ", ";
    o += std::string("\"") + k + "\": " + v;
  };
  kv("frames", json_number(s.frames));
  kv("tp", json_number(s.tp));
  kv("fp", json_number(s.fp));
  kv("tn", json_number(s.tn));
  kv("fn", json_number(s.fn));
  kv("skipped", json_number(s.skipped));
  kv("precision", json_number(s.precision()));
  kv("recall", json_number(s.recall()));
  kv("kind_correct", json_number(s.kind_correct));
  kv("kind_ok", json_number(s.kind_ok));
  kv("wrong_direction", json_number(s.wrong_direction));
  kv("recall_fully_visible", json_number(s.recall_fully_visible()));
  {
    std::string v = "{";
    for (const auto& [outcome, row] : s.verdicts) {
      v += (v.size() > 1 ? ", " : "") + json_quote(outcome) + ": {";
      bool first = true;
      for (const auto& [why, n] : row) {
        v += (first ? "" : ", ") + json_quote(why) + ": " + json_number(n);
        first = false;
      }
      v += "}";
    }
    kv("verdicts", v + "}");
  }
  kv("fully_visible_frames", json_number(s.full_tp + s.full_fn));
  auto stats = [&](const char* name, const ErrorStats& e, const char* unit) {
    const std::string p(name);
    kv((p + "_err_n").c_str(), json_number(e.n));
    kv((p + "_err_mean_" + unit).c_str(), json_number(e.mean_abs()));
    kv((p + "_err_bias_" + unit).c_str(), json_number(e.mean()));
    kv((p + "_err_sigma_" + unit).c_str(), json_number(e.sigma()));
    kv((p + "_err_max_" + unit).c_str(), json_number(e.max_abs));
  };
  stats("riser", s.riser, "m");
  stats("tread", s.tread, "m");
  stats("width", s.width, "m");
  stats("edge_pos", s.edge_pos, "m");
  stats("edge_line", s.edge_line, "m");
  stats("yaw", s.yaw, "deg");
  return o + "}";
}

}  // namespace

std::string StairEvalTable::to_json() const {
  std::string o = summary_json(all);
  o.pop_back();
  o += ", \"confusion\": {";
  bool first_truth = true;
  for (const auto& [truth, row] : all.confusion) {
    o += (first_truth ? "" : ", ") + json_quote(truth) + ": {";
    first_truth = false;
    bool first = true;
    for (const auto& [pred, n] : row) {
      o += (first ? "" : ", ") + json_quote(pred) + ": " + json_number(n);
      first = false;
    }
    o += "}";
  }
  o += "}";
  for (const auto* group : {&by_kind, &by_scene}) {
    o += group == &by_kind ? ", \"by_kind\": {" : ", \"by_scene\": {";
    bool first = true;
    for (const auto& [k, v] : *group) {
      if (!first) o += ", ";
      first = false;
      o += json_quote(k) + ": " + summary_json(v);
    }
    o += "}";
  }
  return o + "}";
}

std::string StairEvalTable::to_text() const {
  std::string o;
  char line[512];
  auto row = [&](const std::string& name, const EvalSummary& s) {
    auto cm = [](const ErrorStats& e) -> std::string {
      if (!e.n) return "      -     ";
      char b[40];
      std::snprintf(b, sizeof b, "%5.2f+-%-5.2f", 100.0 * e.mean_abs(), 100.0 * e.sigma());
      return b;
    };
    char yaw[40] = "      -     ";
    if (s.yaw.n) std::snprintf(yaw, sizeof yaw, "%5.2f+-%-5.2f", s.yaw.mean_abs(), s.yaw.sigma());
    std::snprintf(line, sizeof line, "%-30s %6d %5d %5d %5d %5d %5d %6.3f %6.3f %s %s %s %s %s %s\n",
                  name.c_str(), s.frames, s.tp, s.fp, s.tn, s.fn, s.skipped, s.precision(), s.recall(),
                  cm(s.riser).c_str(), cm(s.tread).c_str(), cm(s.width).c_str(), cm(s.edge_pos).c_str(),
                  cm(s.edge_line).c_str(), yaw);
    o += line;
  };
  std::snprintf(line, sizeof line,
                "%-30s %6s %5s %5s %5s %5s %5s %6s %6s %-12s %-12s %-12s %-12s %-12s %-12s\n", "", "frames",
                "TP", "FP", "TN", "FN", "skip", "prec", "recall", "riser cm", "tread cm", "width cm",
                "edge cm", "edgeline cm", "yaw deg");
  o += line;
  row("all", all);
  o += "by kind (truth):\n";
  for (const auto& [k, v] : by_kind) row("  " + k, v);
  o += "by scene:\n";
  for (const auto& [k, v] : by_scene) row("  " + k, v);
  std::snprintf(line, sizeof line,
                "kind on TPs: %d exact, %d right as far as the user is concerned (direction, one step or a "
                "flight), of %d; %d detections at a true edge going the wrong way\n",
                all.kind_correct, all.kind_ok, all.tp, all.wrong_direction);
  o += line;
  o += "kind confusion (scored frames; rows truth, columns reported):\n";
  std::vector<std::string> cols;
  for (const auto& [truth, row] : all.confusion)
    for (const auto& [pred, n] : row)
      if (std::find(cols.begin(), cols.end(), pred) == cols.end()) cols.push_back(pred);
  std::sort(cols.begin(), cols.end());
  std::snprintf(line, sizeof line, "  %-14s", "");
  o += line;
  for (const auto& c : cols) {
    std::snprintf(line, sizeof line, " %12s", c.c_str());
    o += line;
  }
  o += "\n";
  for (const auto& [truth, row] : all.confusion) {
    std::snprintf(line, sizeof line, "  %-14s", truth.c_str());
    o += line;
    for (const auto& c : cols) {
      const auto it = row.find(c);
      std::snprintf(line, sizeof line, " %12d", it == row.end() ? 0 : it->second);
      o += line;
    }
    o += "\n";
  }
  // The table of why-nots: each miss and each silent frame with the reason the stage gave.
  for (const char* outcome : {"FN", "TN"}) {
    const auto it = all.verdicts.find(outcome);
    if (it == all.verdicts.end()) continue;
    o += std::string("why not (") + outcome + "):";
    for (const auto& [why, n] : it->second) o += " " + std::to_string(n) + " " + why + ";";
    o += "\n";
  }
  o += "errors: mean |error| +- sigma of the signed error, on true positives; width and edge where both ends "
       "are visible,\nedge line = distance of the true edge centre to the estimated edge line.\n";
  return o;
}

}  // namespace stairguide
