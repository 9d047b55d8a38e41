// Perception (paper section 3): segmentation, floor, Manhattan frame, classification.
// Part 1 renders its own box worlds (planes only, Kinect noise sigma = 1.425e-3 z^2) with exact
// per-pixel truth; part 2 runs the synthetic presets; part 3 the real frames in ../shared/data.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <limits>
#include <map>
#include <random>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "stairguide/perception/perception.hpp"
#include "manhattan_test_util.hpp"

using namespace stairguide;

namespace {

constexpr float kDeg = 3.14159265f / 180.f;

// ---------------------------------------------------------------------------------------------
// A tiny ray caster: axis-aligned boxes in a stair frame (x across, y forward, z up) rotated by
// a yaw about the world z axis, plus an infinite ground plane. Surface ids: 0 ground, 1000+k the
// top of box k (tread k), 2000+k its front face (riser k), 3000 anything else.
struct Box {
  Eigen::Vector3f lo, hi;
  int id;  // step index, 0 for non-step boxes
};
struct World {
  std::vector<Box> boxes;
  float ground_z = 0.f;
  float stair_yaw = 0.f;  // rad, stair frame vs world about z
  float wall_x = 0.f;     // > 0: walls at x = +-wall_x in the stair frame
};
struct View {
  float height = 1.3f, tilt = 45 * kDeg, roll = 0.f, yaw = 0.f;  // camera in world
  CameraIntrinsics K;
};
struct Render {
  RgbdFrame frame;
  std::vector<int> surface;  // per pixel
  cv::Mat clean;             // noise-free depth
  Eigen::Matrix3f R_world_camera;
  Eigen::Vector3f up_camera;  // world up in camera coordinates
};

Eigen::Matrix3f camera_rotation(const View& v) {
  // Columns: camera axes (x right, y down, z forward) in world (x right, y forward, z up).
  const float t = v.tilt;
  Eigen::Vector3f x(1, 0, 0), y(0, -std::sin(t), -std::cos(t)), z(0, std::cos(t), -std::sin(t));
  const Eigen::Vector3f xr = std::cos(v.roll) * x + std::sin(v.roll) * y;
  const Eigen::Vector3f yr = -std::sin(v.roll) * x + std::cos(v.roll) * y;
  Eigen::Matrix3f R;
  R.col(0) = xr;
  R.col(1) = yr;
  R.col(2) = z;
  return Eigen::AngleAxisf(v.yaw, Eigen::Vector3f::UnitZ()).toRotationMatrix() * R;
}

Render render(const World& w, const View& view, std::uint32_t seed, bool noise = true) {
  Render r;
  const CameraIntrinsics& K = view.K;
  r.frame.intrinsics = K;
  r.frame.depth = cv::Mat(K.height, K.width, CV_32FC1, cv::Scalar(0.f));
  r.clean = cv::Mat(K.height, K.width, CV_32FC1, cv::Scalar(0.f));
  r.surface.assign(static_cast<std::size_t>(K.width) * K.height, -1);
  r.R_world_camera = camera_rotation(view);
  r.up_camera = r.R_world_camera.transpose() * Eigen::Vector3f::UnitZ();
  const Eigen::Matrix3f R_stair_world =
      Eigen::AngleAxisf(-w.stair_yaw, Eigen::Vector3f::UnitZ()).toRotationMatrix();
  const Eigen::Vector3f cam_w(0, 0, view.height);
  const Eigen::Vector3f o = R_stair_world * cam_w;
  std::mt19937 rng(seed);
  std::normal_distribution<float> gauss(0.f, 1.f);
  for (int v = 0; v < K.height; ++v) {
    for (int u = 0; u < K.width; ++u) {
      const Eigen::Vector3f dc((u - K.cx) / K.fx, (v - K.cy) / K.fy, 1.f);
      const Eigen::Vector3f d = R_stair_world * (r.R_world_camera * dc);
      float best = 1e9f;
      int sid = -1;
      if (d.z() < -1e-6f) {
        const float t = (w.ground_z - o.z()) / d.z();
        if (t > 0) best = t, sid = 0;
      }
      if (w.wall_x > 0.f) {
        for (float wx : {-w.wall_x, w.wall_x}) {
          if (std::fabs(d.x()) < 1e-6f) continue;
          const float t = (wx - o.x()) / d.x();
          if (t > 0 && t < best) best = t, sid = 3001;
        }
      }
      for (const Box& b : w.boxes) {
        float t0 = 0.f, t1 = 1e9f;
        int axis0 = -1;
        bool hit = true;
        for (int a = 0; a < 3 && hit; ++a) {
          if (std::fabs(d[a]) < 1e-9f) {
            if (o[a] < b.lo[a] || o[a] > b.hi[a]) hit = false;
            continue;
          }
          float ta = (b.lo[a] - o[a]) / d[a], tb = (b.hi[a] - o[a]) / d[a];
          if (ta > tb) std::swap(ta, tb);
          if (ta > t0) t0 = ta, axis0 = a;
          t1 = std::min(t1, tb);
          if (t0 > t1) hit = false;
        }
        if (!hit || axis0 < 0 || t0 >= best) continue;
        best = t0;
        if (b.id > 0 && axis0 == 2 && d.z() < 0)
          sid = 1000 + b.id;
        else if (b.id > 0 && axis0 == 1 && d.y() > 0)
          sid = 2000 + b.id;
        else
          sid = 3000;
      }
      if (sid < 0 || best > 8.f) continue;
      float z = best;  // dc.z == 1: the ray parameter is the depth
      r.clean.at<float>(v, u) = best;
      if (noise) z += gauss(rng) * 1.425e-3f * z * z;
      if (z < 0.4f || z > 6.f) continue;
      r.frame.depth.at<float>(v, u) = z;
      r.surface[static_cast<std::size_t>(v) * K.width + u] = sid;
    }
  }
  return r;
}

struct StairSpec {
  bool ascending = true;
  int steps = 6;
  float riser = 0.17f, tread = 0.30f, width = 1.2f, ahead = 1.5f;
};

World make_stairs(const StairSpec& s, float yaw, float walls) {
  World w;
  w.stair_yaw = yaw;
  w.wall_x = walls;
  const float hw = 0.5f * s.width;
  if (s.ascending) {
    for (int k = 1; k <= s.steps; ++k)
      w.boxes.push_back({Eigen::Vector3f(-hw, s.ahead + (k - 1) * s.tread, -1.f),
                         Eigen::Vector3f(hw, s.ahead + s.steps * s.tread + 1.f, k * s.riser), k});
  } else {
    const float bottom = -s.steps * s.riser;
    w.ground_z = bottom;
    w.boxes.push_back({Eigen::Vector3f(-20.f, -20.f, bottom - 1.f), Eigen::Vector3f(20.f, s.ahead, 0.f), 0});
    for (int k = 1; k < s.steps; ++k)
      w.boxes.push_back({Eigen::Vector3f(-hw, s.ahead + (k - 1) * s.tread, bottom - 1.f),
                         Eigen::Vector3f(hw, s.ahead + k * s.tread, -k * s.riser), k});
  }
  return w;
}

struct Figures {
  int frames = 0, floor_ok = 0, treads = 0, treads_found = 0, mixed = 0;
  float worst_h = 0, worst_tilt = 0, worst_roll = 0, worst_tread_n = 0, worst_tread_h = 0, worst_yaw = 0;
  std::vector<double> ms, cpu_ms;
};

// Checks one rendered frame; returns the figures into `f`.
void check_frame(const Render& r, const StairSpec& s, float cam_h, float stair_yaw_rel, Perception& P,
                 Figures& f, bool verbose) {
  SceneResult sc;
  timespec c0{}, c1{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &c0);
  P.process(r.frame, sc);
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &c1);
  f.cpu_ms.push_back((c1.tv_sec - c0.tv_sec) * 1e3 + (c1.tv_nsec - c0.tv_nsec) * 1e-6);
  if (getenv("SG_DEBUG")) {
    static int dump = 0;
    cv::Mat img(r.frame.depth.rows, r.frame.depth.cols, CV_8UC3);
    const auto& L = P.labels();
    for (int i = 0; i < img.rows * img.cols; ++i) {
      const int l = L[i];
      const unsigned h = l >= 0 ? static_cast<unsigned>(l + 1) * 2654435761u : 0u;
      img.at<cv::Vec3b>(i / img.cols, i % img.cols) =
          l >= 0 ? cv::Vec3b(h & 255, (h >> 8) & 255, (h >> 16) & 255)
                 : (l == -1 ? cv::Vec3b(0, 0, 0) : cv::Vec3b(255, 255, 255));
    }
    cv::imwrite("/tmp/sgdbg_" + std::to_string(dump) + ".png", img);
    const auto& st = P.segmentation().stats();
    std::printf("dump %d: valid %d planar cells %d seeds %d merged %d dropped %d regions %zu\n", dump,
                st.valid_pixels, st.planar_cells, st.seeds_used, st.regions_merged, st.regions_dropped,
                sc.regions.size());
    cv::Mat d8;
    r.frame.depth.convertTo(d8, CV_8U, 40.0);
    cv::imwrite("/tmp/sgdbg_depth_" + std::to_string(dump++) + ".png", d8);
  }
  f.ms.push_back(sc.timings.total_ms);
  ++f.frames;
  if (!sc.floor_found) {
    if (verbose) std::printf("  frame %d no floor: %s\n", f.frames - 1, sc.why.c_str());
    return;
  }
  float tilt, roll;
  tilt_roll_from_up(r.up_camera, tilt, roll);
  const float eh = std::fabs(sc.camera_height - cam_h);
  const float et = std::fabs(sc.camera_tilt - tilt) / kDeg, er = std::fabs(sc.camera_roll - roll) / kDeg;
  f.worst_h = std::max(f.worst_h, eh);
  f.worst_tilt = std::max(f.worst_tilt, et);
  f.worst_roll = std::max(f.worst_roll, er);
  if (eh <= 0.02f && et <= 1.f && er <= 1.f)
    ++f.floor_ok;
  else if (verbose)
    std::printf("  floor off: h %.3f vs %.3f tilt %.2f roll %.2f\n", sc.camera_height, cam_h, et, er);

