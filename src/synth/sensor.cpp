// Kinect-like sensor model. Depth comes from disparity d = F / z (F = IR focal x baseline): the
// sensor's noise is Gaussian in disparity, the disparity is quantised to 1/8 px and the driver
// rounds depth to 1 mm. Measured depth sigma is the sum of all three, so the Gaussian part is
// chosen to make the total equal sigma_coeff * z^2 (Khoshelham & Elberink's 1.425e-3 z^2 is a
// measured figure that already contains quantisation). Holes follow what a structured-light
// sensor loses: out of range, grazing incidence, mixed pixels at depth jumps, and the projector's
// occlusion shadows (projector to the camera's right: shadows fall left of near objects).
#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "stairguide/synth/synth.hpp"
#include "internal.hpp"

namespace stairguide::synth {
namespace {

// xorshift64*: the per-pixel random stream (fast; the seed fixes the realisation).
struct Stream {
  std::uint64_t s;
  explicit Stream(std::uint64_t seed) : s(seed * 0x9E3779B97F4A7C15ull + 0x2545F4914F6CDD1Dull) {
    if (s == 0) s = 1;
  }
  std::uint64_t next() {
    s ^= s >> 12;
    s ^= s << 25;
    s ^= s >> 27;
    return s * 0x2545F4914F6CDD1Dull;
  }
};

// Round to nearest for non-negative values, without the libm call of std::nearbyint.
inline float round_pos(float x) { return static_cast<float>(static_cast<int>(x + 0.5f)); }

// The artefacts of real frames that add to the noise (SynthOptions flying_pixels, speckle_holes;
// dark and glossy faces are holes, depth_sensor_holes), each from its own stream so that the
// noise draws the same with them or without.
void apply_real_artefacts(const RenderBuffers& ideal, const SynthOptions& o, std::uint64_t seed,
                          cv::Mat& depth) {
  const int W = depth.cols, H = depth.rows;
  if (o.flying_pixels > 0.f) {
    // A pixel whose footprint straddles a depth jump reads a mix of the two sides (most of all on a
    // time-of-flight sensor): a depth between them, off both surfaces, where the sensor would
    // otherwise give the nearer side or nothing.
    const std::uint64_t p = static_cast<std::uint64_t>(o.flying_pixels * 65536.f);
    const float zmin = o.min_range_m, zmax = o.max_range_m;
    Stream s(seed ^ 0xF1F1ull);
    for (int v = 1; v + 1 < H; ++v) {
      const float* z = ideal.depth.ptr<float>(v);
      const float* zu = ideal.depth.ptr<float>(v - 1);
      const float* zd = ideal.depth.ptr<float>(v + 1);
      float* out = depth.ptr<float>(v);
      for (int u = 1; u + 1 < W; ++u) {
        const std::uint64_t r = s.next();
        if (z[u] <= 0.f || (r >> 48) >= p) continue;
        const float nb[4] = {z[u - 1], z[u + 1], zu[u], zd[u]};
        float other = 0.f;
        for (float q : nb)
          if (q > 0.f && std::fabs(q - z[u]) > o.edge_jump_abs_m + o.edge_jump_rel * z[u] &&
              std::fabs(q - z[u]) > std::fabs(other - z[u]))
            other = q;
        if (other <= 0.f) continue;
        const float t = static_cast<float>((r >> 16) & 0xFFFF) * (1.f / 65536.f);
        const float zf = z[u] + t * (other - z[u]);
        if (zf >= zmin && zf <= zmax) out[u] = zf;
      }
    }
  }
  if (o.speckle_holes > 0.f) {
    // Blobs of lost readings (speckle the matcher could not match), radius 1-3 px.
    Stream s(seed ^ 0x5BEC1Eull);
    const int blobs = static_cast<int>(o.speckle_holes * static_cast<float>(W * H) / 15.f);
    for (int i = 0; i < blobs; ++i) {
      const int cu = static_cast<int>(s.next() % static_cast<std::uint64_t>(W));
      const int cv = static_cast<int>(s.next() % static_cast<std::uint64_t>(H));
      const int rad = 1 + static_cast<int>(s.next() % 3);
      for (int dv = -rad; dv <= rad; ++dv)
        for (int du = -rad; du <= rad; ++du) {
          const int uu = cu + du, vv = cv + dv;
          if (uu < 0 || vv < 0 || uu >= W || vv >= H || du * du + dv * dv > rad * rad) continue;
          depth.ptr<float>(vv)[uu] = 0.f;
        }
    }
  }
}

// Time-of-flight multipath near concave corners (SynthOptions::multipath_m): per pixel, the
// extra depth a reading gets from light bounced off a surface that faces it nearby. Normals come
// from the ideal depth; a pixel and a neighbour up to multipath_range_m away that each lie in
// front of the other's surface form a concave corner; the bias falls linearly with their distance.
cv::Mat multipath_bias(const RenderBuffers& ideal, const CameraIntrinsics& K, const SynthOptions& o) {
  const int W = ideal.depth.cols, H = ideal.depth.rows;
  cv::Mat P(H, W, CV_32FC3, cv::Scalar(0, 0, 0)), N(H, W, CV_32FC3, cv::Scalar(0, 0, 0));
  for (int v = 0; v < H; ++v) {
    const float* z = ideal.depth.ptr<float>(v);
    cv::Vec3f* p = P.ptr<cv::Vec3f>(v);
    for (int u = 0; u < W; ++u)
      if (z[u] > 0.f)
        p[u] = cv::Vec3f((static_cast<float>(u) - K.cx) / K.fx * z[u],
                         (static_cast<float>(v) - K.cy) / K.fy * z[u], z[u]);
  }
  auto vec = [](const cv::Vec3f& a) { return Eigen::Vector3f(a[0], a[1], a[2]); };
  for (int v = 1; v + 1 < H; ++v)
    for (int u = 1; u + 1 < W; ++u) {
      const Eigen::Vector3f c = vec(P.at<cv::Vec3f>(v, u));
      if (c.z() <= 0.f) continue;
      const Eigen::Vector3f a = vec(P.at<cv::Vec3f>(v, u + 1)) - vec(P.at<cv::Vec3f>(v, u - 1));
      const Eigen::Vector3f b = vec(P.at<cv::Vec3f>(v + 1, u)) - vec(P.at<cv::Vec3f>(v - 1, u));
      const float lim = 0.05f + 0.02f * c.z();  // no normal across a depth jump
      if (std::abs(a.z()) > lim || std::abs(b.z()) > lim || a.norm() == 0.f || b.norm() == 0.f) continue;
      Eigen::Vector3f n = a.cross(b);
      if (n.norm() < 1e-9f) continue;
      n.normalize();
      if (n.dot(c) > 0.f) n = -n;
      N.at<cv::Vec3f>(v, u) = cv::Vec3f(n.x(), n.y(), n.z());
    }
  cv::Mat bias(H, W, CV_32FC1, cv::Scalar(0));
  const int dirs[8][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}, {1, 1}, {-1, -1}, {1, -1}, {-1, 1}};
  const float range = o.multipath_range_m;
  for (int v = 0; v < H; ++v)
    for (int u = 0; u < W; ++u) {
      const cv::Vec3f np = N.at<cv::Vec3f>(v, u);
      if (np[2] == 0.f && np[0] == 0.f && np[1] == 0.f) continue;
      const Eigen::Vector3f p = vec(P.at<cv::Vec3f>(v, u)), n = vec(np);
      const float r_px = std::clamp(K.fx * range / p.z(), 2.f, 60.f);
      float w = 0.f;
      for (const auto& d : dirs)
        for (float s : {0.25f, 0.5f, 1.0f}) {
          const int uu = u + static_cast<int>(std::lround(s * r_px * static_cast<float>(d[0])));
          const int vv = v + static_cast<int>(std::lround(s * r_px * static_cast<float>(d[1])));
          if (uu < 0 || vv < 0 || uu >= W || vv >= H) continue;
          const cv::Vec3f nq = N.at<cv::Vec3f>(vv, uu);
          if (nq[2] == 0.f && nq[0] == 0.f && nq[1] == 0.f) continue;
          const Eigen::Vector3f e = vec(P.at<cv::Vec3f>(vv, uu)) - p;
          const float dist = e.norm();
          if (dist < 1e-3f || dist > range) continue;
          if (e.dot(n) > 0.2f * dist && -e.dot(vec(nq)) > 0.2f * dist) w = std::max(w, 1.f - dist / range);
        }
      bias.at<float>(v, u) = o.multipath_m * w;
    }
  return bias;
}

}  // namespace

