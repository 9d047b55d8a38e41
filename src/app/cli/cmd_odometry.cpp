// Odometry commands:
//   stairguide odometry INPUT --out traj.txt [--frames N]
//   stairguide eval-odometry INPUT... [--json] [--frames N]
//   stairguide bench odometry [INPUT] [--frames N] [--json]
// eval-odometry and the bench run this project's DenseOdometry and OpenCV's
// cv::rgbd::RgbdOdometry (the reference) on the same frames in the same process, interleaved
// frame by frame so that both see the same machine load. Both get the same grey image and the
// same policy: the constant-velocity guess as the initial estimate, held when the estimate fails.
#include <unistd.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <memory>
#include <opencv2/imgproc.hpp>
#include <opencv2/rgbd.hpp>
#include <optional>
#include <string>
#include <vector>

#include "cli/bench_util.hpp"
#include "cli/command.hpp"
#include "stairguide/core/nearest_in_time.hpp"
#include "stairguide/capture/dataset.hpp"
#include "stairguide/capture/frame_source.hpp"
#include "stairguide/odometry/dense_odometry.hpp"
#include "stairguide/odometry/trajectory_metrics.hpp"

namespace stairguide::cli {
namespace {

/// OpenCV's RgbdOdometry with the same outer policy as ours (constant-velocity initial guess,
/// held on failure). Its Rt maps points of the source (previous) frame into the destination
/// (current) one: Rt = T_curr_prev.
class ReferenceOdometry {
 public:
  ReferenceOdometry(const CameraIntrinsics& k, const CaptureConfig& capture) {
    const cv::Mat K = (cv::Mat_<double>(3, 3) << k.fx, 0, k.cx, 0, k.fy, k.cy, 0, 0, 1);
    odo_ = cv::rgbd::RgbdOdometry::create(K, capture.min_range, capture.max_range);
  }
  /// Tracks one frame; returns false when RgbdOdometry reports a failure. The images are kept
  /// (as the next source frame) without a copy: pass images nobody overwrites.
  bool track(const cv::Mat& gray, const cv::Mat& depth) {
    cv::Ptr<cv::rgbd::OdometryFrame> f = cv::rgbd::OdometryFrame::create(gray, depth);
    if (!prev_) {
      odo_->prepareFrameCache(f, cv::rgbd::OdometryFrame::CACHE_ALL);
      prev_ = f;
      return true;
    }
    cv::Mat init(4, 4, CV_64FC1), Rt;
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) init.at<double>(r, c) = velocity_(r, c);
    bool ok = false;
    try {
      ok = odo_->compute(prev_, f, Rt, init);
    } catch (const cv::Exception&) {
      ok = false;
    }
    Eigen::Matrix4d T_curr_prev = velocity_.matrix();
    if (ok && Rt.rows == 4 && Rt.cols == 4) {
      for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) T_curr_prev(r, c) = Rt.at<double>(r, c);
      velocity_.matrix() = T_curr_prev;
    } else {
      ok = false;
    }
    Eigen::Isometry3d step;
    step.matrix() = T_curr_prev;
    pose_ = pose_ * step.inverse();
    prev_ = f;
    return ok;
  }
  Pose pose() const { return pose_.cast<float>(); }

 private:
  cv::Ptr<cv::rgbd::RgbdOdometry> odo_;
  cv::Ptr<cv::rgbd::OdometryFrame> prev_;
  Eigen::Isometry3d velocity_ = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d pose_ = Eigen::Isometry3d::Identity();
};

/// One method's run over one or more sequences.
struct MethodStats {
  RpeResult rpe;
  ErrorSums ate;
  std::vector<double> wall_ms, cpu_ms;
  long frames = 0;
  long failures = 0;
  void add(const MethodStats& o) {
    rpe.translation_m_s += o.rpe.translation_m_s;
    rpe.rotation_deg_s += o.rpe.rotation_deg_s;
    ate += o.ate;
    wall_ms.insert(wall_ms.end(), o.wall_ms.begin(), o.wall_ms.end());
    cpu_ms.insert(cpu_ms.end(), o.cpu_ms.begin(), o.cpu_ms.end());
    frames += o.frames;
    failures += o.failures;
  }
};