  // Treads: truth pixel counts and the region that holds most of each.
  const auto& labels = P.labels();
  std::map<int, int> truth_count;
  std::map<int, std::map<int, int>> overlap;         // tread -> region -> pixels
  std::map<int, std::map<int, int>> region_content;  // region -> surface -> pixels
  for (std::size_t i = 0; i < r.surface.size(); ++i) {
    const int sid = r.surface[i];
    if (sid >= 1000 && sid < 2000) ++truth_count[sid - 1000];
    if (labels[i] >= 0) {
      region_content[labels[i]][sid]++;
      if (sid >= 1000 && sid < 2000) overlap[sid - 1000][labels[i]]++;
    }
  }
  for (auto& [k, n] : truth_count) {
    if (n < 200) continue;
    ++f.treads;
    int best = -1, bn = 0;
    for (auto& [reg, c] : overlap[k])
      if (c > bn) bn = c, best = reg;
    if (best < 0) {
      if (verbose) std::printf("  frame %d tread %d (%d px) not found\n", f.frames - 1, k, n);
      continue;
    }
    const PlaneRegion& R = sc.regions[best];
    const Eigen::Vector3f nf = sc.T_floor_camera.linear() * R.normal;
    const float en = std::acos(std::min(1.f, std::fabs(nf.y()))) / kDeg;
    // Normal error against the true up direction, not the estimated floor.
    const float en_true = std::acos(std::min(1.f, std::fabs(R.normal.dot(r.up_camera)))) / kDeg;
    const float H = (s.ascending ? 1.f : -1.f) * k * s.riser;
    const float eH = std::fabs(R.height - H);
    // Purity: pixels of other surfaces in the region that lie clearly off this tread (more than
    // 2 cm from its plane without noise). Riser pixels right at the nosing are on both planes.
    int total = 0, other_step = 0;
    {
      const auto& L = P.labels();
      const float Hc = cam_h;
      for (std::size_t i = 0; i < L.size(); ++i) {
        if (L[i] != best) continue;
        ++total;
        if (r.surface[i] == 1000 + k) continue;
        const int u = static_cast<int>(i % r.frame.depth.cols), v = static_cast<int>(i / r.frame.depth.cols);
        const float z = r.clean.at<float>(v, u);
        const Eigen::Vector3f pc((u - r.frame.intrinsics.cx) / r.frame.intrinsics.fx * z,
                                 (v - r.frame.intrinsics.cy) / r.frame.intrinsics.fy * z, z);
        const float h = Hc + pc.dot(r.up_camera);
        if (std::fabs(h - H) > 0.02f) ++other_step;
      }
    }
    const bool mixed = other_step > 0.02 * total;
    f.mixed += mixed;
    f.worst_tread_n = std::max(f.worst_tread_n, std::max(en, en_true));
    f.worst_tread_h = std::max(f.worst_tread_h, eH);
    const bool ok =
        en <= 2.f && en_true <= 2.f && eH <= 0.01f && R.cls == RegionClass::kStepCandidate && !mixed;
    f.treads_found += ok;
    if (!ok && verbose && getenv("SG_DEBUG"))
      for (auto& [sid, c] : region_content[best]) std::printf("    surface %d: %d\n", sid, c);
    if (!ok && verbose)
      std::printf(
          "  frame %d tread %d (%d px, region %d px) n-err %.2f/%.2f H %.3f vs %.3f cls %s mixed %d/%d\n",
          f.frames - 1, k, n, R.pixel_count, en, en_true, R.height, H, to_string(R.cls), other_step, total);
  }
  if (sc.manhattan_found) {
    float e = std::fmod(std::fabs(sc.manhattan_yaw - stair_yaw_rel), 90 * kDeg);
    e = std::min(e, 90 * kDeg - e) / kDeg;
    f.worst_yaw = std::max(f.worst_yaw, e);
  } else {
    f.worst_yaw = 999;
  }
}

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

void print_figures(const char* name, const Figures& f, bool with_yaw) {
  std::printf(
      "%s: frames %d floor ok %d treads %d/%d mixed %d worst h %.3f tilt %.2f roll %.2f tread n %.2f "
      "tread H %.3f",
      name, f.frames, f.floor_ok, f.treads_found, f.treads, f.mixed, f.worst_h, f.worst_tilt, f.worst_roll,
      f.worst_tread_n, f.worst_tread_h);
  if (with_yaw) std::printf(" yaw %.2f", f.worst_yaw);
  std::printf(" median %.2f ms (cpu %.2f)\n", median(f.ms), median(f.cpu_ms));
}

void run_rendered(bool ascending, std::uint32_t seed0, int frames, Figures& f) {
  std::mt19937 rng(seed0);
  std::uniform_real_distribution<float> U(0.f, 1.f);
  Perception P;
  for (int i = 0; i < frames; ++i) {
    StairSpec s;
    s.ascending = ascending;
    s.steps = 4 + static_cast<int>(U(rng) * 8.99f);
    s.riser = 0.15f + 0.03f * U(rng);
    s.tread = 0.28f + 0.04f * U(rng);
    s.width = 0.9f + 0.7f * U(rng);
    s.ahead = 0.8f + 2.2f * U(rng);
    View v;
    v.height = 1.0f + 0.6f * U(rng);
    v.tilt = (30.f + 30.f * U(rng)) * kDeg;
    v.roll = (-3.f + 6.f * U(rng)) * kDeg;
    v.yaw = (-25.f + 50.f * U(rng)) * kDeg;
    const World w = make_stairs(s, 0.f, s.width * 0.5f + 0.02f);
    const Render r = render(w, v, seed0 * 1000 + i);
    P.reset();  // independent views
    // Stair direction relative to the camera's forward direction, about up (+ = left).
    check_frame(r, s, v.height, -v.yaw, P, f, true);
  }
}

}  // namespace

TEST(PerceptionRendered, AscendingStairs) {
  Figures f;
  run_rendered(true, 11, 12, f);
  print_figures("ascending", f, true);
  // One frame has a floor strip no wider than the staircase right ahead: reported as no floor.
  EXPECT_GE(f.floor_ok, f.frames - 1);
  EXPECT_EQ(f.treads_found, f.treads);
  EXPECT_EQ(f.mixed, 0);
  EXPECT_LE(f.worst_yaw, 2.f);
}

TEST(PerceptionRendered, DescendingStairs) {
  Figures f;
  run_rendered(false, 23, 12, f);
  print_figures("descending", f, false);
  EXPECT_EQ(f.floor_ok, f.frames);
  EXPECT_GE(f.treads_found, 0.7 * f.treads);  // far descending treads: a known gap (see report)
  EXPECT_LE(f.mixed, 5);
}

// ---------------------------------------------------------------------------------------------
// The synthetic presets (synth/synth.hpp), fixed seeds.
#include "stairguide/synth/synth.hpp"