float depth_sigma_model(float z, const SynthOptions& o) { return o.sigma_coeff * z * z; }

SynthOptions with_real_artefacts(RealSensor sensor, SynthOptions o) {
  if (sensor == RealSensor::kKinectV1 || sensor == RealSensor::kStructuredLight) {
    o = with_real_kinect_noise(o);
  } else {
    o.time_of_flight = true;
    o.width = 512;
    o.height = 424;
    o.min_range_m = 0.5f;
    o.max_range_m = 4.5f;
  }
  if (sensor == RealSensor::kKinectV2Native) {
    // The Kinect v2's depth camera: 70.6 x 60 deg over 512 x 424 px (f = 256 / tan(35.3 deg) = 362;
    // calibrations give 360-368). Multipath: errors of a few cm where two surfaces meet in a
    // concave corner (Sarbolandi, Lefloch, Kolb 2015; Fuersattel et al. 2016).
    o.focal_px = 365.f;
    o.multipath_m = 0.02f;
    o.multipath_range_m = 0.15f;
  }
  if (sensor == RealSensor::kStructuredLight) {
    // The matcher's correlation window (9 x 9 px on the Kinect v1 / PrimeSense chips) straddling a
    // depth jump finds no match: a band of about half a window is lost behind the edge.
    o.edge_hole_px = 3;
  }
  o.speckle_holes = 0.005f;
  o.dark_surface_chance = 0.1f;
  o.dark_surface_range_m = 2.0f;
  o.flying_pixels = 0.3f;
  return o;
}

