// Ground truth of a rendered frame, read off the renderer's per-pixel face ids so that "visible"
// means what the camera actually sees (occluders, the sensor's range and its holes included).
#include <algorithm>
#include <cmath>

#include "internal.hpp"
#include "stairguide/synth/synth.hpp"

namespace stairguide::synth {
namespace {

constexpr int kMinTreadPixels = 200;
constexpr float kEdgeSpacing = 0.02f;     // m between samples of the first edge
constexpr float kMinRiserHeight = 0.08f;  // m, a wall or riser face at least this tall (wall_or_riser_pixels)

}  // namespace

namespace detail {

// True when the point (camera frame) is seen: it projects into the image and a pixel of its 3x3
// neighbourhood has a rendered depth close to the point's (no occluder in front of it).
bool point_seen(const Eigen::Vector3f& p, const cv::Mat& depth, const CameraIntrinsics& K,
                const SynthOptions& o) {
  if (p.z() < o.min_range_m || p.z() > o.max_range_m) return false;
  const float u = K.fx * p.x() / p.z() + K.cx, v = K.fy * p.y() / p.z() + K.cy;
  const int ui = static_cast<int>(std::lround(u)), vi = static_cast<int>(std::lround(v));
  if (ui < 0 || vi < 0 || ui >= depth.cols || vi >= depth.rows) return false;
  const float tol = 0.01f + 0.01f * p.z();
  for (int dv = -1; dv <= 1; ++dv)
    for (int du = -1; du <= 1; ++du) {
      const int uu = ui + du, vv = vi + dv;
      if (uu < 0 || vv < 0 || uu >= depth.cols || vv >= depth.rows) continue;
      const float z = depth.at<float>(vv, uu);
      if (z > 0.f && std::abs(z - p.z()) <= tol) return true;
    }
  return false;
}

}  // namespace detail

FrameTruth compute_truth(const Scene& scene, const WalkerState& walker, const RenderBuffers& ideal,
                         const CameraIntrinsics& K, const SynthOptions& o) {
  FrameTruth t;
  t.scene = scene.name;
  t.T_world_camera = walker.T_world_camera;
  t.camera_height_m = walker.T_world_camera.translation().z() - walker.support_z;
  t.camera_tilt_rad = pose_tilt(walker.T_world_camera);
  t.camera_roll_rad = pose_roll(walker.T_world_camera);

  const auto& faces = scene.faces();
  // Per face: which tread (if any) and whether it is the surface the user stands on.
  std::vector<int> face_slot(faces.size(), -1);
  std::vector<char> face_floor(faces.size(), 0);
  std::vector<char> face_upright(faces.size(), 0);  // walls and risers
  std::vector<int> upright_pixels(faces.size(), 0);
  std::vector<int> slot_base(scene.stairs.size() + 1, 0);
  for (std::size_t i = 0; i < scene.stairs.size(); ++i)
    slot_base[i + 1] = slot_base[i] + scene.stairs[i].steps + 1;
  for (std::size_t f = 0; f < faces.size(); ++f) {
    const Face& fc = faces[f];
    if (fc.stair >= 0 && fc.stair < static_cast<int>(scene.stairs.size()) && fc.tread > 0 &&
        fc.tread <= scene.stairs[static_cast<std::size_t>(fc.stair)].steps)
      face_slot[f] = slot_base[static_cast<std::size_t>(fc.stair)] + fc.tread;
    if (fc.normal.z() > 0.99f && std::abs(fc.vertices[0].z() - walker.support_z) < 0.01f) face_floor[f] = 1;
    if (std::abs(fc.normal.z()) < 0.1f && fc.solid >= 0) {
      // Walls, risers, and the front and sides of step solids (a step without a nosing is one
      // solid whose front face is its riser), at least kMinRiserHeight tall: the 4 cm front edge
      // of an open riser's tread slab is no riser.
      const Solid& so = scene.solids()[static_cast<std::size_t>(fc.solid)];
      float z_lo = fc.vertices.front().z(), z_hi = z_lo;
      for (const Eigen::Vector3f& q : fc.vertices) z_lo = std::min(z_lo, q.z()), z_hi = std::max(z_hi, q.z());
      face_upright[f] =
          (so.label == "wall" || so.label == "riser" || so.stair >= 0) && z_hi - z_lo >= kMinRiserHeight;
    }
  }
  // A tread pixel counts as visible only where the depth sensor gives a reading: a far tread
  // seen beyond the grazing-incidence limit, or a strip lost to mixed pixels behind a nosing,
  // shows in the ideal render but not to a depth camera. The sensor model's own hole rules
  // decide (grazing incidence, depth jumps, projector shadows; the range is checked below); its
  // random dropout and noise are left out (a 0.2 % dropout does not hide a tread).
  std::vector<unsigned char> hole;
  depth_sensor_holes(ideal, K, o, hole);
  std::vector<int> counts(static_cast<std::size_t>(slot_base.back()), 0);
  long floor_pixels = 0;
  for (int v = 0; v < ideal.face.rows; ++v) {
    const int* fr = ideal.face.ptr<int>(v);
    const float* zr = ideal.depth.ptr<float>(v);
    const unsigned char* hr = &hole[static_cast<std::size_t>(v) * static_cast<std::size_t>(ideal.face.cols)];
    for (int u = 0; u < ideal.face.cols; ++u) {
      const int f = fr[u];
      if (f < 0 || zr[u] < o.min_range_m || zr[u] > o.max_range_m) continue;
      const int slot = face_slot[static_cast<std::size_t>(f)];
      if (slot >= 0 && !hr[u]) ++counts[static_cast<std::size_t>(slot)];
      if (face_upright[static_cast<std::size_t>(f)] && !hr[u]) ++upright_pixels[static_cast<std::size_t>(f)];
      floor_pixels += face_floor[static_cast<std::size_t>(f)];
    }
  }
  t.floor_visible = floor_pixels * 20 >= static_cast<long>(ideal.face.total());
  for (const int c : upright_pixels) t.wall_or_riser_pixels = std::max(t.wall_or_riser_pixels, c);

  const Pose T_cw = walker.T_world_camera.inverse();
  for (std::size_t i = 0; i < scene.stairs.size(); ++i) {
    const StairSpec& sp = scene.stairs[i];
    StairTruth st;
    st.id = sp.id;
    st.kind = sp.kind;
    st.steps = sp.steps;
    st.riser_m = sp.riser_m;
    st.tread_m = sp.tread_m;
    st.width_m = sp.width_m;
    st.open_risers = sp.open_risers;
    st.down = sp.down;
    st.T_camera_stair = T_cw * sp.T_world_stair;
    for (int k = 1; k <= sp.steps; ++k) {
      const int c = counts[static_cast<std::size_t>(slot_base[i] + k)];
      if (c >= kMinTreadPixels) {
        st.visible_steps.push_back(k);
        st.visible_pixels.push_back(c);
      }
    }
    // The first edge, sampled every 2 cm along x_S a little inside its ends. It counts as visible
    // when an unoccluded stretch of at least min(0.5 m, half its width) is in view (a wide curb
    // or a flight cut by the image border still shows its edge); both ends must be seen for
    // both_ends_visible.
    const float half = 0.5f * sp.width_m - std::min(0.03f, 0.1f * sp.width_m);
    const int n = std::max(3, static_cast<int>(std::ceil(2.f * half / kEdgeSpacing)) + 1);
    const float step = 2.f * half / static_cast<float>(n - 1);
    int seen = 0;
    bool end_a = false, end_b = false;
    for (int j = 0; j < n; ++j) {
      const float x = -half + step * static_cast<float>(j);
      const bool s = detail::point_seen(st.T_camera_stair * Eigen::Vector3f(x, 0.f, 0.f), ideal.depth, K, o);
      seen += s ? 1 : 0;
      if (j == 0) end_a = s;
      if (j == n - 1) end_b = s;
    }
    st.first_edge_visible = static_cast<float>(seen) * step >= std::min(0.5f, half);
    st.both_ends_visible = end_a && end_b;
    st.user_step = sp.tread_under(walker.body);
    t.stairs.push_back(std::move(st));
  }
  detail::drop_truth(scene, walker, ideal, K, o, t);
  return t;
}

}  // namespace stairguide::synth