struct SequenceResult {
  std::string input;
  std::vector<StampedPose> ours_poses, reference_poses;  ///< every frame, truth or not
  std::string description;
  MethodStats ours, reference;
  long with_truth = 0;
  double max_step_m = 0.0, max_step_deg = 0.0;  ///< largest true motion between two used frames
};

/// Ground truth by timestamp from a dataset folder's groundtruth.txt (nearest within 20 ms, as
/// TUM's associate.py), else whatever the source gives per frame (synthetic scenes).
class TruthLookup {
 public:
  explicit TruthLookup(const std::string& input) {
    std::error_code ec;
    const std::filesystem::path gt = std::filesystem::path(input) / "groundtruth.txt";
    if (std::filesystem::is_directory(input, ec) && std::filesystem::exists(gt, ec))
      poses_ = read_groundtruth(gt.string());
  }
  bool from_file() const { return !poses_.empty(); }
  std::optional<Pose> at(double t, const FrameSource& src) const {
    if (poses_.empty()) {
      auto tr = src.truth();
      if (tr) return tr->T_world_camera;
      return std::nullopt;
    }
    if (const TimedPose* best = nearest_in_time(poses_, t, 0.02)) return best->T_world_camera;
    return std::nullopt;
  }

 private:
  std::vector<TimedPose> poses_;
};

/// The grey image both methods get: the frame's own, else converted from colour, else black.
const cv::Mat& grey_of(const RgbdFrame& f, cv::Mat& buf) {
  if (!f.gray.empty()) return f.gray;
  if (!f.color.empty()) {
    cv::cvtColor(f.color, buf, cv::COLOR_BGR2GRAY);
    return buf;
  }
  buf.create(f.depth.rows, f.depth.cols, CV_8UC1);
  buf.setTo(cv::Scalar(0));
  return buf;
}

/// Frames used from a source: from `start`, every `step`-th (step 2 = every other frame dropped),
/// at most `max_frames` of them (0 = all).
struct FrameSelection {
  long max_frames = 0;
  long start = 0;
  long step = 1;
};