bool sensor_options(const std::string& noise, SynthOptions& o) {
  if (noise == "white") return true;
  if (noise == "kinect")
    o = with_real_kinect_noise(o);
  else if (noise == "real-v1")
    o = with_real_artefacts(RealSensor::kKinectV1, o);
  else if (noise == "real-v2")
    o = with_real_artefacts(RealSensor::kKinectV2, o);
  else if (noise == "tof-v2")
    o = with_real_artefacts(RealSensor::kKinectV2Native, o);
  else if (noise == "sl-v1")
    o = with_real_artefacts(RealSensor::kStructuredLight, o);
  else
    return false;
  return true;
}

const char* sensor_names() { return "'white', 'kinect', 'real-v1', 'real-v2', 'tof-v2' or 'sl-v1'"; }

SynthOptions with_real_kinect_noise(SynthOptions o) {
  o.noise_short_share = 0.6f;
  o.noise_short_px = 2.f;
  o.noise_long_share = 0.4f;
  o.noise_long_px = 10.f;
  return o;
}

float disparity_noise_sigma(float z, const SynthOptions& o) {
  const float F = o.disparity_focal_px * o.baseline_m;
  const float total = o.sigma_coeff * F;  // px: sigma_z = z^2 / F * sigma_d
  const float q = o.disparity_step_px;
  const float mm = o.depth_step_m * F / (z * z);  // depth rounding step, in disparity
  const float var = total * total - q * q / 12.f - mm * mm / 12.f;
  return var > 0.f ? std::sqrt(var) : 0.f;
}