namespace {

struct PresetFigures {
  int frames = 0, floor_visible = 0, floor_ok = 0, floor_wrong_plane = 0;
  int treads = 0, treads_ok = 0, mixed = 0, manhattan_checked = 0, manhattan_ok = 0;
  int manhattan_wrong = 0;  // frames off by more than 2 degrees with a staircase in view
  int manhattan_off = 0;    // frames off by more than 2 degrees with a wall or riser in view
  // Tread failures by kind: no horizontal region at its height, or found with a normal, a
  // height or a class out of bounds (one tread may fail several ways).
  int tread_missed = 0, tread_bad_normal = 0, tread_bad_height = 0, tread_bad_class = 0;
  float worst_h = 0, worst_tilt = 0, worst_roll = 0, worst_n = 0, worst_H = 0, worst_yaw = 0;
  std::vector<double> cpu_ms;
};

// A wall or riser this many pixels (with depth readings) is "visible" for the Manhattan figure.
constexpr int kMinWallOrRiserPixels = 200;

using sg_test::wrap45;

// Height of the tread surface above the stair's base floor, and in the stair frame.
float tread_height(const StairTruth& s, int k) {
  switch (s.kind) {
    case StairKind::kAscending: return k * s.riser_m;
    case StairKind::kDescending: return -k * s.riser_m;
    case StairKind::kSingleStep: return s.riser_m;
    default: return 0.f;
  }
}
bool stair_goes_up(const StairTruth& s) {
  return s.kind == StairKind::kAscending || s.kind == StairKind::kSingleStep;
}

// Static presets: `frames` independent views. Sequences: windows of `window` consecutive frames
// spread over the whole run, so the approach, the first step and the climb or descent are all
// seen. Tracking starts cold at the first window and carries over the gaps between windows (as
// for a sensor that dropped frames for a few seconds): the camera height remembered from the
// floor seen earlier is what tells the tread underfoot from the treads below on a descent.
void run_preset(const std::string& preset, long frames, std::uint32_t seed, long sequence_length,
                PresetFigures& F, const synth::SynthOptions& options = {}) {
  const long window = 8;
  std::vector<long> indices;
  if (sequence_length > 1) {
    for (long w = 0; w < frames / window; ++w) {
      const long start = w * (sequence_length - window) / std::max(1L, frames / window - 1);
      for (long i = 0; i < window; ++i) indices.push_back(start + i);
    }
  } else {
    for (long i = 0; i < frames; ++i) indices.push_back(i);
  }
  Perception P;
  RgbdFrame frame;
  SceneResult sc;
  FrameTruth truth_storage;
  const FrameTruth* truth = &truth_storage;
  for (std::size_t n = 0; n < indices.size(); ++n) {
    synth::render_preset_frame(preset, indices[n], seed, options, frame, truth_storage);
    if (sequence_length <= 1 || n == 0) P.reset();
    timespec c0{}, c1{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &c0);
    P.process(frame, sc);
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &c1);
    F.cpu_ms.push_back((c1.tv_sec - c0.tv_sec) * 1e3 + (c1.tv_nsec - c0.tv_nsec) * 1e-6);
    ++F.frames;
    const Eigen::Matrix3f Rwc = truth->T_world_camera.linear();
    const Eigen::Vector3f up = Rwc.row(2).transpose();
    if (sc.floor_found) {
      // Never a tread or a table: the floor plane must be the one the camera height refers to.
      if (std::fabs(sc.camera_height - truth->camera_height_m) > 0.05f) {
        ++F.floor_wrong_plane;
        std::printf("  %s #%llu: floor at %.3f m, truth %.3f m\n", preset.c_str(),
                    static_cast<unsigned long long>(truth->index), sc.camera_height, truth->camera_height_m);
        if (getenv("SG_DEBUG_FLOOR")) {
          for (const auto& R : sc.regions) {
            if (R.normal.dot(up) < std::cos(15 * kDeg)) continue;
            float nearest = 1e9f;
            for (const auto& q : R.points) {
              const float np = R.normal.dot(q);
              nearest = std::min(nearest, std::sqrt(std::max(0.f, q.squaredNorm() - np * np)));
            }
            std::printf("    region %d: offset %.3f px %d area %.3f near %.2f floor_visible %d\n", R.id,
                        R.offset, R.pixel_count, R.area, nearest, truth->floor_visible);
          }
          cv::Mat d8;
          frame.depth.convertTo(d8, CV_8U, 50.0);
          cv::imwrite("/tmp/sgfloor_" + preset + "_" + std::to_string(truth->index) + ".png", d8);
        }
      }
    }
    if (truth->floor_visible) {
      ++F.floor_visible;
      if (sc.floor_found) {
        const float eh = std::fabs(sc.camera_height - truth->camera_height_m);
        const float et = std::fabs(sc.camera_tilt - truth->camera_tilt_rad) / kDeg;
        const float er = std::fabs(sc.camera_roll - truth->camera_roll_rad) / kDeg;
        if (eh < 0.05f) {
          F.worst_h = std::max(F.worst_h, eh);
          F.worst_tilt = std::max(F.worst_tilt, et);
          F.worst_roll = std::max(F.worst_roll, er);
        }
        if (eh <= 0.02f && et <= 1.f && er <= 1.f) ++F.floor_ok;
      } else {
        std::printf("  %s #%llu: floor visible but not found (%s)\n", preset.c_str(),
                    static_cast<unsigned long long>(truth->index), sc.why.c_str());
      }
    }
    // Manhattan (issue 3: "yaw error <= 2 degrees where at least one wall or riser is visible"):
    // k_M against the world's axes or the staircase's own, modulo 90 degrees. Required on every
    // view where the floor is in view and a wall or riser face shows
    // kMinWallOrRiserPixels with depth readings (a view without a frame counts as a miss), and
    // checked wherever else a frame is reported with a staircase in view.
    const bool wall_or_riser = truth->floor_visible && truth->wall_or_riser_pixels >= kMinWallOrRiserPixels;
    const float yaw_err = sg_test::manhattan_yaw_error_deg(sc, *truth);  // degrees; < 0: no frame
    if (wall_or_riser) {
      ++F.manhattan_checked;
      if (yaw_err >= 0.f && yaw_err <= 2.f)
        ++F.manhattan_ok;
      else if (yaw_err < 0.f)
        std::printf("  %s #%llu: no Manhattan frame, a wall or riser of %d px in view (%s)\n", preset.c_str(),
                    static_cast<unsigned long long>(truth->index), truth->wall_or_riser_pixels,
                    sc.manhattan_why.c_str());
      if (getenv("SG_DEBUG_MANHATTAN") && sc.floor_found && !(yaw_err >= 0.f && yaw_err <= 2.f)) {
        // The vertical regions: size, depth, and yaw error against the truth (what voted).
        for (const PlaneRegion& R : sc.regions) {
          const Eigen::Vector3f nw = Rwc * R.normal;
          if (std::fabs(nw.z()) > std::sin(10 * kDeg)) continue;
          float e = std::fabs(wrap45(std::atan2(nw.y(), nw.x())));
          for (const StairTruth& st : truth->stairs) {
            const Eigen::Vector3f zs = Rwc * st.T_camera_stair.linear().col(2);
            e = std::min(e, std::fabs(wrap45(std::atan2(nw.y(), nw.x()) - std::atan2(zs.y(), zs.x()))));
          }
          std::printf("    vertical: %d px area %.3f m2 %.2f x %.2f m at %.2f m, yaw off %.2f deg\n",
                      R.pixel_count, R.area, R.rect_length_major, R.rect_length_minor, R.centroid.z(),
                      e / kDeg);
        }
      }
    }
    if (yaw_err >= 0.f && (wall_or_riser || truth->any_stair_visible())) {
      F.worst_yaw = std::max(F.worst_yaw, yaw_err);
      if (yaw_err > 2.f) {
        F.manhattan_wrong += truth->any_stair_visible();
        F.manhattan_off += wall_or_riser;
        std::printf("  %s #%llu: Manhattan yaw off by %.2f deg (wall or riser %d px)\n", preset.c_str(),
                    static_cast<unsigned long long>(truth->index), yaw_err, truth->wall_or_riser_pixels);
      }
    }
    if (!sc.floor_found) continue;
    // Treads: the largest horizontal region at each visible tread's height, inside the staircase.
    for (const StairTruth& st : truth->stairs) {
      const Pose T_sc = st.T_camera_stair.inverse();
      const float base_y = stair_goes_up(st) ? st.riser_m : 0.f;  // origin height above the base
      // The staircase's base floor relative to the user's floor (0 for static views).
      for (std::size_t i = 0; i < st.visible_steps.size(); ++i) {
        const int k = st.visible_steps[i];
        if (st.visible_pixels[i] < 200) continue;
        float Hs = tread_height(st, k);
        int best = -1;
        // A curb goes up (origin on the raised level) or down (origin at the user's edge, the
        // other level one riser below): try both.
        const std::vector<std::pair<float, float>> options =
            st.kind == StairKind::kCurb
                ? std::vector<std::pair<float, float>>{{st.riser_m, st.riser_m}, {-st.riser_m, 0.f}}
                : std::vector<std::pair<float, float>>{{Hs, base_y}};
        float by = base_y;
        for (const auto& [h_opt, b_opt] : options) {
          for (int r = 0; r < static_cast<int>(sc.regions.size()); ++r) {
            const PlaneRegion& R = sc.regions[r];
            if (std::fabs(R.normal.dot(up)) < std::cos(10 * kDeg)) continue;
            const Eigen::Vector3f cs = T_sc * R.centroid;
            if (std::fabs(cs.y() + b_opt - h_opt) > 0.05f) continue;
            // The landing or floor after the last riser (tread `steps`) is wider than the flight,
            // and the truth counts its pixels beside the flight too (on a descent the part right
            // after the last riser hides behind the treads above, and what is seen of the lower
            // floor is beside the flight): it is matched by a region at its height reaching beyond
            // the last riser (beside an open-sided descent the lower floor is one region from
            // beside the flight to beyond it). Treads of the flight must lie within its width.
            if (k == st.steps && st.kind != StairKind::kCurb) {
              const float last_riser = (st.steps - 1) * st.tread_m - 0.05f;
              if (cs.z() < last_riser) {
                int beyond = 0;
                for (const Eigen::Vector3f& q : R.points) beyond += (T_sc * q).z() >= last_riser;
                if (beyond < std::min(100, st.visible_pixels[i] / 4)) continue;
              }
            } else if (std::fabs(cs.x()) > 0.5f * st.width_m + 0.1f) {
              continue;
            }
            if (best < 0 || R.pixel_count > sc.regions[best].pixel_count) best = r, Hs = h_opt, by = b_opt;
          }
          if (best >= 0) break;
        }
        const float user_base_k = truth->camera_height_m - (T_sc * Eigen::Vector3f::Zero()).y() - by;
        // The level the user stands on (a curb's upper level, the landing reached at the top of a
        // climb, the floor at the foot of a descent) is the floor, not a step.
        if ((best >= 0 || st.kind != StairKind::kCurb) && std::fabs(user_base_k + Hs) < 0.05f) continue;
        ++F.treads;
        if (best < 0) {
          ++F.tread_missed;
          std::printf("  %s #%llu: tread %d (%d px) not found\n", preset.c_str(),
                      static_cast<unsigned long long>(truth->index), k, st.visible_pixels[i]);
          if (getenv("SG_DEBUG_TREADS")) {  // what lies at the tread's height instead
            for (const PlaneRegion& R : sc.regions) {
              const Eigen::Vector3f cs = T_sc * R.centroid;
              if (std::fabs(cs.y() + by - Hs) > 0.15f) continue;
              std::printf("    near: %d px n-err %.2f dy %.3f x %.2f z %.2f cls %s\n", R.pixel_count,
                          std::acos(std::min(1.f, std::fabs(R.normal.dot(up)))) / kDeg, cs.y() + by - Hs,
                          cs.x(), cs.z(), to_string(R.cls));
            }
          }
          continue;
        }
        const PlaneRegion& R = sc.regions[best];
        const float en = std::acos(std::min(1.f, std::fabs(R.normal.dot(up)))) / kDeg;
        const float H_true = Hs + user_base_k;
        const float eH = std::fabs(R.height - H_true);
        F.worst_n = std::max(F.worst_n, en);
        F.worst_H = std::max(F.worst_H, eH);
        const bool ok = en <= 2.f && eH <= 0.01f && R.cls == RegionClass::kStepCandidate;
        F.treads_ok += ok;
        F.tread_bad_normal += en > 2.f;
        F.tread_bad_height += eH > 0.01f;
        F.tread_bad_class += R.cls != RegionClass::kStepCandidate;
        if (!ok)
          std::printf("  %s #%llu: tread %d (%d px): region %d px n-err %.2f deg H %.3f vs %.3f cls %s\n",
                      preset.c_str(), static_cast<unsigned long long>(truth->index), k, st.visible_pixels[i],
                      R.pixel_count, en, R.height, H_true, to_string(R.cls));
      }
      // Mixing: a horizontal region on the staircase whose points spread over two levels.
      for (const PlaneRegion& R : sc.regions) {
        if (std::fabs(R.normal.dot(up)) < std::cos(10 * kDeg) || R.points.size() < 20) continue;
        const Eigen::Vector3f cs = T_sc * R.centroid;
        if (std::fabs(cs.x()) > 0.5f * st.width_m || cs.z() < 0.05f || cs.z() > st.steps * st.tread_m)
          continue;
        int off = 0;
        for (const auto& q : R.points)
          if (std::fabs((T_sc * q).y() - cs.y()) > 0.03f + 3 * 1.425e-3f * q.z() * q.z()) ++off;
        if (off > 0.03 * R.points.size()) {
          ++F.mixed;
          std::printf("  %s #%llu: region of %d px mixes levels (%d/%zu points off)\n", preset.c_str(),
                      static_cast<unsigned long long>(truth->index), R.pixel_count, off, R.points.size());
        }
      }
    }
  }
}