SequenceResult run_sequence(const std::string& input, const PipelineConfig& config, const FrameSelection& sel,
                            bool with_reference) {
  SequenceResult out;
  out.input = input;
  std::unique_ptr<FrameSource> src = open_frame_source(input, config.capture);
  out.description = src->describe();
  const TruthLookup truth(input);
  DenseOdometry ours(config.odometry, src->intrinsics());
  std::unique_ptr<ReferenceOdometry> ref;
  if (with_reference) ref = std::make_unique<ReferenceOdometry>(src->intrinsics(), config.capture);
  std::vector<StampedPose> est_ours, est_ref, gt;
  const bool tty = isatty(fileno(stderr));
  RgbdFrame frame, fed;
  cv::Mat grey_buf;
  const long total = src->frame_count();
  long read_count = 0;
  for (long i = 0; sel.max_frames <= 0 || i < sel.max_frames; ++i) {
    ReadResult rr;
    // Skip to the next selected frame (the ones in between are dropped unseen).
    do {
      rr = src->read(frame);
      ++read_count;
    } while (rr.ok() && (read_count - 1 < sel.start || (read_count - 1 - sel.start) % sel.step != 0));
    if (rr.status == ReadStatus::kEnd) break;
    if (!rr.ok()) throw SourceError(rr.message.empty() ? "read failed: " + out.description : rr.message);
    // Both methods get the same grey image, converted outside the timed calls.
    fed.index = frame.index;
    fed.timestamp = frame.timestamp;
    fed.intrinsics = frame.intrinsics;
    fed.depth = frame.depth;
    fed.color = cv::Mat();
    fed.gray = grey_of(frame, grey_buf);
    Timer t;
    const OdometryResult r = ours.track(fed);
    const double ow = t.wall(), oc = t.cpu();
    if (i > 0) {
      out.ours.wall_ms.push_back(ow);
      out.ours.cpu_ms.push_back(oc);
      out.ours.failures += r.ok ? 0 : 1;
    }
    out.ours.frames += 1;
    if (ref) {
      // RgbdOdometry keeps the previous frame's images by reference, and sources reuse their
      // buffers: it gets its own copies (made outside the timed call).
      const cv::Mat g = fed.gray.clone(), d = fed.depth.clone();
      Timer tr;
      const bool ok = ref->track(g, d);
      const double rw = tr.wall(), rc = tr.cpu();
      if (i > 0) {
        out.reference.wall_ms.push_back(rw);
        out.reference.cpu_ms.push_back(rc);
        out.reference.failures += ok ? 0 : 1;
      }
      out.reference.frames += 1;
    }
    out.ours_poses.push_back({frame.timestamp, r.T_world_camera});
    if (ref) out.reference_poses.push_back({frame.timestamp, ref->pose()});
    if (auto g = truth.at(frame.timestamp, *src)) {
      gt.push_back({frame.timestamp, *g});
      est_ours.push_back({frame.timestamp, r.T_world_camera});
      if (ref) est_ref.push_back({frame.timestamp, ref->pose()});
    }
    if (tty && (i % 30 == 0))
      std::fprintf(stderr, "\r%s: frame %ld%s", input.c_str(), read_count,
                   total > 0 ? (" / " + std::to_string(total)).c_str() : "");
  }
  if (tty) std::fprintf(stderr, "\r%*s\r", 60, "");
  out.with_truth = static_cast<long>(gt.size());
  // RPE pairs frames 1 s apart, within 20 ms, or within about half a frame interval when frames
  // are dropped (--step) so that no frame lands within 20 ms of the 1 s mark.
  std::vector<double> spacing;
  for (std::size_t i = 1; i < gt.size(); ++i) {
    spacing.push_back(gt[i].timestamp - gt[i - 1].timestamp);
    const Pose d = gt[i - 1].T_world_camera.inverse() * gt[i].T_world_camera;
    out.max_step_m = std::max(out.max_step_m, static_cast<double>(d.translation().norm()));
    out.max_step_deg =
        std::max(out.max_step_deg, static_cast<double>(rad2deg(Eigen::AngleAxisf(d.linear()).angle())));
  }
  const double max_dt = std::max(0.02, 0.6 * percentile(spacing, 0.5));
  out.ours.rpe = relative_pose_error(est_ours, gt, 1.0, max_dt);
  out.ours.ate = absolute_trajectory_error(est_ours, gt);
  if (ref) {
    out.reference.rpe = relative_pose_error(est_ref, gt, 1.0, max_dt);
    out.reference.ate = absolute_trajectory_error(est_ref, gt);
  }
  return out;
}

void print_method_json(const char* indent, const char* name, const MethodStats& m, bool last) {
  std::printf(
      "%s\"%s\": {\"rpe_trans_rmse_m_s\": %.6f, \"rpe_rot_rmse_deg_s\": %.6f, \"ate_rmse_m\": %.6f, "
      "\"median_ms\": %.3f, \"p95_ms\": %.3f, \"frames\": %ld, \"failures\": %ld, \"median_cpu_ms\": %.3f, "
      "\"p95_cpu_ms\": %.3f, \"rpe_pairs\": %zu}%s\n",
      indent, name, m.rpe.translation_m_s.rmse(), m.rpe.rotation_deg_s.rmse(), m.ate.rmse(),
      percentile(m.wall_ms, 0.5), percentile(m.wall_ms, 0.95), m.frames, m.failures,
      percentile(m.cpu_ms, 0.5), percentile(m.cpu_ms, 0.95), m.rpe.translation_m_s.count, last ? "" : ",");
}