void depth_sensor_holes(const RenderBuffers& ideal, const CameraIntrinsics& K, const SynthOptions& o,
                        std::vector<unsigned char>& hole) {
  const int W = ideal.depth.cols, H = ideal.depth.rows;
  hole.assign(static_cast<std::size_t>(W * H), 0);
  if (!o.noise) return;
  const float cos_graze = std::cos(deg2rad(o.grazing_max_deg));
  const float shadow_f = K.fx * o.baseline_m;  // shadows use the image's own projection
  for (int v = 0; v < H; ++v) {
    const float* z = ideal.depth.ptr<float>(v);
    const float* zu = v > 0 ? ideal.depth.ptr<float>(v - 1) : nullptr;
    const float* zd = v + 1 < H ? ideal.depth.ptr<float>(v + 1) : nullptr;
    const float* ci = ideal.cos_incidence.ptr<float>(v);
    unsigned char* hr = &hole[static_cast<std::size_t>(v * W)];
    for (int u = 0; u < W; ++u) {
      const float zp = z[u];
      if (zp <= 0.f) continue;
      if (ci[u] < cos_graze) {
        hr[u] = 1;
        continue;
      }
      // Mixed pixels: the farther side of a depth jump is lost.
      const float jump = o.edge_jump_abs_m + o.edge_jump_rel * zp;
      auto nearer = [&](float zq) { return zq > 0.f && zp - zq > jump; };
      if ((u > 0 && nearer(z[u - 1])) || (u + 1 < W && nearer(z[u + 1])) || (zu && nearer(zu[u])) ||
          (zd && nearer(zd[u])))
        hr[u] = 1;
      // A structured-light matcher's window: the band up to edge_hole_px behind the jump.
      for (int k = 2; k <= o.edge_hole_px && !hr[u]; ++k)
        if ((u >= k && nearer(z[u - k])) || (u + k < W && nearer(z[u + k])) ||
            (v >= k && nearer(ideal.depth.ptr<float>(v - k)[u])) ||
            (v + k < H && nearer(ideal.depth.ptr<float>(v + k)[u])))
          hr[u] = 1;
    }
    if (o.dark_surface_chance > 0.f) {
      // A dark face returns too little of the light beyond a range; a glossy one mirrors it away
      // except where it faces the sensor squarely, where the bright spot saturates. Either loses
      // its readings in one piece, as on the real frames, not scattered. Which faces: a hash of
      // the face's index, so that the ground truth's visibility (which calls this) agrees.
      const std::uint64_t chance = static_cast<std::uint64_t>(o.dark_surface_chance * 65536.f);
      const float cos_spot = std::cos(deg2rad(12.f));
      const int* f = ideal.face.ptr<int>(v);
      int last_face = -2;
      bool dark = false, glossy = false;
      for (int u = 0; u < W; ++u) {
        if (f[u] < 0 || z[u] <= 0.f) continue;
        if (f[u] != last_face) {
          last_face = f[u];
          Stream face_s(0xDA4Cull + static_cast<std::uint64_t>(f[u]) * 0x100000001B3ull);
          const std::uint64_t r = face_s.next();
          const bool odd = ((r >> 47) & 1u) != 0;
          dark = (r >> 48) < chance && !odd;
          glossy = (r >> 48) < chance && odd;
        }
        if ((dark && z[u] > o.dark_surface_range_m) || (glossy && ci[u] > cos_spot)) hr[u] = 1;
      }
    }
    if (o.shadows && !o.time_of_flight) {
      // A point at column u is lit by the projector ray with coordinate u - f b / z; it is in
      // shadow when a point to its right already reached a smaller projector coordinate.
      float run_min = 1e30f;
      for (int u = W - 1; u >= 0; --u) {
        if (z[u] <= 0.f) continue;
        const float key = static_cast<float>(u) - shadow_f / z[u];
        if (key > run_min + 0.5f) hr[u] = 1;
        run_min = std::min(run_min, key);
      }
    }
  }
}

