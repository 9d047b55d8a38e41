// Traversal commands (issue 32):
//   stairguide replay INPUT --out DIR [--frames N] [--drift SCALE_PERCENT,YAW_DEG_PER_S]
//   stairguide eval-traversal DIR... [--json]
// replay runs the daemon's runtime in synchronous mode, as fast as it goes (our DenseOdometry,
// perception with the Manhattan carry, the stairs stage, the traversal tracker and the cue
// decision, exactly as the daemon composes them, plus a second tracker held by the odometry alone
// for comparison) and writes frames.jsonl (a line per frame), trajectory.txt (TUM)
// and traversal.png (the camera's y_S-z_S path against the stair profile with and without the
// correction, the paper's Fig. 19, and the gap at each step, Fig. 20). eval-traversal scores
// those folders against the truth the input carried (synthetic walks, labelled datasets).
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <initializer_list>
#include <string>
#include <utility>
#include <vector>

#include "cli/command.hpp"
#include "stairguide/capture/frame_source.hpp"
#include "stairguide/core/json.hpp"
#include "stairguide/perception/perception.hpp"
#include "stairguide/runtime/logging.hpp"
#include "stairguide/runtime/runtime.hpp"
#include "stairguide/stairs/stairs.hpp"
#include "stairguide/stairs/traversal.hpp"