void print(const std::string& name, const PresetFigures& F) {
  std::printf(
      "%-28s frames %3d floor %d/%d (wrong plane %d) h %.3f tilt %.2f roll %.2f | treads %d/%d n %.2f H %.3f "
      "(missed %d, normal %d, height %d, class %d) mixed %d | manhattan %d/%d (wrong %d) yaw %.2f | cpu "
      "median %.2f ms\n",
      name.c_str(), F.frames, F.floor_ok, F.floor_visible, F.floor_wrong_plane, F.worst_h, F.worst_tilt,
      F.worst_roll, F.treads_ok, F.treads, F.worst_n, F.worst_H, F.tread_missed, F.tread_bad_normal,
      F.tread_bad_height, F.tread_bad_class, F.mixed, F.manhattan_ok, F.manhattan_checked, F.manhattan_wrong,
      F.worst_yaw, median(F.cpu_ms));
}

}  // namespace

// Sums over every preset, checked once all have run (issue 3's figures are over all presets).
struct Totals {
  PresetFigures all;
  int presets = 0;
  static Totals& get() {  // static presets
    static Totals t;
    return t;
  }
  static Totals& sequences() {
    static Totals t;
    return t;
  }
  void add(const PresetFigures& F) {
    ++presets;
    all.frames += F.frames;
    all.floor_visible += F.floor_visible;
    all.floor_ok += F.floor_ok;
    all.floor_wrong_plane += F.floor_wrong_plane;
    all.treads += F.treads;
    all.treads_ok += F.treads_ok;
    all.tread_missed += F.tread_missed;
    all.tread_bad_normal += F.tread_bad_normal;
    all.tread_bad_height += F.tread_bad_height;
    all.tread_bad_class += F.tread_bad_class;
    all.mixed += F.mixed;
    all.manhattan_checked += F.manhattan_checked;
    all.manhattan_ok += F.manhattan_ok;
    all.manhattan_wrong += F.manhattan_wrong;
    all.manhattan_off += F.manhattan_off;
  }
};

