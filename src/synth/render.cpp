// Rasteriser of the synthetic world. Every face is a planar convex polygon, so inverse depth is
// an affine function of the pixel coordinates over it: the depth buffer holds 1/z, the inner
// loop is one multiply-add and a compare, and the depth at a pixel centre is exactly the
// ray/plane distance (what a ray caster would give) without per-pixel intersection tests.
// Solids outside the view frustum are culled by their bounding sphere, back faces by their normal.
#include <algorithm>
#include <cmath>
#include <vector>

#include "stairguide/synth/synth.hpp"
#include "internal.hpp"

namespace stairguide::synth {
namespace {

constexpr float kNear = 0.05f;  // m, near clipping plane

struct Vec2 {
  float x, y;
};

// Clips a polygon (camera coordinates) to z >= kNear (Sutherland-Hodgman, one plane).
int clip_near(const Eigen::Vector3f* in, int n, Eigen::Vector3f* out) {
  int m = 0;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3f& a = in[i];
    const Eigen::Vector3f& b = in[(i + 1) % n];
    const bool ina = a.z() >= kNear, inb = b.z() >= kNear;
    if (ina) out[m++] = a;
    if (ina != inb) {
      const float t = (kNear - a.z()) / (b.z() - a.z());
      out[m++] = a + t * (b - a);
    }
  }
  return m;
}

struct FaceShade {
  float nu, nv, n0;      // n . ray = nu u + nv v + n0
  float su, sv, s0, sb;  // texture s = z (su u + sv v + s0) + sb, in texels
  float tu, tv, t0, tb;
  const float* tex;
  float contrast;
  float col[3];        // 255 * Lambert * albedo (BGR)
  float relief = 0.f;  // m, Material::relief_m
};

// floor() without the libm call (baseline x86-64 has no SSE4.1 round instruction).
inline int fast_floor(float x) {
  const int i = static_cast<int>(x);
  return x < static_cast<float>(i) ? i - 1 : i;
}

// The face's texture, bilinear, at texture coordinates (ts, tt) in texels.
inline float texture_at(const FaceShade& s, float ts, float tt) {
  constexpr int TN = detail::kTextureSize;
  const int is = fast_floor(ts), it = fast_floor(tt);
  const float ax = ts - static_cast<float>(is), ay = tt - static_cast<float>(it);
  const int x0 = is & (TN - 1), y0 = it & (TN - 1);
  const int x1 = (x0 + 1) & (TN - 1), y1 = (y0 + 1) & (TN - 1);
  const float a = s.tex[y0 * TN + x0], b = s.tex[y0 * TN + x1], c = s.tex[y1 * TN + x0],
              d = s.tex[y1 * TN + x1];
  const float top = a + (b - a) * ax, bot = c + (d - c) * ax;
  return top + (bot - top) * ay;
}

// Phase 1: every face in view, clipped at the near plane, rasterised into out.depth (inverse depth,
// nearest wins) and out.face. Returns the faces drawn.
std::vector<int> rasterize(const Scene& scene, const Pose& T_cw, const CameraIntrinsics& K,
                           RenderBuffers& out) {
  const int W = K.width, H = K.height;
  const Eigen::Matrix3f R_cw = T_cw.linear();
  const float fx = K.fx, fy = K.fy, cx = K.cx, cy = K.cy;

  // Frustum side planes through the optical centre (inward normals), covering pixel edges.
  const float xl = (-0.5f - cx) / fx, xr = (static_cast<float>(W) - 0.5f - cx) / fx;
  const float yt = (-0.5f - cy) / fy, yb = (static_cast<float>(H) - 0.5f - cy) / fy;
  const Eigen::Vector3f planes[4] = {
      Eigen::Vector3f(1.f, 0.f, -xl).normalized(), Eigen::Vector3f(-1.f, 0.f, xr).normalized(),
      Eigen::Vector3f(0.f, 1.f, -yt).normalized(), Eigen::Vector3f(0.f, -1.f, yb).normalized()};

  const auto& faces = scene.faces();
  std::vector<int> drawn;
  drawn.reserve(faces.size());
  std::vector<Eigen::Vector3f> vc(64), clipped(80);
  std::vector<Vec2> p2(80);

  for (const Solid& s : scene.solids()) {
    const Eigen::Vector3f c = T_cw * s.T_world_solid.translation();
    const Eigen::Vector3f& h = s.half_extents;
    const float r = s.shape == SolidShape::kBox
                        ? h.norm()
                        : std::sqrt(std::max(h.x(), h.y()) * std::max(h.x(), h.y()) + h.z() * h.z());
    if (c.z() + r < kNear) continue;
    bool outside = false;
    for (const auto& pl : planes)
      if (pl.dot(c) < -r) outside = true;
    if (outside) continue;

    for (int fi = s.first_face; fi < s.first_face + s.face_count; ++fi) {
      const Face& f = faces[static_cast<std::size_t>(fi)];
      const Eigen::Vector3f n = R_cw * f.normal;
      const Eigen::Vector3f v0 = T_cw * f.vertices[0];
      const float dist = n.dot(v0);
      if (dist > -1e-6f) continue;  // back face or seen edge-on
      const int nv = static_cast<int>(f.vertices.size());
      if (static_cast<int>(vc.size()) < nv) {
        vc.resize(static_cast<std::size_t>(nv));
        clipped.resize(static_cast<std::size_t>(nv) + 8);
        p2.resize(static_cast<std::size_t>(nv) + 8);
      }
      bool all_front = true;
      for (int i = 0; i < nv; ++i) {
        vc[static_cast<std::size_t>(i)] = T_cw * f.vertices[static_cast<std::size_t>(i)];
        if (vc[static_cast<std::size_t>(i)].z() < kNear) all_front = false;
      }
      int m = nv;
      const Eigen::Vector3f* poly = vc.data();
      if (!all_front) {
        m = clip_near(vc.data(), nv, clipped.data());
        if (m < 3) continue;
        poly = clipped.data();
      }
      float ymin = 1e30f, ymax = -1e30f, xmin = 1e30f, xmax = -1e30f;
      for (int i = 0; i < m; ++i) {
        const float iz = 1.f / poly[i].z();
        Vec2& q = p2[static_cast<std::size_t>(i)];
        q.x = fx * poly[i].x() * iz + cx;
        q.y = fy * poly[i].y() * iz + cy;
        ymin = std::min(ymin, q.y);
        ymax = std::max(ymax, q.y);
        xmin = std::min(xmin, q.x);
        xmax = std::max(xmax, q.x);
      }
      // Pixel centres at integer coordinates; half-open rule [min, max) so that faces sharing
      // an edge neither overlap nor leave a crack.
      const int v0i = std::max(0, static_cast<int>(std::ceil(ymin)));
      const int v1i = std::min(H - 1, static_cast<int>(std::ceil(ymax)) - 1);
      if (v0i > v1i || xmax < -0.5f || xmin > static_cast<float>(W) - 0.5f) continue;
      drawn.push_back(fi);
      // 1/z = A u + B v + C over the face.
      const float A = n.x() / (fx * dist), B = n.y() / (fy * dist);
      const float C = (n.z() - n.x() * cx / fx - n.y() * cy / fy) / dist;
      for (int v = v0i; v <= v1i; ++v) {
        const float fv = static_cast<float>(v);
        float lo = 1e30f, hi = -1e30f;
        for (int i = 0; i < m; ++i) {
          const Vec2& a = p2[static_cast<std::size_t>(i)];
          const Vec2& b = p2[static_cast<std::size_t>((i + 1) % m)];
          if ((a.y <= fv && fv < b.y) || (b.y <= fv && fv < a.y)) {
            const float x = a.x + (fv - a.y) * (b.x - a.x) / (b.y - a.y);
            lo = std::min(lo, x);
            hi = std::max(hi, x);
          }
        }
        if (lo > hi) continue;
        const int u0 = std::max(0, static_cast<int>(std::ceil(lo)));
        const int u1 = std::min(W - 1, static_cast<int>(std::ceil(hi)) - 1);
        float* ib = out.depth.ptr<float>(v);
        int* fb = out.face.ptr<int>(v);
        const float row = B * fv + C;
        for (int u = u0; u <= u1; ++u) {
          const float w = A * static_cast<float>(u) + row;
          if (w > ib[u]) {
            ib[u] = w;
            fb[u] = fi;
          }
        }
      }
    }
  }
  return drawn;
}

// Phase 2: the per-face terms of the per-pixel pass (light is directional, so Lambert is constant
// per face; colour = albedo * Lambert * (1 + contrast * texture)).
std::vector<FaceShade> face_terms(const Scene& scene, const Pose& T_world_camera, const Eigen::Matrix3f& R_cw,
                                  const CameraIntrinsics& K, const std::vector<int>& drawn) {
  const float fx = K.fx, fy = K.fy, cx = K.cx, cy = K.cy;
  const auto& faces = scene.faces();
  const Eigen::Vector3f light = scene.light_dir.normalized();
  const Eigen::Vector3f t_wc = T_world_camera.translation();
  const auto& solids = scene.solids();
  std::vector<FaceShade> fs(faces.size());
  for (const int fi : drawn) {
    const Face& f = faces[static_cast<std::size_t>(fi)];
    const Material& mat = solids[static_cast<std::size_t>(f.solid)].material;
    FaceShade& s = fs[static_cast<std::size_t>(fi)];
    const Eigen::Vector3f n = R_cw * f.normal;
    // cos(incidence) * |ray| = n . ray, affine in the pixel coordinates.
    s.nu = n.x() / fx;
    s.nv = n.y() / fy;
    s.n0 = n.z() - n.x() * cx / fx - n.y() * cy / fy;
    const float inv_texel = 1.f / mat.texel_m;
    const Eigen::Vector3f as = inv_texel * (R_cw * f.tex_s), at = inv_texel * (R_cw * f.tex_t);
    // Texture coordinate s = as . (z * ray) + bs, with ray = ((u-cx)/fx, (v-cy)/fy, 1).
    s.su = as.x() / fx;
    s.sv = as.y() / fy;
    s.s0 = as.z() - as.x() * cx / fx - as.y() * cy / fy;
    s.sb = inv_texel * (t_wc - f.tex_origin).dot(f.tex_s);
    s.tu = at.x() / fx;
    s.tv = at.y() / fy;
    s.t0 = at.z() - at.x() * cx / fx - at.y() * cy / fy;
    s.tb = inv_texel * (t_wc - f.tex_origin).dot(f.tex_t);
    s.tex = detail::texture(mat.texture);
    s.contrast = mat.contrast;
    s.relief = mat.relief_m;
    const float lambert = scene.ambient + (1.f - scene.ambient) * std::max(0.f, f.normal.dot(light));
    for (int c = 0; c < 3; ++c) s.col[c] = 255.f * lambert * mat.albedo[c];
  }
  return fs;
}

// Phase 3: per pixel, depth from inverse depth (with a relief's texture), the cosine of incidence
// and, with `shade`, the colour.
void shade_pixels(const std::vector<FaceShade>& fs, const CameraIntrinsics& K, bool shade,
                  RenderBuffers& out) {
  const int W = K.width, H = K.height;
  const float fx = K.fx, fy = K.fy, cx = K.cx, cy = K.cy;
  if (shade) out.color.create(H, W, CV_8UC3);
  constexpr int TN = detail::kTextureSize;
  std::vector<float> ray_norm_inv(static_cast<std::size_t>(W));
  for (int v = 0; v < H; ++v) {
    float* zrow = out.depth.ptr<float>(v);
    const int* frow = out.face.ptr<int>(v);
    float* crow = out.cos_incidence.ptr<float>(v);
    uchar* col = shade ? out.color.ptr<uchar>(v) : nullptr;
    const float fv = static_cast<float>(v);
    const float ry = (fv - cy) / fy;
    for (int u = 0; u < W; ++u) {
      const float rx = (static_cast<float>(u) - cx) / fx;
      ray_norm_inv[static_cast<std::size_t>(u)] = 1.f / std::sqrt(rx * rx + ry * ry + 1.f);
    }
    for (int u = 0; u < W; ++u) {
      const int fi = frow[u];
      if (fi < 0) {
        zrow[u] = 0.f;
        crow[u] = 0.f;
        if (col) col[3 * u] = col[3 * u + 1] = col[3 * u + 2] = 40;
        continue;
      }
      float z = 1.f / zrow[u];
      const FaceShade& s = fs[static_cast<std::size_t>(fi)];
      const float fu = static_cast<float>(u);
      if (s.relief > 0.f) {
        // A surface with a relief (carpet pile): the depth follows its texture, a few mm either way.
        const float ts = z * (s.su * fu + s.sv * fv + s.s0) + s.sb;
        const float tt = z * (s.tu * fu + s.tv * fv + s.t0) + s.tb;
        z += s.relief * texture_at(s, ts, tt);
      }
      zrow[u] = z;
      crow[u] = std::abs(s.nu * fu + s.nv * fv + s.n0) * ray_norm_inv[static_cast<std::size_t>(u)];
      if (!col) continue;
      float k = 1.f;
      if (s.contrast > 0.f) {
        const float ts = z * (s.su * fu + s.sv * fv + s.s0) + s.sb;
        const float tt = z * (s.tu * fu + s.tv * fv + s.t0) + s.tb;
        const int is = fast_floor(ts), it = fast_floor(tt);
        const float ax = ts - static_cast<float>(is), ay = tt - static_cast<float>(it);
        const int x0 = is & (TN - 1), y0 = it & (TN - 1);
        const int x1 = (x0 + 1) & (TN - 1), y1 = (y0 + 1) & (TN - 1);
        const float* tex = s.tex;
        const float a = tex[y0 * TN + x0], b = tex[y0 * TN + x1], c = tex[y1 * TN + x0],
                    d = tex[y1 * TN + x1];
        const float top = a + (b - a) * ax, bot = c + (d - c) * ax;
        k = std::max(0.05f, 1.f + s.contrast * (top + (bot - top) * ay));
      }
      for (int c = 0; c < 3; ++c) {
        const float x = s.col[c] * k;
        col[3 * u + c] = static_cast<uchar>(x >= 255.f ? 255 : static_cast<int>(x + 0.5f));
      }
    }
  }
}

}  // namespace

void render(const Scene& scene, const Pose& T_world_camera, const CameraIntrinsics& K, RenderBuffers& out,
            bool shade) {
  const int W = K.width, H = K.height;
  out.depth.create(H, W, CV_32FC1);
  out.face.create(H, W, CV_32SC1);
  out.cos_incidence.create(H, W, CV_32FC1);
  out.depth.setTo(0.f);  // holds inverse depth until the end; 0 = infinitely far
  out.face.setTo(-1);

  const Pose T_cw = T_world_camera.inverse();
  const std::vector<int> drawn = rasterize(scene, T_cw, K, out);
  shade_pixels(face_terms(scene, T_world_camera, T_cw.linear(), K, drawn), K, shade, out);
}

}  // namespace stairguide::synth