void print_table(const std::string& title, const MethodStats& a, const MethodStats& b) {
  std::printf("%s\n", title.c_str());
  std::printf("  %-26s %14s %14s\n", "", "ours", "RgbdOdometry");
  std::printf("  %-26s %14.4f %14.4f\n", "RPE trans RMSE (m/s)", a.rpe.translation_m_s.rmse(),
              b.rpe.translation_m_s.rmse());
  std::printf("  %-26s %14.3f %14.3f\n", "RPE rot RMSE (deg/s)", a.rpe.rotation_deg_s.rmse(),
              b.rpe.rotation_deg_s.rmse());
  std::printf("  %-26s %14.4f %14.4f\n", "ATE RMSE (m)", a.ate.rmse(), b.ate.rmse());
  std::printf("  %-26s %14.2f %14.2f\n", "median ms/frame (wall)", percentile(a.wall_ms, 0.5),
              percentile(b.wall_ms, 0.5));
  std::printf("  %-26s %14.2f %14.2f\n", "p95 ms/frame (wall)", percentile(a.wall_ms, 0.95),
              percentile(b.wall_ms, 0.95));
  std::printf("  %-26s %14.2f %14.2f\n", "median ms/frame (cpu)", percentile(a.cpu_ms, 0.5),
              percentile(b.cpu_ms, 0.5));
  std::printf("  %-26s %14ld %14ld\n", "frames", a.frames, b.frames);
  std::printf("  %-26s %14ld %14ld\n", "failures", a.failures, b.failures);
  const double ma = percentile(a.wall_ms, 0.5), mb = percentile(b.wall_ms, 0.5);
  if (ma > 0.0) std::printf("  speed-up (median wall): %.2fx\n", mb / ma);
}

/// Writes poses in TUM format; false when the file cannot be written.
bool write_tum(const std::string& path, const std::vector<StampedPose>& poses, const std::string& what) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (!f) return false;
  std::fprintf(f, "# %s\n# T_world_camera, world = first camera (C0)\n# timestamp tx ty tz qx qy qz qw\n",
               what.c_str());
  for (const auto& p : poses) {
    const Eigen::Quaternionf q(p.T_world_camera.linear());
    const Eigen::Vector3f t = p.T_world_camera.translation();
    std::fprintf(f, "%.6f %.7f %.7f %.7f %.7f %.7f %.7f %.7f\n", p.timestamp, t.x(), t.y(), t.z(), q.x(),
                 q.y(), q.z(), q.w());
  }
  return std::fclose(f) == 0;
}

// ---- stairguide odometry INPUT --out traj.txt ---------------------------------------------