class TotalsCheck : public ::testing::Environment {
 public:
  void TearDown() override {
    int statics = 0;
    for (const auto& p : synth::presets()) statics += p.default_frames <= 1;
    if (Totals::get().presets + Totals::sequences().presets < static_cast<int>(synth::presets().size()))
      return;  // filtered
    for (int k = 0; k < 2; ++k) {
      const PresetFigures& A = (k == 0 ? Totals::get() : Totals::sequences()).all;
      std::printf(
          "ALL %s: frames %d floor %d/%d (%.1f %%) wrong plane %d | treads %d/%d (%.1f %%) (missed %d, "
          "normal %d, height %d, class %d) mixed %d | manhattan %d/%d (wrong %d, off with a wall in view "
          "%d)\n",
          k == 0 ? "STATIC PRESETS" : "SEQUENCE WINDOWS", A.frames, A.floor_ok, A.floor_visible,
          100.0 * A.floor_ok / std::max(1, A.floor_visible), A.floor_wrong_plane, A.treads_ok, A.treads,
          100.0 * A.treads_ok / std::max(1, A.treads), A.tread_missed, A.tread_bad_normal, A.tread_bad_height,
          A.tread_bad_class, A.mixed, A.manhattan_ok, A.manhattan_checked, A.manhattan_wrong,
          A.manhattan_off);
    }
    const PresetFigures& A = Totals::get().all;
    EXPECT_EQ(Totals::get().presets, statics);
    EXPECT_EQ(A.floor_wrong_plane, 0) << "never a tread or a table taken for the floor";
    EXPECT_EQ(Totals::sequences().all.floor_wrong_plane, 0)
        << "never a tread below the user taken for the floor";
    // Issue 3 asks 99 % (measured 427/428; 424/428 before a strip going on beside the flight or
    // deeper than its treads was told from a first tread). The miss is a frame where a floor strip
    // no deeper than a tread, with a tread one riser above it, fills the bottom of the view: in one
    // frame that is also what the first tread of a staircase looks like, and the detector says "no
    // floor" rather than count one step too few (in use, tracking from earlier frames decides).
    EXPECT_GE(A.floor_ok, 0.99 * A.floor_visible) << "floor found where it is visible";
    EXPECT_EQ(Totals::sequences().all.floor_ok, Totals::sequences().all.floor_visible)
        << "floor found where it is visible, walking sequences";
    // Every tread with >= 200 pixels that keep a depth reading: 514/514 measured (502/502 before
    // the floor was found on 3 more views of ascending flights, whose treads now count). 501/502 before
    // a tread's sliver under the shadow of the next nosing was split off its riser (nosing_landing
    // #11); 498/502 before tread/riser crease strips and tread slivers at the top border were
    // split off, and before the landing after the last riser was matched beside the flight;
    // 485/537 before thin strips were seeded on dominant directions and before the truth left out
    // tread pixels the sensor gives no depth for (grazing incidence, mixed pixels behind nosings).
    EXPECT_EQ(A.treads_ok, A.treads) << "every tread found over all static presets (measured 514/514)";
    // Manhattan, issue 3's reading: a frame within 2 deg on every view with the floor and a wall
    // or riser (>= 200 px, >= 8 cm tall: an open riser's tread edge is none) in view. Measured
    // 222/222 static views, 32/40 walking; no frame is ever more than 2 deg off with a staircase
    // in view, and none with only a wall in view. The walking misses, all without a frame: a
    // 450 px strip of wall at the top of the view while turning (8 views: in the daemon the
    // odometry carries the frame held in the world through them, see test_walk_manhattan).
    // History: counted only on views reporting a frame, 143/143. On every view: 209/241 once the
    // paper's 5 % share of planar area (it refused curbs' and single steps' risers 1.3 m wide) was
    // dropped and one narrow plane, or two faces of one box, no longer made a frame; 199/226 once
    // an open riser's tread edge no longer counted as a riser; 208/226 once planes with floor
    // beyond them (furniture, risers, people) voted only when the walls make no frame; 213/226 once
    // two narrow strips of one riser or wall on one line counted as one plane as wide as they span
    // (and a 3 cm leg beside a person's front no longer made a "parallel pair": test_perception_manhattan);
    // 214/226 once a vetoing wall as wide as one that makes a frame alone gave the frame itself;
    // 215/226 once a wall on the floor with nothing beyond it was trusted from 20 cm wide (as wide
    // as a wall that may veto a frame), not 30 (test_perception_manhattan); 212/222 once the lower
    // floor ran on under the upper floor beside an open-sided descent (test_capture_synthetic):
    // its slab edge, 0.2 m tall in a bottomless void, had counted as a wall on 4 views (a miss on
    // one, frames on the other three); 214/222 once the image edges' compass confirmed planes too
    // narrow or small to trust alone (people #7, ascending_short #15: test_perception_manhattan);
    // 215/222 once a band along a level axis tilted beyond 10 deg by its fit joined them
    // (single_step #20, a riser's corner at the image edge); 216/222 once a floor refused for where
    // it lies still gave the vertical to measure the frame about (ascending_short #13: ManhattanFrame.
    // FloorRefusedStillGivesTheVertical); 217/222 once walls reaching the depth cut-off were fitted
    // on their readings clear of its noise band (sofa #0 had been 2.01 deg off: ManhattanFrame.
    // FarWallsFittedClearOfTheCutOff); 219/222 once the image edges agreeing with a wall at the
    // cut-off that vetoes the frame of clutter turned against the room gave the frame (room_clutter
    // #6 and #10, 2 deg off or more as the walls alone: ManhattanFrame.
    // ImageEdgesGiveTheFrameThatFarWallsVetoed); 220/222 once image edges too weak to confirm
    // just any plane confirmed a strip of wall on the floor with nothing beyond it (people #14:
    // ManhattanFrame.WeakImageEdgesConfirmAWallsFootInACorner); 222/222 once a long straight edge
    // lying on the floor (the foot of the wall ahead, beyond the depth cut-off) confirmed the walls
    // at the cut-off that agree with it (floor_only #17, bench #14: ManhattanFrame.
    // FloorLinesConfirmWallsAtTheCutOff).
    EXPECT_EQ(A.manhattan_wrong, 0) << "Manhattan yaw more than 2 deg off with a staircase in view";
    EXPECT_EQ(Totals::sequences().all.manhattan_wrong, 0) << "Manhattan yaw off, walking";
    EXPECT_EQ(A.manhattan_ok, A.manhattan_checked)
        << "Manhattan frame within 2 deg where a wall or riser is in view (222/222)";
    EXPECT_GE(Totals::sequences().all.manhattan_ok, 31) << "the same, walking (32/40)";
    EXPECT_LE(A.manhattan_off, 1)
        << "a frame more than 2 deg off with a wall in view (5 before the veto, 1 before "
           "the far walls were fitted clear of the cut-off, now 0)";
  }
};
const auto* const kTotals = ::testing::AddGlobalTestEnvironment(new TotalsCheck);

class PerceptionPreset : public ::testing::TestWithParam<std::string> {};

TEST_P(PerceptionPreset, FiguresOfIssue3) {
  const std::string preset = GetParam();
  long frames = 24, length = 1;
  for (const auto& p : synth::presets())
    if (p.name == preset && p.default_frames > 1) length = p.default_frames, frames = 32;
  PresetFigures F;
  // SG_SEED=N runs the presets on another seed (the bounds below hold for the default one):
  // measured Manhattan 219/232 on seed 7 and 237/247 on seed 8, no frame off with stairs in view.
  const char* seed = getenv("SG_SEED");
  run_preset(preset, frames, seed ? static_cast<std::uint32_t>(std::strtoul(seed, nullptr, 10)) : 20261123u,
             length, F);
  (length <= 1 ? Totals::get() : Totals::sequences()).add(F);
  print(preset, F);
  ASSERT_GT(F.frames, 0);
  // Issue 3's figures where they are met (see the report for the measured numbers):
  // (>= 99 % over all presets; with 12 frames a preset may miss one.)
  // A floor strip at the bottom of the view, right before a staircase and no wider than it, cannot
  // be told from a first tread in one frame: such frames report no floor (see FloorDetector).
  if (length <= 1) {
    EXPECT_GE(F.floor_ok, std::min(0.99 * F.floor_visible, F.floor_visible - 2.0))
        << "floor found within 2 cm / 1 deg";
  }
  EXPECT_EQ(F.mixed, 0) << "a region mixes two levels";
  EXPECT_EQ(F.manhattan_wrong, 0) << "a Manhattan frame more than 2 deg off with a staircase in view";
  // Known gaps, held as regression floors (the issue asks for 0 and 100 %): a frame without a
  // visible floor may still take the nearest big horizontal plane (a seat, a tread) for it, and
  // far or thin treads are sometimes split or missed.
  // Never a tread, a seat or a platform: on a descent the remembered camera height rules out
  // the treads and the landing below while the tread underfoot is out of view.
  EXPECT_EQ(F.floor_wrong_plane, 0) << "a tread, a seat or a platform taken for the floor";
  if (length > 1) {
    // Walking: the floor is tracked, also at the top of a descent where the treads below are
    // nearer the user's feet than the floor beside the stairwell (measured: every frame).
    EXPECT_EQ(F.floor_ok, F.floor_visible) << "floor found within 2 cm / 1 deg";
  }
  if (length <= 1) {
    // Measured with the seeds above (treads ok / treads). Horizontal regions take the floor's
    // normal (classify_regions), so every tread found has a normal within the floor's error.
    static const std::map<std::string, std::pair<int, int>> measured = {
        {"ascending_static", {51, 51}},
        {"descending_static", {106, 106}},
        {"open_risers_static", {51, 51}},
        {"nosing_landing_static", {56, 56}},
        {"rotated_static", {53, 53}},
        {"people_static", {90, 90}},
        {"handrails_open_sides_static", {46, 46}},
        {"single_step_static", {16, 16}},
        {"curb_static", {7, 7}},
        {"ascending_short_static", {38, 38}}};
    const auto it = measured.find(preset);
    if (it != measured.end()) {
      EXPECT_EQ(F.treads, it->second.second) << "visible treads (the synthetic world changed?)";
      EXPECT_GE(F.treads_ok, it->second.first) << "treads found with normal <= 2 deg, height <= 1 cm";
    }
    EXPECT_GE(F.treads_ok, 0.95 * F.treads) << "treads found with normal <= 2 deg, height <= 1 cm";
    EXPECT_EQ(F.tread_bad_normal, 0) << "a tread found with its normal more than 2 deg off";
    EXPECT_EQ(F.tread_bad_class, 0) << "a tread found but not classed step candidate";
  }
}

// Issue 3's figures on the static presets again, with the depth noise correlated in space as the
// real clouds' (synth::with_real_kinect_noise; the figures above are on white noise). Not the
// issue's figures: what they become when the synthetic sensor is as unkind as the real one,
// held as regression floors. Measured on the default seed (white noise in brackets): floor
// 427/428 (427/428), wrong plane 0 (0), treads 512/514 (514/514, two found 1-2 cm off in
// height), mixed 0 (0), Manhattan 204/222 (222/222), no frame more than 2 deg off with a staircase
// in view (0), 9 with a wall in view (0). (203/222 before the image edges agreeing with a vetoing
// wall at the depth cut-off gave the frame: ManhattanConfig::compass_veto_min_support. 200/222, 1
// and 11 before a flat riser with a noisy patch at its edge was no longer taken for a facet of a
// curved surface: single_step #9 and #12 had no vertical plane;
// PerceptionRegions.FlatRiserWithANoisyPatchAtItsEdgeIsNoCurvedFacet. 10 before a table's edge
// confirmed by the image edges no longer made the frame alone, table #15 2.12 deg off:
// ManhattanConfig::hanging_min_height.)
TEST(PerceptionPresetRealLikeNoise, FiguresOfIssue3) {
  Totals sum;  // not the suite's Totals::get(): these views are not issue 3's figures
  const char* seed = getenv("SG_SEED");
  for (const auto& p : synth::presets()) {
    if (p.default_frames > 1) continue;
    PresetFigures F;
    run_preset(p.name, 24, seed ? static_cast<std::uint32_t>(std::strtoul(seed, nullptr, 10)) : 20261123u, 1,
               F, synth::with_real_kinect_noise());
    print(p.name, F);
    sum.add(F);
  }
  const PresetFigures& A = sum.all;
  std::printf(
      "REAL-LIKE NOISE, STATIC PRESETS: floor %d/%d wrong plane %d | treads %d/%d mixed %d | manhattan %d/%d "
      "(wrong %d, off with a wall in view %d)\n",
      A.floor_ok, A.floor_visible, A.floor_wrong_plane, A.treads_ok, A.treads, A.mixed, A.manhattan_ok,
      A.manhattan_checked, A.manhattan_wrong, A.manhattan_off);
  if (seed) return;  // the floors below are the default seed's
  EXPECT_GE(A.floor_ok, 0.99 * A.floor_visible);
  EXPECT_EQ(A.floor_wrong_plane, 0);
  EXPECT_GE(A.treads_ok, 512) << "measured 512/514";
  EXPECT_EQ(A.mixed, 0);
  EXPECT_GE(A.manhattan_ok, 204) << "measured 204/222";
  EXPECT_EQ(A.manhattan_wrong, 0) << "measured 0";
  EXPECT_LE(A.manhattan_off, 9) << "measured 9";
}

