// `stairguide eval INPUT... [--json]`: stair detection and modelling scored against ground truth.
// Inputs: dataset folders with labels.yaml (per frame, or one label for the whole folder written by
// hand: dataset.hpp, read_folder_label_yaml), "synth:PRESET[:FRAMES[:SEED[:NOISE]]]" (the renderer directly;
// "synth:all:FRAMES:SEED" runs every preset), or a labels.csv of single frames (path,label,kind,note;
// paths relative to the file) whose labels carry no pose. The accuracy claims come from here.
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>
#include <vector>

#include "cli/command.hpp"
#include "stairguide/capture/frame_source.hpp"
#include "stairguide/synth/synth.hpp"
#include "stairguide/perception/perception.hpp"
#include "stairguide/eval/stair_eval.hpp"
#include "stairguide/stairs/drop_detection.hpp"
#include "stairguide/stairs/stairs.hpp"

namespace fs = std::filesystem;

namespace stairguide::cli {
namespace {

bool is_static_preset(const std::string& name) {
  for (const auto& p : synth::presets())
    if (p.name == name) return p.default_frames == 1;
  for (const auto& p : synth::world_presets())
    if (p.name == name) return p.default_frames == 1;
  for (const auto& p : synth::world2_presets())
    if (p.name == name) return p.default_frames == 1;
  for (const auto& p : synth::drop_presets())
    if (p.name == name) return p.default_frames == 1;
  return false;
}

/// Splits one CSV line (double quotes group commas; "" is a quote).
std::vector<std::string> csv_fields(const std::string& line) {
  std::vector<std::string> out(1);
  bool quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        out.back() += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        out.back() += c;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      out.emplace_back();
    } else if (c != '\r') {
      out.back() += c;
    }
  }
  return out;
}

struct Runner {
  Perception perception;
  StairStage stage;
  SceneResult scene;
  StairResult result;
  StairEvalTable table;
  DropConfig drop_config;
  DropEvalTable drops;  // the drop stage as the runtime's perception stage runs it (pipeline.cpp)
  bool progress = isatty(2) != 0;
  bool verbose = false;
  long index = 0;
  explicit Runner(const PipelineConfig& c) : perception(c), stage(c), drop_config(c.drops) {}

  void frame(const RgbdFrame& f, const FrameTruth& truth, bool independent, const StairEvalOptions& opt,
             const std::string& scene_name) {
    if (independent) perception.reset();
    perception.process(f, scene);
    stage.run(scene, f.intrinsics, result);
    const StairFrameEval e = evaluate_stair_frame(result, truth, opt);
    table.add(e, scene_name);
    const DropResult drop = detect_drop(f, scene, drop_config);
    const DropSummary told = summarize_drop(drop, result);
    drops.add(told, truth, scene_name, scene.floor_found);
    if (verbose) {
      std::printf("%-28s %5lu %-8s truth %-11s (%2d treads) got %-11s %2d levels  %s", scene_name.c_str(),
                  static_cast<unsigned long>(truth.index), to_string(e.outcome), to_string(e.truth_kind),
                  e.truth_visible_steps, result.detected ? to_string(result.kind) : "-", result.levels,
                  to_string(result.verdict));
      if (e.outcome == EvalOutcome::kTP)
        std::printf("  riser %+.1f tread %+.1f width %+.1f edge %.1f cm yaw %.2f deg", 100 * e.riser_err,
                    100 * e.tread_err, 100 * e.width_err, 100 * e.edge_line_err, e.yaw_err_deg);
      else if (result.levels > 0)
        // Why a model was refused is often a measure out of the code (a 2 m "tread"), and which floor
        // it stood on: what was measured, and the floor perception gave it.
        std::printf("  measured riser %.1f tread %.1f width %.1f cm, floor %s (camera %.3f m, truth %.3f m)",
                    100 * result.riser_m, 100 * result.tread_m, 100 * result.width_m,
                    scene.floor_found ? (scene.floor_tracked ? "tracked" : "found") : "none",
                    scene.floor_found ? scene.camera_height : 0.f, truth.camera_height_m);
      if (told.detected || truth.drop_in_view)
        std::printf("  drop: truth %s %.2f m %+.0f deg, got %s %.2f m %+.0f deg (%s)",
                    truth.drop_in_view ? "yes" : "no", truth.drop_distance_m, rad2deg(truth.drop_bearing_rad),
                    told.detected ? "yes" : "no", told.distance_m, rad2deg(told.bearing_rad),
                    to_string(drop.verdict));
      std::printf("\n");
    }
    ++index;
  }
};