namespace stairguide::cli {
namespace {

// "2,1" -> 2 % scale error, 1 deg/s yaw.
void parse_drift(const std::string& s, float& scale, float& yaw_rate) {
  char* end = nullptr;
  const double a = std::strtod(s.c_str(), &end);
  if (end == s.c_str() || *end != ',')
    throw UsageError("--drift '" + s + "': expected SCALE_PERCENT,YAW_DEG_PER_S");
  const char* b0 = end + 1;
  const double b = std::strtod(b0, &end);
  if (end == b0 || *end != '\0' || !std::isfinite(a) || !std::isfinite(b) || std::fabs(a) > 50 ||
      std::fabs(b) > 90)
    throw UsageError("--drift '" + s +
                     "': expected SCALE_PERCENT,YAW_DEG_PER_S (|scale| <= 50, |yaw| <= 90)");
  scale = static_cast<float>(a / 100.0);
  yaw_rate = static_cast<float>(b * M_PI / 180.0);
}

struct Sample {
  float cam_y = NAN, cam_z = NAN, u_cam_y = NAN, u_cam_z = NAN, t_cam_y = NAN, t_cam_z = NAN;
  int t_step = -1;
};

// ---- traversal.png: two plots with axes in metres (and centimetres), ticks, legends, a title ----

// A tick step of 1, 2 or 5 times a power of ten giving about `n` ticks over `range`.
double tick_step(double range, int n) {
  const double raw = std::max(1e-6, range / std::max(1, n));
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  for (const double m : {1.0, 2.0, 5.0})
    if (m * p >= raw) return m * p;
  return 10.0 * p;
}

void text(cv::Mat& img, const std::string& s, cv::Point at, double scale = 0.45, int thick = 1) {
  cv::putText(img, s, at, cv::FONT_HERSHEY_SIMPLEX, scale, cv::Scalar(0, 0, 0), thick, cv::LINE_AA);
}
int text_width(const std::string& s, double scale = 0.45) {
  int base = 0;
  return cv::getTextSize(s, cv::FONT_HERSHEY_SIMPLEX, scale, 1, &base).width;
}
std::string tick_label(double v, double step) {
  char b[32];
  std::snprintf(b, sizeof b, step < 0.1 ? "%.2f" : step < 1 ? "%.1f" : "%.0f", std::fabs(v) < 1e-9 ? 0.0 : v);
  return b;
}

// A plot area `box` showing x in [x0, x1] and y in [y0, y1] (data units): frame, ticks and labels.
struct Axes {
  cv::Rect box;
  double x0, x1, y0, y1;
  cv::Point at(double x, double y) const {
    return cv::Point(box.x + static_cast<int>(std::lround((x - x0) / (x1 - x0) * box.width)),
                     box.y + box.height - static_cast<int>(std::lround((y - y0) / (y1 - y0) * box.height)));
  }
  void draw(cv::Mat& img, const std::string& xlabel, const std::string& ylabel, double xscale = 1.0,
            double yscale = 1.0) const {
    const cv::Scalar grid(225, 225, 225), black(0, 0, 0);
    const double xs = tick_step((x1 - x0) * xscale, 8), ys = tick_step((y1 - y0) * yscale, 6);
    for (double v = std::ceil(x0 * xscale / xs) * xs; v <= x1 * xscale + 1e-9; v += xs) {
      const cv::Point p = at(v / xscale, y0);
      cv::line(img, cv::Point(p.x, box.y), cv::Point(p.x, box.y + box.height), grid, 1);
      cv::line(img, p, p + cv::Point(0, 5), black, 1);
      const std::string l = tick_label(v, xs);
      text(img, l, p + cv::Point(-text_width(l) / 2, 20));
    }
    for (double v = std::ceil(y0 * yscale / ys) * ys; v <= y1 * yscale + 1e-9; v += ys) {
      const cv::Point p = at(x0, v / yscale);
      cv::line(img, cv::Point(box.x, p.y), cv::Point(box.x + box.width, p.y), grid, 1);
      cv::line(img, p, p - cv::Point(5, 0), black, 1);
      const std::string l = tick_label(v, ys);
      text(img, l, p + cv::Point(-9 - text_width(l), 5));
    }
    cv::rectangle(img, box, black, 1);
    text(img, xlabel, cv::Point(box.x + box.width / 2 - text_width(xlabel) / 2, box.y + box.height + 40));
    // The y label, written upright to the left of the tick labels.
    const int w = text_width(ylabel), h = 20;
    cv::Mat label(h, w + 4, CV_8UC3, cv::Scalar(255, 255, 255));
    text(label, ylabel, cv::Point(2, 14));
    cv::Mat up;
    cv::rotate(label, up, cv::ROTATE_90_COUNTERCLOCKWISE);
    const int lx = std::max(0, box.x - 62), ly = std::max(0, box.y + box.height / 2 - up.rows / 2);
    if (lx + up.cols <= img.cols && ly + up.rows <= img.rows)
      up.copyTo(img(cv::Rect(lx, ly, up.cols, up.rows)));
  }
};

// A legend box at `corner` (top-left): a sample of each colour and its meaning.
void legend(cv::Mat& img, cv::Point corner, const std::vector<std::pair<cv::Scalar, std::string>>& items,
            bool bars = false) {
  int w = 0;
  for (const auto& it : items) w = std::max(w, text_width(it.second));
  const cv::Rect box(corner.x, corner.y, w + 50, 20 * static_cast<int>(items.size()) + 8);
  cv::rectangle(img, box, cv::Scalar(255, 255, 255), cv::FILLED);
  cv::rectangle(img, box, cv::Scalar(0, 0, 0), 1);
  for (std::size_t i = 0; i < items.size(); ++i) {
    const int y = corner.y + 16 + 20 * static_cast<int>(i);
    if (bars)
      cv::rectangle(img, cv::Point(corner.x + 8, y - 9), cv::Point(corner.x + 34, y + 1), items[i].first,
                    cv::FILLED);
    else
      cv::line(img, cv::Point(corner.x + 8, y - 4), cv::Point(corner.x + 34, y - 4), items[i].first, 2);
    text(img, items[i].second, cv::Point(corner.x + 42, y));
  }
}

void draw_png(const std::string& path, const std::vector<Sample>& s, const TraversalResult& model, int steps,
              float riser, float tread, int direction) {
  const int W = 1000, H = 860;
  cv::Mat img(H, W, CV_8UC3, cv::Scalar(255, 255, 255));
  const cv::Scalar truth_c(200, 120, 0), odo_c(0, 0, 220), corr_c(0, 160, 0), stair_c(0, 0, 0);
  text(img, "stairguide replay: the camera in the stair frame, corrected and by odometry alone",
       cv::Point(20, 28), 0.6, 2);

  // Top: the camera's y_S-z_S path against the stair profile (the paper's Fig. 19), one metre the
  // same length on both axes.
  float zmin = -1.f, zmax = 1.f, ymin = -0.5f, ymax = 2.f;
  for (const Sample& p : s)
    for (const auto& q : {std::make_pair(p.cam_z, p.cam_y), std::make_pair(p.u_cam_z, p.u_cam_y),
                          std::make_pair(p.t_cam_z, p.t_cam_y)})
      if (std::isfinite(q.first) && std::isfinite(q.second)) {
        zmin = std::min(zmin, q.first), zmax = std::max(zmax, q.first);
        ymin = std::min(ymin, q.second), ymax = std::max(ymax, q.second);
      }
  const int n = std::max(steps, model.steps_known);
  const float r = riser > 0 ? riser : model.riser_m, t = tread > 0 ? tread : model.tread_m;
  ymin = std::min(ymin, direction < 0 ? -r * static_cast<float>(n) - 0.1f : -r - 0.1f);
  zmin -= 0.1f, zmax += 0.1f, ymin -= 0.05f, ymax += 0.1f;
  const cv::Rect area(90, 60, W - 120, 420);
  const double sc =
      std::min(area.width / std::max(0.1f, zmax - zmin), area.height / std::max(0.1f, ymax - ymin));
  const int pw = static_cast<int>(sc * (zmax - zmin)), ph = static_cast<int>(sc * (ymax - ymin));
  Axes top{cv::Rect(area.x, area.y + area.height - ph, pw, ph), zmin, zmax, ymin, ymax};
  top.draw(img, "z_S: along the stair from its first edge (m)", "y_S: up (m)");
  if (n > 0 && r > 0 && t > 0) {
    // Stair frame: ascending tread j at y = (j-1) r from z = (j-1) t; descending tread j at -j r.
    std::vector<cv::Point> prof;
    float y = direction > 0 ? -r : 0.f;
    prof.push_back(top.at(zmin, y));
    for (int j = 1; j <= n; ++j) {
      const float z = static_cast<float>(j - 1) * t;
      prof.push_back(top.at(z, y));
      y = direction > 0 ? static_cast<float>(j - 1) * r : -static_cast<float>(j) * r;
      prof.push_back(top.at(z, y));
    }
    prof.push_back(top.at(zmax, y));
    cv::polylines(img, prof, false, stair_c, 2, cv::LINE_AA);
  }
  auto path_of = [&](auto get, const cv::Scalar& col) {
    std::vector<cv::Point> pts;
    for (const Sample& p : s) {
      const auto [z, y] = get(p);
      if (std::isfinite(z) && std::isfinite(y)) pts.push_back(top.at(z, y));
    }
    if (pts.size() > 1) cv::polylines(img, pts, false, col, 2, cv::LINE_AA);
  };
  path_of([](const Sample& p) { return std::make_pair(p.t_cam_z, p.t_cam_y); }, truth_c);
  path_of([](const Sample& p) { return std::make_pair(p.u_cam_z, p.u_cam_y); }, odo_c);
  path_of([](const Sample& p) { return std::make_pair(p.cam_z, p.cam_y); }, corr_c);
  legend(img, cv::Point(top.box.x + 10, top.box.y + 10),
         {{corr_c, "camera, odometry corrected by the live view (eq. 15)"},
          {odo_c, "camera, odometry alone (eq. 14)"},
          {truth_c, "camera, ground truth"},
          {stair_c, "stair profile"}});

  // Bottom: the gap along z_S to the truth the moment each step is reached (Fig. 20; needs the truth).
  const int gtop = 570;
  text(img, "gap along z_S to the truth when each step is reached (the paper's Fig. 20)",
       cv::Point(20, gtop - 20), 0.55, 1);
  double gmax = 0.05;
  std::vector<bool> done(static_cast<std::size_t>(std::max(steps, 0) + 1), false);
  std::vector<std::array<float, 2>> gaps(static_cast<std::size_t>(std::max(steps, 0) + 1), {NAN, NAN});
  for (const Sample& p : s) {
    if (p.t_step < 1 || p.t_step > steps || done[static_cast<std::size_t>(p.t_step)]) continue;
    done[static_cast<std::size_t>(p.t_step)] = true;
    gaps[static_cast<std::size_t>(p.t_step)] = {std::fabs(p.cam_z - p.t_cam_z),
                                                std::fabs(p.u_cam_z - p.t_cam_z)};
    for (const float g : gaps[static_cast<std::size_t>(p.t_step)])
      if (std::isfinite(g)) gmax = std::max(gmax, static_cast<double>(g));
  }
  Axes bottom{cv::Rect(90, gtop, W - 120, H - gtop - 60), 0.5, std::max(steps, 1) + 0.5, 0.0, gmax * 1.5};
  bottom.draw(img, steps > 0 ? "step reached" : "step reached (no truth in this input: no gaps)", "gap (cm)",
              1.0, 100.0);
  const double bw = 0.35;
  for (int k = 1; k <= steps; ++k)
    for (int i = 0; i < 2; ++i) {
      const float g = gaps[static_cast<std::size_t>(k)][static_cast<std::size_t>(i)];
      if (!std::isfinite(g)) continue;
      const double x = k - bw + i * bw;
      cv::rectangle(img, bottom.at(x, g), bottom.at(x + bw, 0.0), i == 0 ? corr_c : odo_c, cv::FILLED);
    }
  legend(img, cv::Point(bottom.box.x + 10, bottom.box.y + 8),
         {{corr_c, "corrected by the live view"}, {odo_c, "odometry alone"}}, true);
  if (!cv::imwrite(path, img)) throw std::runtime_error(path + ": cannot write the PNG");
}

// An output file whose every failure is named. Each frame's line is flushed as it is written, so a
// failed write (a full disk) names the very frame, and the file is cut back to its last whole line:
// what it holds is then every frame before that one, never half a line.
class OutFile {
 public:
  explicit OutFile(std::string path) : path_(std::move(path)), f_(std::fopen(path_.c_str(), "w")) {
    if (!f_) throw std::runtime_error(path_ + ": cannot create (" + std::strerror(errno) + ")");
  }
  ~OutFile() {
    if (f_) std::fclose(f_);
  }
  OutFile(const OutFile&) = delete;
  OutFile& operator=(const OutFile&) = delete;
  const std::string& path() const { return path_; }