INSTANTIATE_TEST_SUITE_P(AllPresets, PerceptionPreset, ::testing::ValuesIn([] {
                           std::vector<std::string> names;
                           for (const auto& p : synth::presets()) names.push_back(p.name);
                           return names;
                         }()),
                         [](const ::testing::TestParamInfo<std::string>& i) { return i.param; });

// ---------------------------------------------------------------------------------------------
// Real frames from ../shared/data (labels.csv): what their labels allow.
#include <fstream>
#include <sstream>

#include "stairguide/capture/dataset.hpp"

namespace {

struct Label {
  std::string path, label, kind;
};

std::vector<Label> read_labels(const std::string& dir) {
  std::vector<Label> out;
  std::ifstream in(dir + "/labels.csv");
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line)) {
    std::stringstream ss(line);
    Label l;
    std::getline(ss, l.path, ',');
    std::getline(ss, l.label, ',');
    std::getline(ss, l.kind, ',');
    if (!l.path.empty()) out.push_back(l);
  }
  return out;
}

// Distinct levels of big planes parallel to `n0` (offsets along it), merged within 4 cm.
std::vector<float> levels_along(const SceneResult& sc, const Eigen::Vector3f& n0, int min_px) {
  std::vector<float> d;
  for (const auto& r : sc.regions)
    if (r.pixel_count >= min_px && r.normal.dot(n0) >= std::cos(8 * kDeg)) d.push_back(r.offset);
  std::sort(d.begin(), d.end());
  std::vector<float> lv;
  for (float x : d)
    if (lv.empty() || x - lv.back() > 0.04f) lv.push_back(x);
  return lv;
}

bool has_riser_gap(const std::vector<float>& lv) {
  for (std::size_t i = 0; i < lv.size(); ++i)
    for (std::size_t j = i + 1; j < lv.size(); ++j)
      if (lv[j] - lv[i] >= 0.13f && lv[j] - lv[i] <= 0.22f) return true;
  return false;
}

}  // namespace

TEST(PerceptionRealData, LabelledFrames) {
  const std::string dir = STAIRGUIDE_SHARED_DATA;
  std::ifstream probe(dir + "/labels.csv");
  if (!probe) GTEST_SKIP() << "no real data at " << dir << " (labels.csv missing)";
  const auto labels = read_labels(dir);
  ASSERT_FALSE(labels.empty());
  int open_riser_frames = 0, open_riser_stacked = 0;
  for (const Label& l : labels) {
    RgbdFrame f;
    try {
      f = read_pcd_frame(dir + "/" + l.path);
    } catch (const std::exception& e) {
      ADD_FAILURE() << l.path << ": " << e.what();
      continue;
    }
    Perception P;
    SceneResult sc;
    P.process(f, sc);
    int candidates = 0;
    for (const auto& r : sc.regions) candidates += r.cls == RegionClass::kStepCandidate;
    std::printf("%-75s %-5s floor %d regions %3zu candidates %d %.2f ms\n", l.path.c_str(), l.label.c_str(),
                sc.floor_found, sc.regions.size(), candidates, sc.timings.total_ms);
    if (l.label == "none") {
      // No staircase: never a stack of step candidates (two at a riser's spacing).
      std::vector<float> h;
      for (const auto& r : sc.regions)
        if (r.cls == RegionClass::kStepCandidate) h.push_back(r.height);
      std::sort(h.begin(), h.end());
      EXPECT_FALSE(has_riser_gap(h) && h.size() >= 2) << l.path;
    } else if (l.path.find("tutorials_pairwise") != std::string::npos) {
      // Open-riser staircase seen by a level camera: the camera's tilt is outside the chest
      // range, so no floor; but the treads are horizontal planes (normal along -y_C) stacked one
      // riser apart above the floor level.
      ++open_riser_frames;
      EXPECT_FALSE(sc.floor_found) << l.path << ": a level camera is outside the 20-70 deg tilt rule";
      const auto lv = levels_along(sc, Eigen::Vector3f(0.f, -1.f, 0.f), 300);
      std::printf("  horizontal levels (m below the camera):");
      for (float x : lv) std::printf(" %.3f", x);
      std::printf("\n");
      EXPECT_TRUE(has_riser_gap(lv)) << l.path << ": no tread one riser above another horizontal level";
      int stacked = 0;  // levels with another one a riser below
      for (std::size_t i = 0; i < lv.size(); ++i)
        for (std::size_t j = i + 1; j < lv.size(); ++j)
          if (lv[j] - lv[i] >= 0.13f && lv[j] - lv[i] <= 0.22f) {
            ++stacked;
            break;
          }
      open_riser_stacked += stacked >= 2;
    } else if (l.path.find("stair-perception-fhg") != std::string::npos) {
      // Close-up of two nosings, no floor in view: no floor may be invented, and the two treads
      // are parallel planes a riser apart.
      EXPECT_FALSE(sc.floor_found) << l.path;
      ASSERT_FALSE(sc.regions.empty());
      const PlaneRegion* big = &sc.regions[0];
      for (const auto& r : sc.regions)
        if (r.pixel_count > big->pixel_count) big = &r;
      const auto lv = levels_along(sc, big->normal, 1000);
      std::printf("  levels along the biggest plane's normal:");
      for (float x : lv) std::printf(" %.3f", x);
      std::printf("\n");
      EXPECT_TRUE(has_riser_gap(lv)) << l.path;
    }
  }
  EXPECT_EQ(open_riser_frames, 5);
  EXPECT_GE(open_riser_stacked, 3) << "three treads stacked in most open-riser frames";
}

// ---------------------------------------------------------------------------------------------
// Real Kinect frames: big planes come out whole, curved things (people) are obstacles, and the
// region counts stay near the number of surfaces. Kinect depth is quantised in disparity (steps
// of about 2.85e-3 z^2 m) and has low-frequency distortion: before the fixes of issue 3 /
// brief seg2 a corridor with five people gave 286 regions (each person tiled into facets) and
// the corridor floor was cut into a main region and a fringe of patches.
namespace {

// Share of the valid pixels within 3 sigma (1.425e-3 z^2) of region `r`'s plane that the region
// holds. (Pixels on the same infinite plane elsewhere count against it: this is a lower bound.)
double plane_coverage(const RgbdFrame& f, const std::vector<int>& labels, const PlaneRegion& r) {
  const CameraIntrinsics& K = f.intrinsics;
  long on = 0, mine = 0;
  for (int v = 0; v < f.depth.rows; ++v)
    for (int u = 0; u < f.depth.cols; ++u) {
      const float z = f.depth.at<float>(v, u);
      if (!(z > 0.f) || !std::isfinite(z)) continue;
      const Eigen::Vector3f p((u - K.cx) / K.fx * z, (v - K.cy) / K.fy * z, z);
      if (std::fabs(r.normal.dot(p) + r.offset) > 3.f * 1.425e-3f * z * z) continue;
      ++on;
      mine += labels[static_cast<std::size_t>(v) * f.depth.cols + u] == r.id;
    }
  return on > 0 ? static_cast<double>(mine) / static_cast<double>(on) : 0.0;
}

// The biggest region whose normal is within 10 degrees of `n0`.
const PlaneRegion* biggest_along(const SceneResult& sc, const Eigen::Vector3f& n0) {
  const PlaneRegion* best = nullptr;
  for (const auto& r : sc.regions)
    if (r.normal.dot(n0) >= std::cos(10 * kDeg) && (!best || r.pixel_count > best->pixel_count)) best = &r;
  return best;
}

}  // namespace