/// A labelled stream (dataset folder or synthetic preset). Returns false with a message on error.
bool run_source(Runner& run, const std::string& input, const PipelineConfig& config, std::string& error) {
  std::unique_ptr<FrameSource> source;
  try {
    source = open_frame_source(input, config.capture);
  } catch (const SourceError& e) {
    error = e.what();
    return false;
  }
  RgbdFrame frame;
  long n = 0;
  for (;;) {
    const ReadResult rr = source->read(frame);
    if (rr.status == ReadStatus::kEnd) break;
    if (!rr.ok()) {
      error = "input '" + input + "', frame " + std::to_string(n) + ": " + rr.message;
      return false;
    }
    const auto truth = source->truth();
    if (!truth) {
      error =
          "input '" + input +
          "' has no labels (a dataset folder needs labels.yaml: per frame, see 'stairguide synth', or one "
          "'folder:' label written by hand, see the README)";
      return false;
    }
    const std::string scene = truth->scene.empty() ? input : truth->scene;
    // A whole-folder label written by hand has no pose: detections are matched by direction.
    StairEvalOptions opt;
    opt.ignore_pose = !truth->pose_known;
    run.frame(frame, *truth, n == 0 || is_static_preset(truth->scene), opt, scene);
    ++n;
    if (run.progress && n % 20 == 0) std::fprintf(stderr, "\r%s: %ld frames", input.c_str(), n);
  }
  if (run.progress) std::fprintf(stderr, "\r%s: %ld frames\n", input.c_str(), n);
  if (n == 0) {
    error = "input '" + input + "' gave no frames";
    return false;
  }
  return true;
}

/// A labels.csv of single frames (the shared real data): stair/none and a kind, no pose.
bool run_csv(Runner& run, const std::string& path, const PipelineConfig& config, std::string& error) {
  std::ifstream in(path);
  if (!in) {
    error = path + ": cannot open";
    return false;
  }
  const fs::path dir = fs::path(path).parent_path();
  std::string line;
  int line_no = 0, frames = 0;
  StairEvalOptions opt;
  opt.ignore_pose = true;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.empty() || line_no == 1) continue;  // header
    const auto f = csv_fields(line);
    if (f.size() < 2) {
      error = path + ":" + std::to_string(line_no) + ": expected path,label,kind,note";
      return false;
    }
    FrameTruth truth;
    truth.scene =
        "real:" + (f[1] == "stair" ? (f.size() > 2 && !f[2].empty() ? f[2] : std::string("stair")) : "none");
    if (f[1] == "stair") {
      StairTruth s;
      // A curb's kind does not say which way it goes: the file must (curb_up / curb_down).
      const std::string kind = f.size() < 3 ? std::string() : f[2];
      if (kind == "curb_up" || kind == "curb_down") {
        s.kind = StairKind::kCurb;
        s.down = kind == "curb_down";
      } else if (kind == "curb") {
        error =
            path + ":" + std::to_string(line_no) + ": kind 'curb' needs its direction: curb_up or curb_down";
        return false;
      } else if (!parse_stair_kind(kind, s.kind) || s.kind == StairKind::kNone) {
        error = path + ":" + std::to_string(line_no) +
                ": label 'stair' needs a kind (ascending, descending, single_step, curb_up, curb_down)";
        return false;
      } else {
        s.down = s.kind == StairKind::kDescending;
      }
      s.visible_steps = {1, 2};
      s.first_edge_visible = true;
      truth.stairs.push_back(s);
    } else if (f[1] != "none") {
      error = path + ":" + std::to_string(line_no) + ": label must be 'stair' or 'none', got '" + f[1] + "'";
      return false;
    }
    std::unique_ptr<FrameSource> source;
    RgbdFrame frame;
    const std::string file = (dir / f[0]).string();
    try {
      source = open_frame_source(file, config.capture);
    } catch (const SourceError& e) {
      error = path + ":" + std::to_string(line_no) + ": " + e.what();
      return false;
    }
    const ReadResult rr = source->read(frame);
    if (!rr.ok()) {
      error = file + ": " + rr.message;
      return false;
    }
    run.frame(frame, truth, true, opt, truth.scene);
    ++frames;
  }
  if (frames == 0) {
    error = path + ": no frames listed";
    return false;
  }
  return true;
}

int eval(Context& ctx) {
  const bool json = ctx.flag("--json");
  const bool verbose = ctx.flag("--verbose");
  const auto inputs = ctx.positionals(1, 1000);
  Runner run(ctx.config);
  run.verbose = verbose && !json;
  for (const std::string& input : inputs) {
    std::vector<std::string> expanded;
    if (input.rfind("synth:all", 0) == 0 && (input.size() == 9 || input[9] == ':')) {
      for (const auto& p : synth::presets()) expanded.push_back("synth:" + p.name + input.substr(9));
    } else {
      expanded.push_back(input);
    }
    for (const std::string& in : expanded) {
      std::string error;
      const bool csv = in.size() > 4 && in.compare(in.size() - 4, 4, ".csv") == 0;
      if (!(csv ? run_csv(run, in, ctx.config, error) : run_source(run, in, ctx.config, error))) {
        std::fprintf(stderr, "stairguide eval: %s\n", error.c_str());
        return 1;
      }
    }
  }
  if (json) {
    std::string o = run.table.to_json();
    o.pop_back();  // the stairs' object, with the drops' added to it
    std::printf("%s, \"drops\": %s}\n", o.c_str(), run.drops.to_json().c_str());
  } else {
    std::fputs(run.table.to_text().c_str(), stdout);
    std::fputs(run.drops.to_text().c_str(), stdout);
  }
  return 0;
}

}  // namespace

SG_COMMAND("eval", "eval INPUT... [--json] [--verbose]",
           "score stair detection on labelled inputs: dataset folders, synth:PRESET[:FRAMES[:SEED[:NOISE]]], "
           "labels.csv",
           eval);

}  // namespace stairguide::cli
