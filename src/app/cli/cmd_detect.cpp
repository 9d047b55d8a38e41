// `stairguide detect INPUT [--frame N] [--json] [--png OUT.png]`: perception then stair detection
// and modelling (paper sections 3-4) on one frame; the model as text or JSON, drawn like Fig. 13.
#include <chrono>
#include <cstdio>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>

#include "cli/command.hpp"
#include "cli/write_image.hpp"
#include "cli/open_input.hpp"
#include "stairguide/core/json.hpp"
#include "stairguide/capture/frame_source.hpp"
#include "stairguide/perception/perception.hpp"
#include "stairguide/stairs/stair_checks.hpp"
#include "stairguide/eval/stair_draw.hpp"
#include "stairguide/eval/stair_eval.hpp"
#include "stairguide/stairs/stairs.hpp"

namespace stairguide::cli {
namespace {

std::string fmt(double v) { return json_number(v); }
const auto& quote = json_quote;

std::string vec3(const Eigen::Vector3f& v) {
  return "[" + fmt(v.x()) + ", " + fmt(v.y()) + ", " + fmt(v.z()) + "]";
}

std::string mat4(const Pose& T) {
  const Eigen::Matrix4f M = T.matrix();
  std::string o = "[";
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) o += fmt(M(r, c)) + (r == 3 && c == 3 ? "]" : ", ");
  return o;
}

const char* direction_name(int d) { return d > 0 ? "up" : d < 0 ? "down" : "none"; }

int detect(Context& ctx) {
  const bool json = ctx.flag("--json");
  const auto png = ctx.option("--png");
  const long frame_no = ctx.int_option("--frame", 0, 100000000).value_or(0);
  const auto pos = ctx.positionals(1, 1);
  const std::string input = pos[0];

  const std::unique_ptr<FrameSource> source = open_input(input, ctx.config.capture, "stairguide detect");
  if (!source) return 1;
  if (source->frame_count() >= 0 && frame_no >= source->frame_count()) {
    std::fprintf(stderr, "stairguide detect: --frame %ld is past the end of %s (%ld frames)\n", frame_no,
                 source->describe().c_str(), source->frame_count());
    return 2;
  }
  // As in `analyze`: frames before N go through perception too, so that the floor tracking (and
  // the camera height it remembers) sees the same history as in a live run; unless the source's
  // frames are unrelated views.
  Perception perception(ctx.config);
  StairStage stage(ctx.config);
  SceneResult scene;
  StairResult result;
  RgbdFrame frame;
  const bool independent = source->independent_frames();
  auto t0 = std::chrono::steady_clock::now(), t1 = t0;
  for (long i = 0; i <= frame_no; ++i) {
    const ReadResult rr = source->read(frame);
    if (!rr.ok()) {
      std::fprintf(stderr, "stairguide detect: cannot read frame %ld of %s: %s\n", i,
                   source->describe().c_str(), rr.message.empty() ? "end of input" : rr.message.c_str());
      return 1;
    }
    if (independent && i < frame_no) continue;
    t0 = std::chrono::steady_clock::now();
    perception.process(frame, scene);
    t1 = std::chrono::steady_clock::now();
  }
  stage.run(scene, frame.intrinsics, result);
  const double perception_ms = std::chrono::duration<double, std::milli>(t1 - t0).count();
  const auto truth = source->truth();

  if (png) {
    cv::Mat image = draw_classification(frame.color.empty() ? frame.gray : frame.color, frame.depth, scene,
                                        perception.labels(), 0.35f);
    draw_stair_model(image, frame.intrinsics, result);
    if (!write_image(*png, image, "stairguide detect")) return 1;
  }

  if (json) {
    std::string o = "{";
    auto kv = [&](const char* k, const std::string& v) {
      if (o.size() > 1) o += ", ";
      o += std::string("\"") + k + "\": " + v;
    };
    kv("input", quote(input));
    kv("frame", fmt(static_cast<double>(frame_no)));
    kv("floor_found", scene.floor_found ? "true" : "false");
    kv("stair", result.detected ? "true" : "false");
    kv("verdict", quote(to_string(result.verdict)));
    kv("code", quote(result.detected ? code_notes_text(result.code_notes) : ""));
    kv("kind", quote(to_string(result.kind)));
    // The kind alone does not say which way a curb goes; a curb down taken for one up is a fall.
    kv("direction", quote(direction_name(result.direction())));
    kv("levels", fmt(result.levels));
    kv("riser_m", fmt(result.riser_m));
    kv("tread_m", fmt(result.tread_m));
    kv("width_m", fmt(result.width_m));
    kv("T_camera_stair", mat4(result.T_camera_stair));
    kv("edge_left", vec3(result.edge_left));
    kv("edge_right", vec3(result.edge_right));
    kv("method", quote(to_string(result.method)));
    kv("without_floor", result.without_floor ? "true" : "false");
    kv("floor_remembered", result.floor_remembered ? "true" : "false");
    if (!scene.floor_found) {
      // What the floorless route saw: why a stack was placed, left unplaced or refused.
      const FloorlessTrace& t = stage.floorless_trace();
      std::string heights = "[";
      for (float h : t.level_heights) heights += (heights.size() > 1 ? ", " : "") + fmt(h);
      std::string near = "[";
      for (float d : t.near_distances) near += (near.size() > 1 ? ", " : "") + fmt(d);
      kv("floorless", "{\"up_found\": " + std::string(t.up_found ? "true" : "false") +
                          ", \"tilt_deg\": " + fmt(rad2deg(t.tilt)) + ", \"levels\": " + fmt(t.levels) +
                          ", \"stacked\": " + fmt(t.stacked) + ", \"direction\": " + fmt(t.direction) +
                          ", \"level_heights_m\": " + heights + "], \"near_distances_m\": " + near +
                          "], \"first_near_cut\": " + (t.first_near_cut ? "true" : "false") +
                          ", \"first_depth_m\": " + fmt(t.first_depth) +
                          ", \"floor_level\": " + (t.floor_level ? "true" : "false") +
                          ", \"floor_seen\": " + (t.floor_seen ? "true" : "false") +
                          ", \"floor_beside\": " + (t.floor_beside ? "true" : "false") +
                          ", \"landing_split\": " + (t.landing_split ? "true" : "false") +
                          ", \"riser_against\": " + (t.riser_against ? "true" : "false") +
                          ", \"anchored\": " + (t.anchored ? "true" : "false") +
                          ", \"first_index\": " + fmt(t.first_index) + "}");
    }
    kv("candidates", fmt(result.candidates));
    kv("rejected_candidates", fmt(result.rejected_candidates));
    kv("timings_ms", "{\"perception\": " + fmt(perception_ms) +
                         ", \"detection\": " + fmt(result.timings.detection_ms) +
                         ", \"modelling\": " + fmt(result.timings.modelling_ms) +
                         ", \"stairs\": " + fmt(result.timings.total_ms) + "}");
    if (truth) {
      const StairFrameEval e = evaluate_stair_frame(result, *truth);
      std::string stairs = "[";
      for (const auto& st : truth->stairs) {
        if (stairs.size() > 1) stairs += ", ";
        stairs += "{\"kind\": " + quote(to_string(st.kind)) +
                  ", \"direction\": " + quote(st.goes_down() ? "down" : "up") +
                  ", \"riser_m\": " + fmt(st.riser_m) + ", \"tread_m\": " + fmt(st.tread_m) +
                  ", \"width_m\": " + fmt(st.width_m) +
                  ", \"visible_steps\": " + fmt(static_cast<double>(st.visible_steps.size())) +
                  ", \"user_step\": " + fmt(st.user_step) +
                  ", \"T_camera_stair\": " + mat4(st.T_camera_stair) + "}";
      }
      kv("truth", "{\"kind\": " + quote(to_string(e.truth_kind)) +
                      ", \"visible_steps\": " + fmt(e.truth_visible_steps) +
                      ", \"outcome\": " + quote(to_string(e.outcome)) + ", \"stairs\": " + stairs + "]}");
    }
    std::printf("%s}\n", o.c_str());
    return 0;
  }

  std::printf("%s, frame %ld\n", source->describe().c_str(), frame_no);
  if (!scene.floor_found) std::printf("floor: not found (%s)\n", scene.why.c_str());
  if (result.detected) {
    const Eigen::Vector3f o = result.origin();
    std::printf("stair: %s (%s), %d levels seen, riser %.1f cm, tread %.1f cm, width %.1f cm, axes by %s\n",
                to_string(result.kind), direction_name(result.direction()), result.levels,
                100.f * result.riser_m, 100.f * result.tread_m, 100.f * result.width_m,
                to_string(result.method));
    std::printf("building code: %s\n", code_notes_text(result.code_notes).c_str());
    std::printf("first edge centre (camera frame): %.3f %.3f %.3f m\n", o.x(), o.y(), o.z());
  } else {
    std::printf("stair: none (%s)\n", to_string(result.verdict));
  }
  std::printf("step candidates: %d, left out: %d\n", result.candidates, result.rejected_candidates);
  std::printf("timings: perception %.2f ms, detection %.3f ms, modelling %.3f ms\n", perception_ms,
              result.timings.detection_ms, result.timings.modelling_ms);
  if (truth) {
    const StairFrameEval e = evaluate_stair_frame(result, *truth);
    std::printf("truth: %s (%d visible treads) -> %s\n", to_string(e.truth_kind), e.truth_visible_steps,
                to_string(e.outcome));
  }
  return 0;
}

}  // namespace

SG_COMMAND("detect", "detect INPUT [--frame N] [--json] [--png OUT.png]",
           "detect and model the staircase in one frame (paper section 4)", detect);

}  // namespace stairguide::cli