TEST(PerceptionRealData, BigPlanesWholeCurvedSurfacesObstacles) {
  const std::string dir = STAIRGUIDE_SHARED_DATA;
  const std::string clouds = dir + "/pcl-kinect-clouds";
  std::ifstream probe(clouds + "/test/office1.pcd");
  if (!probe) GTEST_SKIP() << "no real data at " << clouds;

  {  // Corridor with five people walking away, floor in the lower middle.
    const RgbdFrame f = read_pcd_frame(clouds + "/test/five_people.pcd");
    Perception P;
    SceneResult sc;
    P.process(f, sc);
    const PlaneRegion* floor = biggest_along(sc, Eigen::Vector3f(0.f, -1.f, 0.f));
    ASSERT_NE(floor, nullptr);
    const double cov = plane_coverage(f, P.segmentation().labels(), *floor);
    // The people: pixels in obstacle clusters (labels -2 - k), as a share of the valid pixels.
    long obstacle = 0, valid = 0;
    const auto& L = P.segmentation().labels();
    for (std::size_t p = 0; p < L.size(); ++p) {
      obstacle += L[p] <= -2;
      valid +=
          f.depth.at<float>(static_cast<int>(p) / f.depth.cols, static_cast<int>(p) % f.depth.cols) > 0.f;
    }
    const double people = static_cast<double>(obstacle) / static_cast<double>(valid);
    std::printf(
        "five_people: regions %zu, floor region %d px covers %.1f %% of the floor-plane pixels, "
        "%zu obstacle clusters with %.1f %% of the valid pixels\n",
        sc.regions.size(), floor->pixel_count, 100 * cov, sc.clusters.size(), 100 * people);
    EXPECT_LE(sc.regions.size(), 170u) << "was 286: the people were tiled into planar facets";
    EXPECT_GE(floor->pixel_count, 20000) << "was 16000 with a fringe of floor patches around it";
    EXPECT_GE(cov, 0.55) << "was 0.45";
    EXPECT_GE(people, 0.3) << "the people are obstacles (was 0: all planar facets)";
  }
  {  // Office: back wall, a side wall (seen at a grazing angle), door, desk clutter.
    const RgbdFrame f = read_pcd_frame(clouds + "/test/office1.pcd");
    Perception P;
    SceneResult sc;
    P.process(f, sc);
    const PlaneRegion* back = biggest_along(sc, Eigen::Vector3f(0.f, 0.f, -1.f));
    const PlaneRegion* side = biggest_along(sc, Eigen::Vector3f(-0.98f, 0.f, -0.2f).normalized());
    ASSERT_NE(back, nullptr);
    ASSERT_NE(side, nullptr);
    const double cb = plane_coverage(f, P.segmentation().labels(), *back);
    const double cs = plane_coverage(f, P.segmentation().labels(), *side);
    std::printf("office1: regions %zu, back wall %d px covers %.1f %%, side wall %d px covers %.1f %%\n",
                sc.regions.size(), back->pixel_count, 100 * cb, side->pixel_count, 100 * cs);
    EXPECT_LE(sc.regions.size(), 140u) << "was 167";
    EXPECT_GE(back->pixel_count, 80000);
    EXPECT_GE(cb, 0.9);
    EXPECT_GE(side->pixel_count, 27000) << "was 22000 and a fringe of patches";
    EXPECT_GE(cs, 0.55) << "was 0.45";
  }
  // Open-riser staircase room (5 captures) and a hand-held kitchen sequence: region counts.
  for (int i = 1; i <= 5; ++i) {
    const RgbdFrame f =
        read_pcd_frame(clouds + "/tutorials_pairwise/capture000" + std::to_string(i) + ".pcd");
    Perception P;
    SceneResult sc;
    P.process(f, sc);
    EXPECT_LE(sc.regions.size(), 240u) << "capture000" << i << " (was 276-323)";
  }
  const std::string kitchen = dir + "/7scenes-redkitchen-0000-0299";
  std::ifstream depth_list(kitchen + "/depth.txt");
  if (depth_list) {
    // Frames 0, 100 and 200 (TUM list: "timestamp path" lines, # comments), each on its own.
    std::vector<std::string> files;
    std::string line;
    while (std::getline(depth_list, line))
      if (!line.empty() && line[0] != '#') files.push_back(line.substr(line.find(' ') + 1));
    ASSERT_GE(files.size(), 201u);
    for (std::size_t i : {0u, 100u, 200u}) {
      const RgbdFrame f = read_depth_png_frame(kitchen + "/" + files[i]);
      Perception P;
      SceneResult sc;
      P.process(f, sc);
      std::printf("kitchen frame %zu: regions %zu\n", i, sc.regions.size());
      EXPECT_LE(sc.regions.size(), 130u) << "kitchen frame " << i << " (was 160-181)";
    }
  }
}

// The far walls of the real clouds, cut at the depth cut-off (capture max_range, 5 m) as the
// daemon sees them, against the same planes seen uncut to 8 m (truncated only by the room): the
// Manhattan frame takes the yaw of such a plane (most of it within range_clip_margin of the cut-off,
// wider than sliver_width) from its plane held upright (fit_upright_normal), which had made the
// synthetic far walls' yaw errors about half. Here it must be no worse on the whole.
TEST(PerceptionRealData, FarWallsAtTheCutOffHeldUprightAreNoWorse) {
  const std::string clouds = std::string(STAIRGUIDE_SHARED_DATA) + "/pcl-kinect-clouds";
  std::ifstream probe(clouds + "/test/office1.pcd");
  if (!probe) GTEST_SKIP() << "no real data at " << clouds;
  const ManhattanConfig mc;
  const float cut = CaptureConfig{}.max_range, clip_depth = cut - mc.range_clip_margin;
  auto yaw_about = [](const Eigen::Vector3f& n, const Eigen::Vector3f& up) {
    const Eigen::Vector3f a = (Eigen::Vector3f::UnitX() - up * up.x()).normalized(), b = up.cross(a);
    return std::atan2(n.dot(b), n.dot(a));
  };
  auto apart_deg = [](float x, float y) {  // modulo 180 degrees
    float d = std::fmod(std::fabs(x - y), static_cast<float>(M_PI));
    return std::min(d, static_cast<float>(M_PI) - d) / kDeg;
  };
  // The clear depth ManhattanTracker fits such walls to: 3 sigma of noise short of the cut-off.
  const float noise = SegmentationConfig{}.depth_noise_coeff, clear_depth = cut - 3.f * noise * cut * cut;
  int n = 0, better = 0, refitted = 0, worse_clear = 0;
  double sum_free = 0, sum_upright = 0, sum_clear = 0;
  for (const char* name : {"office1", "five_people"}) {
    const RgbdFrame f = read_pcd_frame(clouds + "/test/" + name + ".pcd");
    RgbdFrame uncut = f, at_cut = f;
    uncut.depth = f.depth.clone();
    at_cut.depth = f.depth.clone();
    uncut.depth.setTo(0.f, f.depth > 8.f);
    at_cut.depth.setTo(0.f, f.depth > cut);
    Segmentation S_uncut, S_cut;
    std::vector<PlaneRegion> R_uncut, R_cut;
    std::vector<ObstacleCluster> C;
    ASSERT_TRUE(S_uncut.run(uncut, R_uncut, C));
    ASSERT_TRUE(S_cut.run(at_cut, R_cut, C));
    // Up: the biggest plane facing the camera's -y within 25 degrees (a floor, a ceiling, a desk).
    const PlaneRegion* level = nullptr;
    for (const PlaneRegion& r : R_uncut)
      if (std::fabs(r.normal.y()) > std::cos(25 * kDeg) && (!level || r.pixel_count > level->pixel_count))
        level = &r;
    ASSERT_NE(level, nullptr) << name;
    const Eigen::Vector3f up = level->normal.y() < 0.f ? level->normal : Eigen::Vector3f(-level->normal);
    for (const PlaneRegion& r : R_cut) {
      if (std::fabs(r.normal.dot(up)) > std::sin(mc.vertical_tolerance) ||
          r.rect_length_minor < mc.sliver_width)
        continue;
      std::size_t clipped = 0;
      for (const Eigen::Vector3f& q : r.points) clipped += q.z() > clip_depth;
      if (2 * clipped <= r.points.size()) continue;
      // The uncut region holding most of its pixels.
      std::map<int, int> votes;
      for (int p : r.pixels)
        if (S_uncut.labels()[static_cast<std::size_t>(p)] >= 0)
          ++votes[S_uncut.labels()[static_cast<std::size_t>(p)]];
      int match = -1, most = 0;
      for (const auto& [k, c] : votes)
        if (c > most) match = k, most = c;
      if (match < 0 || 2 * most < static_cast<int>(r.pixels.size())) continue;
      const PlaneRegion& u = R_uncut[static_cast<std::size_t>(match)];
      const float truth = yaw_about(fit_upright_normal(u.points, up, u.normal), up);
      const float e_free = apart_deg(yaw_about(r.normal, up), truth);
      const Eigen::Vector3f n_upright = fit_upright_normal(r.points, up, r.normal);
      const float e_upright = apart_deg(yaw_about(n_upright, up), truth);
      const float e_clear = apart_deg(
          yaw_about(fit_upright_normal_clear_of_cutoff(r.points, up, n_upright, clear_depth), up), truth);
      std::printf(
          "%s: far plane %d px %.2f x %.2f m at %.2f m (uncut %d px): yaw off %.2f deg as segmented, "
          "%.2f held upright, %.2f clear of the cut-off\n",
          name, r.pixel_count, r.rect_length_major, r.rect_length_minor, r.centroid.z(), u.pixel_count,
          e_free, e_upright, e_clear);
      ++n;
      better += e_upright < e_free;
      refitted += e_clear != e_upright;
      worse_clear += e_clear > e_upright + 0.05f;
      sum_free += e_free;
      sum_upright += e_upright;
      sum_clear += e_clear;
    }
  }
  std::printf(
      "%d far planes: mean yaw error %.2f deg as segmented, %.2f held upright, better in %d; %.2f clear of "
      "the cut-off (%d refitted, %d worse)\n",
      n, sum_free / std::max(n, 1), sum_upright / std::max(n, 1), better, sum_clear / std::max(n, 1),
      refitted, worse_clear);
  ASSERT_GE(n, 10) << "the clouds' far walls at the cut-off (14 at the time of writing)";
  EXPECT_LE(sum_upright, sum_free) << "held upright, far walls are worse on the whole";
  EXPECT_GE(2 * better, n) << "held upright, fewer than half the far walls are better";
  // Fitted clear of the cut-off's noise band (ManhattanTracker does so after holding them upright):
  // measured 2 of 14 refitted, 4.44 -> 1.95 and 4.14 -> 4.11 deg off.
  EXPECT_LE(sum_clear, sum_upright) << "clear of the cut-off, far walls are worse on the whole";
  EXPECT_EQ(worse_clear, 0) << "clear of the cut-off, a far wall is worse";
}