void apply_depth_sensor(const RenderBuffers& ideal, const CameraIntrinsics& K, const SynthOptions& o,
                        std::uint64_t seed, cv::Mat& depth_out) {
  const int W = ideal.depth.cols, H = ideal.depth.rows;
  depth_out.create(H, W, CV_32FC1);
  const float zmin = o.min_range_m, zmax = o.max_range_m;
  if (!o.noise) {
    for (int v = 0; v < H; ++v) {
      const float* in = ideal.depth.ptr<float>(v);
      float* out = depth_out.ptr<float>(v);
      for (int u = 0; u < W; ++u) out[u] = (in[u] >= zmin && in[u] <= zmax) ? in[u] : 0.f;
    }
    return;
  }

  std::vector<unsigned char> hole;
  depth_sensor_holes(ideal, K, o, hole);

  const float F = o.disparity_focal_px * o.baseline_m;
  const float q = o.disparity_step_px, inv_q = 1.f / q;
  const float ds = o.depth_step_m, inv_ds = 1.f / ds;
  const float* g = detail::gaussian_table();
  // Gaussian disparity sigma tabulated per centimetre of depth (it varies slowly with z).
  const int n_sigma = static_cast<int>(zmax * 100.f) + 2;
  std::vector<float> sigma(static_cast<std::size_t>(n_sigma));
  for (int i = 0; i < n_sigma; ++i)
    sigma[static_cast<std::size_t>(i)] =
        disparity_noise_sigma(std::max(0.005f, 0.01f * static_cast<float>(i)), o);
  const std::uint64_t drop_threshold = static_cast<std::uint64_t>(std::clamp(o.dropout, 0.f, 1.f) * 65536.f);
  // Correlated parts of the noise (SynthOptions::noise_*_share): white fields of their own streams,
  // blurred and brought back to unit variance; the per-pixel draw below keeps the rest.
  const float short_share = std::clamp(o.noise_short_share, 0.f, 1.f);
  const float long_share = std::clamp(o.noise_long_share, 0.f, 1.f - short_share);
  const float white_weight = std::sqrt(1.f - short_share - long_share);
  cv::Mat correlated;
  auto add_blurred = [&](float share, float blur_px, std::uint64_t salt) {
    if (!(share > 0.f)) return;
    cv::Mat field(H, W, CV_32FC1);
    Stream s(seed ^ salt);
    for (int v = 0; v < H; ++v) {
      float* f = field.ptr<float>(v);
      for (int u = 0; u < W; ++u) f[u] = g[(s.next() >> 48) & detail::kGaussianMask];
    }
    const float b = std::max(0.3f, blur_px);
    const cv::Mat k = cv::getGaussianKernel(2 * static_cast<int>(std::ceil(3.f * b)) + 1, b, CV_32F);
    cv::sepFilter2D(field, field, CV_32F, k, k, cv::Point(-1, -1), 0.0, cv::BORDER_REFLECT);
    // The blurred field's variance: the kernel's sum of squares, squared (separable).
    const double ss = k.dot(k);
    field *= std::sqrt(share) / std::sqrt(ss * ss);
    if (correlated.empty())
      correlated = field;
    else
      correlated += field;
  };
  add_blurred(short_share, o.noise_short_px, 0x5eed0001ull);
  add_blurred(long_share, o.noise_long_px, 0x5eed0002ull);
  Stream rng(seed);
  // Every pixel draws one number (the stream stays aligned to pixels): its low bits drop it, its
  // high bits pick its white noise, mixed with the correlated field; `measure(zp, n, v, u)` turns
  // the true depth and that noise into the depth the sensor reports (0: none).
  auto each_pixel = [&](auto measure) {
    for (int v = 0; v < H; ++v) {
      const float* z = ideal.depth.ptr<float>(v);
      float* out = depth_out.ptr<float>(v);
      const unsigned char* hr = &hole[static_cast<std::size_t>(v * W)];
      const float* cr = correlated.empty() ? nullptr : correlated.ptr<float>(v);
      for (int u = 0; u < W; ++u) {
        const std::uint64_t r = rng.next();
        const float zp = z[u];
        if (zp < zmin || zp > zmax || hr[u] || ((r >> 16) & 0xFFFF) < drop_threshold) {
          out[u] = 0.f;
          continue;
        }
        float n = g[(r >> 48) & detail::kGaussianMask];
        if (cr) n = white_weight * n + cr[u];
        const float zn = measure(zp, n, v, u);
        out[u] = (zn >= zmin && zn <= zmax) ? zn : 0.f;
      }
    }
  };
  if (o.time_of_flight) {
    // Time of flight (Kinect v2): noise in depth itself, rounded to the driver's millimetre.
    const cv::Mat mp = o.multipath_m > 0.f ? multipath_bias(ideal, K, o) : cv::Mat();
    each_pixel([&](float zp, float n, int v, int u) {
      const float zm = mp.empty() ? zp : zp + mp.ptr<float>(v)[u];
      return round_pos((zm + (o.tof_sigma_m + o.tof_sigma_per_m2 * zp * zp) * n) * inv_ds) * ds;
    });
  } else {
    // Structured light (Kinect v1): noise in disparity, quantised to the sensor's sub-pixel step.
    each_pixel([&](float zp, float n, int, int) {
      float d = F / zp + sigma[static_cast<std::size_t>(zp * 100.f + 0.5f)] * n;
      if (d <= 0.5f * q) return 0.f;
      d = round_pos(d * inv_q) * q;
      return round_pos((F / d) * inv_ds) * ds;
    });
  }
  apply_real_artefacts(ideal, o, seed, depth_out);
}

void apply_color_sensor(const RenderBuffers& ideal, const SynthOptions& o, std::uint64_t seed,
                        cv::Mat& color_out, cv::Mat& gray_out) {
  if (!o.noise || o.color_noise <= 0.f) {
    ideal.color.copyTo(color_out);
  } else {
    color_out.create(ideal.color.size(), CV_8UC3);
    const float* g = detail::gaussian_table();
    // Integer noise values, so the per-pixel work is a lookup, an add and a clamp.
    std::vector<short> noise(detail::kGaussianMask + 1);
    for (std::size_t i = 0; i < noise.size(); ++i)
      noise[i] = static_cast<short>(std::lround(std::clamp(o.color_noise * g[i], -127.f, 127.f)));
    Stream rng(seed ^ 0xC0102u);
    for (int v = 0; v < ideal.color.rows; ++v) {
      const uchar* in = ideal.color.ptr<uchar>(v);
      uchar* out = color_out.ptr<uchar>(v);
      for (int u = 0; u < 3 * ideal.color.cols; u += 3) {
        const std::uint64_t r = rng.next();
        for (int c = 0; c < 3; ++c) {
          const int x = in[u + c] + noise[(r >> (16 * c + 8)) & detail::kGaussianMask];
          out[u + c] = static_cast<uchar>(x < 0 ? 0 : (x > 255 ? 255 : x));
        }
      }
    }
  }
  cv::cvtColor(color_out, gray_out, cv::COLOR_BGR2GRAY);
}

}  // namespace stairguide::synth