int cmd_odometry(Context& ctx) {
  const auto out_path = ctx.option("--out");
  const auto frames = ctx.int_option("--frames", 1, 100000000);
  const bool verbose = ctx.flag("--verbose");
  const auto pos = ctx.positionals(1, 1);
  if (!out_path) throw UsageError("--out FILE is required");
  std::unique_ptr<FrameSource> src = open_frame_source(pos[0], ctx.config.capture);
  std::FILE* f = std::fopen(out_path->c_str(), "w");
  if (!f) {
    std::fprintf(stderr, "stairguide odometry: cannot write %s\n", out_path->c_str());
    return 1;
  }
  std::fprintf(f,
               "# stairguide dense odometry of %s\n# T_world_camera, world = first camera (C0)\n"
               "# timestamp tx ty tz qx qy qz qw\n",
               src->describe().c_str());
  DenseOdometry odo(ctx.config.odometry, src->intrinsics());
  RgbdFrame frame;
  std::vector<double> ms;
  long n = 0, failures = 0;
  int code = 0;
  for (; !frames || n < *frames; ++n) {
    const ReadResult rr = src->read(frame);
    if (rr.status == ReadStatus::kEnd) break;
    if (!rr.ok()) {
      std::fprintf(stderr, "stairguide odometry: %s\n", rr.message.c_str());
      code = 1;
      break;
    }
    Timer t;
    const OdometryResult r = odo.track(frame);
    if (n > 0) ms.push_back(t.wall());
    failures += r.ok ? 0 : 1;
    if (verbose)
      std::fprintf(
          stderr, "%ld %.6f %s%s%s it=%d px=%d inl=%.3f res=%.3f rmsI=%.2f rmsW=%.5f step=%.4fm %.3fdeg\n", n,
          frame.timestamp, r.ok ? "ok" : "FAIL", r.ok ? "" : ": ", r.why, r.iterations, r.pixels_used,
          r.inlier_fraction, r.residual, r.photometric_rms, r.inv_depth_rms,
          r.T_prev_curr.translation().norm(), rad2deg(Eigen::AngleAxisf(r.T_prev_curr.linear()).angle()));
    const Eigen::Quaternionf q(r.T_world_camera.linear());
    const Eigen::Vector3f p = r.T_world_camera.translation();
    std::fprintf(f, "%.6f %.7f %.7f %.7f %.7f %.7f %.7f %.7f\n", frame.timestamp, p.x(), p.y(), p.z(), q.x(),
                 q.y(), q.z(), q.w());
  }
  if (std::fclose(f) != 0) {
    std::fprintf(stderr, "stairguide odometry: error writing %s\n", out_path->c_str());
    return 1;
  }
  std::printf("%s: %ld frames, %ld failures, median %.2f ms, p95 %.2f ms per frame -> %s\n",
              src->describe().c_str(), n, failures, percentile(ms, 0.5), percentile(ms, 0.95),
              out_path->c_str());
  return code;
}

// ---- stairguide eval-odometry INPUT... [--json] ---------------------------------------------

int cmd_eval_odometry(Context& ctx) {
  const bool json = ctx.flag("--json");
  const auto save = ctx.option("--save");
  FrameSelection sel;
  sel.max_frames = ctx.int_option("--frames", 2, 100000000).value_or(0);
  sel.start = ctx.int_option("--start", 0, 100000000).value_or(0);
  sel.step = ctx.int_option("--step", 1, 100).value_or(1);
  const auto inputs = ctx.positionals(1, 1000);
  std::vector<SequenceResult> results;
  for (const auto& in : inputs) {
    results.push_back(run_sequence(in, ctx.config, sel, true));
    if (save) {
      const std::string stem = *save + (inputs.size() > 1 ? "." + std::to_string(results.size()) : "");
      if (!write_tum(stem + ".ours.txt", results.back().ours_poses, "stairguide DenseOdometry of " + in) ||
          !write_tum(stem + ".reference.txt", results.back().reference_poses,
                     "OpenCV RgbdOdometry of " + in)) {
        std::fprintf(stderr, "stairguide eval-odometry: cannot write %s.*.txt\n", stem.c_str());
        return 1;
      }
    }
    if (results.back().with_truth < 3) {
      std::fprintf(stderr,
                   "stairguide eval-odometry: %s has no ground truth for its frames (groundtruth.txt "
                   "within 20 ms, or a synthetic source)\n",
                   in.c_str());
      return 1;
    }
  }
  MethodStats ours, ref;
  for (const auto& r : results) {
    ours.add(r.ours);
    ref.add(r.reference);
  }
  if (json) {
    std::printf("{\n");
    print_method_json("  ", "ours", ours, false);
    print_method_json("  ", "reference", ref, false);
    std::printf("  \"sequences\": [\n");
    for (std::size_t i = 0; i < results.size(); ++i) {
      std::string name;
      for (char c : results[i].input) name += (c == '"' || c == '\\') ? '_' : c;
      std::printf("    {\"input\": \"%s\",\n", name.c_str());
      print_method_json("      ", "ours", results[i].ours, false);
      print_method_json("      ", "reference", results[i].reference, true);
      std::printf("    }%s\n", i + 1 < results.size() ? "," : "");
    }
    std::printf("  ]\n}\n");
    return 0;
  }
  for (const auto& r : results) {
    char title[512];
    std::snprintf(title, sizeof title, "%s (largest true step between used frames: %.1f cm, %.1f deg)",
                  r.description.c_str(), 100.0 * r.max_step_m, r.max_step_deg);
    print_table(title, r.ours, r.reference);
  }
  if (results.size() > 1) print_table("all sequences", ours, ref);
  return 0;
}