  /// Writes `text` (whole lines); `what` names them in the error ("frame 12").
  void write(const std::string& text, const std::string& what) {
    if (std::fwrite(text.data(), 1, text.size(), f_) != text.size() || std::fflush(f_) != 0) {
      const int e = errno;
      if (ftruncate(fileno(f_), whole_) == 0) std::fseek(f_, whole_, SEEK_SET);
      throw std::runtime_error(path_ + ": cannot write " + what + " (" + std::strerror(e) + ")");
    }
    whole_ += static_cast<off_t>(text.size());
  }
  /// Flushes to the disk and closes: a failure here is a failure of the whole file.
  void close() {
    std::FILE* f = f_;
    f_ = nullptr;
    const bool synced = std::fflush(f) == 0 && (fsync(fileno(f)) == 0 || errno == EINVAL || errno == EROFS);
    const int e = errno;
    if (std::fclose(f) != 0 || !synced)
      throw std::runtime_error(path_ + ": cannot write the file to the disk (" +
                               std::strerror(synced ? errno : e) + ")");
  }

 private:
  std::string path_;
  std::FILE* f_ = nullptr;
  off_t whole_ = 0;  // bytes of whole lines written
};

// `--drift`: every increment of the odometry (1 + scale) long, the world turning yaw_rate * t about
// the vertical (the first floor's, in the odometry's world). Applied to the odometry's output
// before any stage uses it, so the tracker, the Manhattan carry and the held tracker all see it.
struct Drift {
  float scale = 0.f, yaw_rate = 0.f;
  Pose drifted = Pose::Identity(), last_raw = Pose::Identity(), raw = Pose::Identity();
  Eigen::Vector3f up_world{0.f, -1.f, 0.f};
  bool have_up = false, have_raw = false;