// The Manhattan frame on real data: the kitchen's walls and cupboards do not move, so k_M carried
// into the world by the sequence's ground-truth poses must keep one direction (modulo 90 degrees
// about the vertical) from view to view, each view on its own. This checks the yaw where the
// synthetic truth cannot: real walls, real noise, a hand-held camera.
TEST(PerceptionRealData, KitchenManhattanFrameHoldsStillInTheWorld) {
  const std::string kitchen = std::string(STAIRGUIDE_SHARED_DATA) + "/7scenes-redkitchen-0000-0299";
  std::ifstream depth_list(kitchen + "/depth.txt"), poses(kitchen + "/groundtruth.txt");
  if (!depth_list || !poses) GTEST_SKIP() << "no 7-Scenes kitchen under " << STAIRGUIDE_SHARED_DATA;
  std::vector<std::string> files;
  std::vector<Eigen::Matrix3f> R_wc;
  std::string line;
  while (std::getline(depth_list, line))
    if (!line.empty() && line[0] != '#') files.push_back(line.substr(line.find(' ') + 1));
  while (std::getline(poses, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream in(line);
    double t, x, y, z, qx, qy, qz, qw;
    in >> t >> x >> y >> z >> qx >> qy >> qz >> qw;
    R_wc.push_back(Eigen::Quaternionf(static_cast<float>(qw), static_cast<float>(qx), static_cast<float>(qy),
                                      static_cast<float>(qz))
                       .normalized()
                       .toRotationMatrix());
  }
  ASSERT_EQ(files.size(), R_wc.size());
  sg_test::WorldManhattan world;
  for (std::size_t i = 0; i < files.size(); i += 10) {
    const RgbdFrame f = read_depth_png_frame(kitchen + "/" + files[i]);
    Perception P;  // each view on its own: nothing carried over
    SceneResult sc;
    P.process(f, sc);
    if (sc.floor_found && sc.manhattan_found) world.add(sc, R_wc[i]);
  }
  // Measured: 16 of the 30 views (the others have no floor in view, or too little wall), every
  // one within 1.68 degrees of the views' mean.
  ASSERT_GE(world.k.size(), 13u) << "Manhattan frame found on too few kitchen views";
  const float mean = world.mean_yaw();
  float worst = 0.f;
  for (float a : world.yaws()) worst = std::max(worst, std::fabs(wrap45(a - mean)));
  std::printf("kitchen: Manhattan frame on %zu of %zu views; world yaw within %.2f deg of the mean\n",
              world.k.size(), (files.size() + 9) / 10, worst / kDeg);
  EXPECT_LE(worst / kDeg, 2.5f);
}

// The residuals of a frame's big planes about their fit, correlated between pixels k apart along
// a row (k = 1, 4, 8), averaged over the planes of 5000 pixels or more (their count: `planes`).
namespace {
std::array<double, 3> residual_correlation(const RgbdFrame& f, int& planes) {
  Segmentation S;
  std::vector<PlaneRegion> R;
  std::vector<ObstacleCluster> C;
  std::array<double, 3> mean{0, 0, 0};
  planes = 0;
  if (!S.run(f, R, C)) return mean;
  const CameraIntrinsics& K = f.intrinsics;
  std::vector<float> e(static_cast<std::size_t>(K.width * K.height));
  for (const PlaneRegion& r : R) {
    if (r.pixel_count < 5000) continue;
    std::fill(e.begin(), e.end(), std::numeric_limits<float>::quiet_NaN());
    auto ray_of = [&](int p, float& z) {
      const int v = p / K.width, u = p - v * K.width;
      z = f.depth.ptr<float>(v)[u];
      return Eigen::Vector3d((u - K.cx) / K.fx, (v - K.cy) / K.fy, 1.0);
    };
    // Least squares in inverse depth, 1 / z = a . ray (as the segmentation fits planes).
    Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
    Eigen::Vector3d b = Eigen::Vector3d::Zero();
    float z = 0.f;
    for (int p : r.pixels) {
      const Eigen::Vector3d ray = ray_of(p, z);
      if (!(z > 0.f)) continue;
      A += ray * ray.transpose();
      b += ray / z;
    }
    const Eigen::Vector3d a = A.ldlt().solve(b);
    for (int p : r.pixels) {
      const Eigen::Vector3d ray = ray_of(p, z);
      if (z > 0.f) e[static_cast<std::size_t>(p)] = static_cast<float>(1.0 / z - a.dot(ray));
    }
    const int lags[3] = {1, 4, 8};
    for (int i = 0; i < 3; ++i) {
      double sxy = 0, sxx = 0, syy = 0;
      for (int p : r.pixels) {
        if (p % K.width + lags[i] >= K.width) continue;
        const float x = e[static_cast<std::size_t>(p)], y = e[static_cast<std::size_t>(p + lags[i])];
        if (std::isnan(x) || std::isnan(y)) continue;
        sxy += x * y, sxx += x * x, syy += y * y;
      }
      mean[i] += sxy / std::sqrt(std::max(sxx * syy, 1e-300));
    }
    ++planes;
  }
  for (double& m : mean) m /= std::max(planes, 1);
  return mean;
}
}  // namespace

// The synthetic sensor's default noise is white: each pixel its own draw. A real structured-light
// sensor's is not (it matches a window of its speckle pattern), and a plane fitted on N pixels of
// correlated noise is fixed far less well than N independent readings would fix it: fitting on
// every pixel instead of a subsample made synthetic far walls' yaw twice as good, and the real
// clouds' no better. This measures the gap and checks the model of it
// (synth::with_real_kinect_noise) against the real clouds.
TEST(PerceptionRealData, SyntheticNoiseCorrelatedAsTheRealClouds) {
  const std::string clouds = std::string(STAIRGUIDE_SHARED_DATA) + "/pcl-kinect-clouds";
  std::ifstream probe(clouds + "/test/office1.pcd");
  if (!probe) GTEST_SKIP() << "no real data at " << clouds;
  auto add = [](std::array<double, 3>& sum, int& n, const std::array<double, 3>& c, int planes) {
    for (int i = 0; i < 3; ++i) sum[i] += c[i] * planes;
    n += planes;
  };
  std::array<double, 3> real{0, 0, 0}, white{0, 0, 0}, modelled{0, 0, 0};
  int n_real = 0, n_white = 0, n_modelled = 0, planes = 0;
  for (const char* name : {"office1", "five_people"}) {
    const auto c = residual_correlation(read_pcd_frame(clouds + "/test/" + name + ".pcd"), planes);
    add(real, n_real, c, planes);
  }
  RgbdFrame frame;
  FrameTruth truth;
  for (const char* preset : {"corridor_static", "ascending_static"}) {
    for (int i : {0, 5}) {
      synth::render_preset_frame(preset, i, 1, synth::SynthOptions{}, frame, truth);
      add(white, n_white, residual_correlation(frame, planes), planes);
      synth::render_preset_frame(preset, i, 1, synth::with_real_kinect_noise(), frame, truth);
      add(modelled, n_modelled, residual_correlation(frame, planes), planes);
    }
  }
  ASSERT_GE(n_real, 8) << "big planes in the real clouds (12 at the time of writing)";
  ASSERT_GE(n_white, 8);
  ASSERT_GE(n_modelled, 8);
  const int lags[3] = {1, 4, 8};
  for (int i = 0; i < 3; ++i) {
    real[i] /= n_real, white[i] /= n_white, modelled[i] /= n_modelled;
    std::printf(
        "residual correlation at %d px: real %.2f (%d planes), synthetic white %.2f, synthetic modelled "
        "%.2f\n",
        lags[i], real[i], n_real, white[i], modelled[i]);
    EXPECT_NEAR(modelled[i], real[i], 0.15) << "the modelled noise's correlation at " << lags[i] << " px";
  }
  EXPECT_GT(real[0], 0.5) << "the real clouds' noise is correlated between neighbouring pixels";
  EXPECT_LT(white[0], 0.1) << "the default synthetic noise is white";
}