// ---- stairguide bench odometry [INPUT] ------------------------------------------------------

int bench_odometry(Context& ctx) {
  const bool json = ctx.flag("--json");
  const auto frames = ctx.int_option("--frames", 2, 100000000);
  const auto pos = ctx.positionals(0, 1);
  const std::string input = pos.empty() ? "synth:ascending_approach_climb:150" : pos[0];
  // Ours and the reference on the same frames, both on this thread.
  FrameSelection sel;
  sel.max_frames = frames.value_or(0);
  const SequenceResult r = run_sequence(input, ctx.config, sel, true);
  const double m1 = percentile(r.ours.wall_ms, 0.5);
  const double mr = percentile(r.reference.wall_ms, 0.5);
  const double c1 = percentile(r.ours.cpu_ms, 0.5), cr = percentile(r.reference.cpu_ms, 0.5);
  if (json) {
    std::printf(
        "{\"input\": \"%s\", \"frames\": %ld, \"ours_median_ms\": %.3f, \"ours_p95_ms\": %.3f, "
        "\"reference_median_ms\": %.3f, \"reference_p95_ms\": %.3f, "
        "\"ours_median_cpu_ms\": %.3f, \"reference_median_cpu_ms\": %.3f, \"speedup\": %.3f, "
        "\"speedup_cpu\": %.3f}\n",
        input.c_str(), r.ours.frames, m1, percentile(r.ours.wall_ms, 0.95), mr,
        percentile(r.reference.wall_ms, 0.95), c1, cr, m1 > 0 ? mr / m1 : 0.0, c1 > 0 ? cr / c1 : 0.0);
    return 0;
  }
  std::printf("odometry on %s (%ld frames; ms per frame, wall clock / thread CPU)\n", r.description.c_str(),
              r.ours.frames);
  std::printf("  ours          median %7.2f / %7.2f  p95 %7.2f\n", m1, c1, percentile(r.ours.wall_ms, 0.95));
  std::printf("  RgbdOdometry  median %7.2f / %7.2f  p95 %7.2f\n", mr, cr,
              percentile(r.reference.wall_ms, 0.95));
  std::printf("  speed-up: %.2fx wall, %.2fx cpu\n", m1 > 0 ? mr / m1 : 0.0, c1 > 0 ? cr / c1 : 0.0);
  return 0;
}

}  // namespace

SG_COMMAND("odometry", "odometry INPUT --out TRAJ.txt [--frames N] [--verbose]",
           "dense RGB-D odometry of a recording; writes the trajectory in TUM format", cmd_odometry);
SG_COMMAND("eval-odometry",
           "eval-odometry INPUT... [--json] [--frames N] [--start I] [--step K] [--save PREFIX]",
           "odometry RPE/ATE/time against ground truth, side by side with OpenCV RgbdOdometry",
           cmd_eval_odometry);
SG_BENCH("odometry", "odometry [INPUT] [--frames N] [--json]",
         "dense odometry vs OpenCV RgbdOdometry (median/p95 ms per frame, speed-up)", bench_odometry);

}  // namespace stairguide::cli