  bool on() const { return scale != 0.f || yaw_rate != 0.f; }
  void apply(double timestamp, Pose& T_wc) {
    raw = T_wc;
    if (!on()) return;
    const Eigen::Matrix3f Rz =
        Eigen::AngleAxisf(yaw_rate * static_cast<float>(timestamp), up_world).toRotationMatrix();
    const Eigen::Vector3f p =
        have_raw ? Eigen::Vector3f(drifted.translation() +
                                   Rz * ((1.f + scale) * (T_wc.translation() - last_raw.translation())))
                 : T_wc.translation();
    last_raw = T_wc;
    have_raw = true;
    drifted.linear() = Rz * T_wc.linear();
    drifted.translation() = p;
    T_wc = drifted;
  }
  // The vertical from the first floor seen, in the odometry's own (undrifted) world.
  void see_floor(const SceneResult& scene) {
    if (have_up || !scene.floor_found) return;
    up_world =
        (raw.linear() * scene.T_floor_camera.linear().transpose() * Eigen::Vector3f::UnitY()).normalized();
    have_up = true;
  }
};

// One frame's line of frames.jsonl.
std::string frame_line(long n, const runtime::FrameObservation& ob, const TraversalResult& u,
                       const Sample& sm, const StairTruth* st, float t_along) {
  const runtime::OdometryOutput& o = ob.odometry;
  const runtime::PerceptionOutput& p = ob.perception;
  const TraversalResult& r = p.traversal;
  const StairResult& stair = ob.stair;
  auto num = [](double v) { return json_number(v); };
  std::string line =
      "{\"frame\": " + std::to_string(n) + ", \"ts\": " + num(ob.frame.timestamp) +
      ", \"odom_ok\": " + std::to_string(o.ok ? 1 : 0) + ", \"perception\": " + json_quote(p.state) +
      ", \"manhattan\": " +
      json_quote(!p.manhattan_found    ? "none"
                 : p.manhattan_carried ? "carried"
                                       : "seen") +
      ", \"detected\": " + std::to_string(stair.detected ? 1 : 0) +
      ", \"kind\": " + json_quote(to_string(stair.kind)) + ", \"levels\": " + std::to_string(stair.levels) +
      ", \"det_riser_m\": " + num(stair.riser_m) + ", \"det_tread_m\": " + num(stair.tread_m) +
      ", \"state\": " + json_quote(r.ran ? to_string(r.state) : "-") +
      ", \"step\": " + std::to_string(r.step_index) + ", \"left\": " + std::to_string(r.steps_left) +
      ", \"known\": " + std::to_string(r.steps_known) +
      ", \"last_known\": " + std::to_string(r.last_known ? 1 : 0) +
      ", \"in_view\": " + std::to_string(r.in_view ? 1 : 0) + ", \"distance_m\": " + num(r.distance_m) +
      ", \"riser_m\": " + num(r.riser_m) + ", \"tread_m\": " + num(r.tread_m) +
      ", \"width_m\": " + num(r.width_m) + ", \"corr_height_m\": " + num(r.corr_height_m) +
      ", \"corr_along_m\": " + num(r.corr_along_m) + ", \"corr_yaw_rad\": " + num(r.corr_yaw_rad) +
      ", \"has_model\": " + std::to_string(r.direction != 0 ? 1 : 0) + ", \"cam_y\": " + num(sm.cam_y) +
      ", \"cam_z\": " + num(sm.cam_z) + ", \"cue\": " + json_quote(ob.cue.empty() ? "-" : ob.cue) +
      ", \"u_state\": " + json_quote(to_string(u.state)) + ", \"u_step\": " + std::to_string(u.step_index) +
      ", \"u_has_model\": " + std::to_string(u.direction != 0 ? 1 : 0) + ", \"u_cam_y\": " + num(sm.u_cam_y) +
      ", \"u_cam_z\": " + num(sm.u_cam_z);
  if (st)
    line += ", \"truth\": 1, \"t_step\": " + std::to_string(st->user_step) +
            ", \"t_steps\": " + std::to_string(st->steps) +
            ", \"t_direction\": " + std::to_string(st->goes_down() ? -1 : 1) +
            ", \"t_riser_m\": " + num(st->riser_m) + ", \"t_tread_m\": " + num(st->tread_m) +
            ", \"t_along\": " + num(t_along) + ", \"t_cam_y\": " + num(sm.t_cam_y) +
            ", \"t_cam_z\": " + num(sm.t_cam_z);
  else
    line += ", \"truth\": 0";
  line += ", \"ms_odometry\": " + num(o.ms) + ", \"ms_perception\": " + num(p.ms) +
          ", \"ms_traversal\": " + num(r.ms) + "}\n";
  return line;
}

// The daemon's runtime in synchronous mode (runtime.hpp: every frame through odometry, perception
// with the Manhattan carry, stairs, traversal and the cue decision, in order, on this thread): the
// replay's figures are the daemon's by construction. This command only adds what it writes: the
// files, and a second tracker held by the odometry alone, fed what the runtime's stages saw.
int replay(Context& ctx) {
  const auto out = ctx.option("--out");
  const auto max_frames = ctx.int_option("--frames", 1, 100000000);
  Drift drift;
  if (const auto d = ctx.option("--drift")) parse_drift(*d, drift.scale, drift.yaw_rate);
  const auto pos = ctx.positionals(1, 1);
  if (!out) throw UsageError("--out DIR is required");
  std::error_code ec;
  std::filesystem::create_directories(*out, ec);
  if (ec) throw std::runtime_error(*out + ": cannot create the folder (" + ec.message() + ")");
  OutFile jl(*out + "/frames.jsonl"), traj(*out + "/trajectory.txt");
  traj.write(std::string("# timestamp tx ty tz qx qy qz qw (stairguide replay: DenseOdometry") +
                 (drift.on() ? ", drift injected" : "") + ")\n",
             "the header");

  // The cues are decided (frames.jsonl has them) but never played.
  PipelineConfig config = ctx.config;
  config.feedback.audio_enabled = false;
  config.feedback.haptic_enabled = false;
  TraversalConfig held_cfg = config.traversal;
  held_cfg.correct = false;
  TraversalTracker held(held_cfg);

  std::vector<Sample> samples;
  TraversalResult last_model;
  int steps = 0, direction = 1;
  float riser = 0.f, tread = 0.f;
  std::uint64_t track = 0;
  const bool tty = isatty(STDERR_FILENO);
  long n = 0, total = -1;

  runtime::RuntimeOptions opt;
  opt.input = pos[0];
  opt.realtime = false;
  opt.synchronous = true;
  opt.frame_lines = false;
  opt.max_frames = max_frames ? *max_frames : -1;
  if (drift.on())
    opt.pose_filter = [&](const RgbdFrame& f, runtime::OdometryOutput& o) {
      drift.apply(f.timestamp, o.T_world_camera);
    };
  opt.observer = [&](const runtime::FrameObservation& ob) {
    const runtime::OdometryOutput& o = ob.odometry;
    const TraversalResult& r = ob.perception.traversal;
    const Pose& T_wc = o.T_world_camera;
    if (drift.on()) drift.see_floor(ob.scene);
    if (!o.ok) ++track;
    const TraversalResult u = held.update(ob.scene, ob.stair, T_wc, o.ok, ob.frame.timestamp, track);
    if (r.direction != 0) last_model = r;
    Sample sm;
    if (r.direction != 0) {
      const Eigen::Vector3f c = r.T_world_stair.inverse() * T_wc.translation();
      sm.cam_y = c.y(), sm.cam_z = c.z();
    }
    if (u.direction != 0) {
      const Eigen::Vector3f c = u.T_world_stair.inverse() * T_wc.translation();
      sm.u_cam_y = c.y(), sm.u_cam_z = c.z();
    }
    const auto truth = ob.source.truth();
    const StairTruth* st = truth && !truth->stairs.empty() ? &truth->stairs[0] : nullptr;
    float t_along = NAN;
    if (st) {
      const Pose T_sc = st->T_camera_stair.inverse();
      Eigen::Vector3f fwd = T_sc.linear().col(2);
      fwd.y() = 0.f;
      t_along = (T_sc.translation() - config.traversal.body_behind * fwd.normalized()).z();
      sm.t_cam_y = T_sc.translation().y(), sm.t_cam_z = T_sc.translation().z();
      sm.t_step = st->user_step;
      steps = st->steps, riser = st->riser_m, tread = st->tread_m, direction = st->goes_down() ? -1 : 1;
    }
    samples.push_back(sm);
    const std::string what = "frame " + std::to_string(n);
    jl.write(frame_line(n, ob, u, sm, st, t_along), what);
    const Eigen::Quaternionf q(T_wc.linear());
    char tl[200];
    std::snprintf(tl, sizeof tl, "%.6f %.6f %.6f %.6f %.6f %.6f %.6f %.6f\n", ob.frame.timestamp,
                  T_wc.translation().x(), T_wc.translation().y(), T_wc.translation().z(), q.x(), q.y(), q.z(),
                  q.w());
    traj.write(tl, what);
    ++n;
    if (total < 0) total = ob.source.frame_count();
    if (tty && n % 10 == 0) {
      if (total > 0)
        std::fprintf(stderr, "\rreplay: frame %ld of %ld", n, total);
      else
        std::fprintf(stderr, "\rreplay: frame %ld", n);
    }
  };
  runtime::setup_logging("warn");  // the runtime's start and end lines would otherwise go to stdout
  runtime::Runtime rt(config, opt, nullptr);
  rt.start();  // a missing or corrupt input throws, naming it
  const int code = rt.run();
  if (tty && n >= 10) std::fprintf(stderr, "\n");
  // What was read is kept (the files hold every frame before a failure), then the failure is named.
  jl.close();
  traj.close();
  if (code != 0) {
    std::string why = rt.failure().empty() ? pos[0] + ": the replay failed" : rt.failure();
    why +=
        "; " + *out + "/frames.jsonl and trajectory.txt hold the " + std::to_string(n) + " frames before it";
    try {
      if (n > 0) draw_png(*out + "/traversal.png", samples, last_model, steps, riser, tread, direction);
    } catch (const std::exception& e) {
      why += std::string(" (and ") + e.what() + ")";  // the read failure stays the news
    }
    throw std::runtime_error(why);
  }
  if (n > 0) draw_png(*out + "/traversal.png", samples, last_model, steps, riser, tread, direction);
  if (n == 0) throw std::runtime_error(pos[0] + ": no frame could be read");
  std::printf("replay: %ld frames -> %s/frames.jsonl, trajectory.txt, traversal.png\n", n, out->c_str());
  return 0;
}

// ---- eval-traversal ----

bool find_num(const std::string& line, const char* key, double& v) {
  const std::string k = std::string("\"") + key + "\": ";
  const std::size_t p = line.find(k);
  if (p == std::string::npos) return false;
  char* end = nullptr;
  v = std::strtod(line.c_str() + p + k.size(), &end);
  return end != line.c_str() + p + k.size();
}
// Each key's number where the line has it (the others keep their value).
void find_nums(const std::string& line, std::initializer_list<std::pair<const char*, double*>> keys) {
  for (const auto& [key, v] : keys) find_num(line, key, *v);
}
std::string find_str(const std::string& line, const char* key) {
  const std::string k = std::string("\"") + key + "\": \"";
  const std::size_t p = line.find(k);
  if (p == std::string::npos) return "";
  const std::size_t e = line.find('"', p + k.size());
  return line.substr(p + k.size(), e - p - k.size());
}

struct SeqScore {
  int frames_on_stairs = 0, right = 0, phantom = 0, climbed = 0, steps = 0;
  bool count_exact = false, missed_last = true;
  double gap_c = 0, gap_u = 0;
  double fr = 0, ft = 0, sr = 0, st = 0;
  int nf = 0;
};

int eval_traversal(Context& ctx) {
  const bool json = ctx.flag("--json");
  const auto dirs = ctx.positionals(1, 1000);
  std::vector<SeqScore> all;
  for (const std::string& d : dirs) {
    std::ifstream in(d + "/frames.jsonl");
    if (!in)
      throw std::runtime_error(
          d + "/frames.jsonl: cannot read (make it with 'stairguide replay INPUT --out " + d + "')");
    SeqScore s;
    std::vector<bool> gap_done;
    std::string line;
    int lines = 0, with_truth = 0;
    while (std::getline(in, line)) {
      ++lines;
      double v = 0;
      if (!find_num(line, "frame", v))
        throw std::runtime_error(d + "/frames.jsonl:" + std::to_string(lines) + ": not a replay frame line");
      if (!find_num(line, "truth", v) || v == 0) continue;
      ++with_truth;
      double step = 0, t_step = 0, t_steps = 0, t_tread = 0, t_along = 0, known = 0, last_known = 0;
      find_nums(line, {{"step", &step},
                       {"t_step", &t_step},
                       {"t_steps", &t_steps},
                       {"t_tread_m", &t_tread},
                       {"t_along", &t_along},
                       {"known", &known},
                       {"last_known", &last_known}});
      const int N = static_cast<int>(t_steps);
      s.steps = N;
      if (gap_done.size() != static_cast<std::size_t>(N + 1))
        gap_done.assign(static_cast<std::size_t>(N + 1), false);
      const std::string state = find_str(line, "state");
      if (t_step >= 1 && t_along < (N - 1) * t_tread + 0.2) {
        ++s.frames_on_stairs;
        s.right += static_cast<int>(step) == static_cast<int>(t_step);
      }
      if (step > N || known > N) ++s.phantom;
      if (state == "on_stairs" || state == "last_step" || state == "arrived")
        s.climbed = std::max(s.climbed, static_cast<int>(step));
      if (state == "last_step" && t_step < N) s.missed_last = false;
      const int k = static_cast<int>(t_step);
      if (k >= 1 && k <= N && !gap_done[static_cast<std::size_t>(k)]) {
        double cy, cz, uy, uz, ty, tz, hm = 0, uhm = 0;
        find_num(line, "has_model", hm);
        find_num(line, "u_has_model", uhm);
        if (hm > 0 && find_num(line, "cam_y", cy) && find_num(line, "cam_z", cz) &&
            find_num(line, "t_cam_y", ty) && find_num(line, "t_cam_z", tz)) {
          gap_done[static_cast<std::size_t>(k)] = true;
          s.gap_c = std::max(s.gap_c, std::max(std::fabs(cy - ty), std::fabs(cz - tz)));
          if (uhm > 0 && find_num(line, "u_cam_y", uy) && find_num(line, "u_cam_z", uz))
            s.gap_u = std::max(s.gap_u, std::max(std::fabs(uy - ty), std::fabs(uz - tz)));
        }
      }
      double det = 0, in_view = 0, dr = 0, dt = 0, r = 0, t = 0, tr = 0;
      find_nums(line, {{"detected", &det},
                       {"in_view", &in_view},
                       {"det_riser_m", &dr},
                       {"det_tread_m", &dt},
                       {"riser_m", &r},
                       {"tread_m", &t},
                       {"t_riser_m", &tr}});
      if (det > 0 && in_view > 0 && dr > 0 && dt > 0) {
        s.sr += std::fabs(dr - tr), s.st += std::fabs(dt - t_tread), s.fr += std::fabs(r - tr),
            s.ft += std::fabs(t - t_tread);
        ++s.nf;
      }
    }
    if (with_truth == 0)
      throw std::runtime_error(d + "/frames.jsonl: no frame carries a truth to score against");
    s.count_exact = s.climbed == s.steps;
    all.push_back(s);
  }
  SeqScore tot;
  int exact = 0, missed = 0;
  for (const SeqScore& s : all) {
    tot.frames_on_stairs += s.frames_on_stairs, tot.right += s.right, tot.phantom += s.phantom;
    exact += s.count_exact, missed += s.missed_last;
    tot.gap_c = std::max(tot.gap_c, s.gap_c), tot.gap_u = std::max(tot.gap_u, s.gap_u);
    tot.fr += s.fr, tot.ft += s.ft, tot.sr += s.sr, tot.st += s.st, tot.nf += s.nf;
  }
  const double nf = std::max(1, tot.nf);
  const double acc = tot.frames_on_stairs ? static_cast<double>(tot.right) / tot.frames_on_stairs : 0.0;
  if (json) {
    std::printf(
        "{\"sequences\": %zu, \"frames_on_stairs\": %d, \"step_index_accuracy\": %s, \"count_exact\": %d, "
        "\"phantom_steps\": %d, \"missed_last_step\": %d, \"gap_corrected_max_m\": %s, "
        "\"gap_uncorrected_max_m\": %s, \"fused_riser_err_m\": %s, \"fused_tread_err_m\": %s, "
        "\"single_frame_riser_err_m\": %s, \"single_frame_tread_err_m\": %s}\n",
        all.size(), tot.frames_on_stairs, json_number(acc).c_str(), exact, tot.phantom, missed,
        json_number(tot.gap_c).c_str(), json_number(tot.gap_u).c_str(), json_number(tot.fr / nf).c_str(),
        json_number(tot.ft / nf).c_str(), json_number(tot.sr / nf).c_str(), json_number(tot.st / nf).c_str());
    return 0;
  }
  for (std::size_t i = 0; i < all.size(); ++i) {
    const SeqScore& s = all[i];
    std::printf(
        "%s: %d steps, step right %d/%d, climbed %d (%s), phantom frames %d, last step %s, gap max %.1f cm "
        "(odometry only %.1f cm)\n",
        dirs[i].c_str(), s.steps, s.right, s.frames_on_stairs, s.climbed, s.count_exact ? "exact" : "WRONG",
        s.phantom, s.missed_last ? "MISSED" : "announced before it", 100 * s.gap_c, 100 * s.gap_u);
  }
  std::printf(
      "%zu sequences: step index right on %.2f%% of %d frames on the flight, count exact %d, phantom %d, "
      "last step missed %d, gap max %.1f cm corrected / %.1f cm odometry only, riser err fused %.2f / single "
      "%.2f cm, tread err fused %.2f / single %.2f cm\n",
      all.size(), 100 * acc, tot.frames_on_stairs, exact, tot.phantom, missed, 100 * tot.gap_c,
      100 * tot.gap_u, 100 * tot.fr / nf, 100 * tot.sr / nf, 100 * tot.ft / nf, 100 * tot.st / nf);
  return 0;
}

}  // namespace

SG_COMMAND("replay", "replay INPUT --out DIR [--frames N] [--drift SCALE_PERCENT,YAW_DEG_PER_S]",
           "the daemon's pipeline on one thread (as stairguided --sync); frames.jsonl, trajectory.txt, "
           "traversal.png",
           replay);
SG_COMMAND("eval-traversal", "eval-traversal DIR... [--json]",
           "scores replay folders: step index, count, phantom and last steps, drift gap, fused vs "
           "single-frame model",
           eval_traversal);

}  // namespace stairguide::cli
