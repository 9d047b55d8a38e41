// Procedural textures: tileable value noise and patterns, so that every surface has intensity
// gradients for photometric odometry. Made once per process from fixed seeds (deterministic).
#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "stairguide/synth/builders.hpp"
#include "internal.hpp"

namespace stairguide::synth::detail {
namespace {

constexpr int N = kTextureSize;

float smoother(float x) { return x * x * x * (x * (x * 6.f - 15.f) + 10.f); }

// One octave of tileable value noise with `cells_x` x `cells_y` lattice cells over the tile.
void add_value_noise(std::vector<float>& img, int cells_x, int cells_y, float amp, Rng& rng) {
  std::vector<float> lattice(static_cast<std::size_t>(cells_x * cells_y));
  for (auto& v : lattice) v = rng.uniform(-1.f, 1.f);
  const float sx = static_cast<float>(cells_x) / N, sy = static_cast<float>(cells_y) / N;
  for (int y = 0; y < N; ++y) {
    const float fy = static_cast<float>(y) * sy;
    const int y0 = static_cast<int>(fy);
    const float ty = smoother(fy - static_cast<float>(y0));
    const int ya = y0 % cells_y, yb = (y0 + 1) % cells_y;
    for (int x = 0; x < N; ++x) {
      const float fx = static_cast<float>(x) * sx;
      const int x0 = static_cast<int>(fx);
      const float tx = smoother(fx - static_cast<float>(x0));
      const int xa = x0 % cells_x, xb = (x0 + 1) % cells_x;
      const float a = lattice[static_cast<std::size_t>(ya * cells_x + xa)];
      const float b = lattice[static_cast<std::size_t>(ya * cells_x + xb)];
      const float c = lattice[static_cast<std::size_t>(yb * cells_x + xa)];
      const float d = lattice[static_cast<std::size_t>(yb * cells_x + xb)];
      img[static_cast<std::size_t>(y * N + x)] +=
          amp * ((a + (b - a) * tx) + ((c + (d - c) * tx) - (a + (b - a) * tx)) * ty);
    }
  }
}

void normalise(std::vector<float>& img) {
  double s = 0, s2 = 0;
  for (float v : img) {
    s += v;
    s2 += static_cast<double>(v) * v;
  }
  const double n = static_cast<double>(img.size());
  const double mean = s / n;
  const double sd = std::sqrt(std::max(1e-12, s2 / n - mean * mean));
  for (float& v : img) v = static_cast<float>((v - mean) / sd);
}

std::vector<float> make(Texture t) {
  std::vector<float> img(static_cast<std::size_t>(N * N), 0.f);
  Rng rng(mix_seed(0x7e47u, static_cast<std::uint64_t>(t)));
  const float kTwoPi = 6.2831853f;
  switch (t) {
    case Texture::kPlain:
      add_value_noise(img, 4, 4, 1.0f, rng);
      add_value_noise(img, 16, 16, 0.5f, rng);
      add_value_noise(img, 64, 64, 0.25f, rng);
      break;
    case Texture::kTiles: {
      add_value_noise(img, 8, 8, 0.4f, rng);
      add_value_noise(img, 64, 64, 0.3f, rng);
      std::array<float, 16> tile{};
      for (auto& v : tile) v = rng.uniform(-0.4f, 0.4f);
      for (int y = 0; y < N; ++y)
        for (int x = 0; x < N; ++x) {
          float& v = img[static_cast<std::size_t>(y * N + x)];
          v += tile[static_cast<std::size_t>((y / 64) * 4 + x / 64)];
          if (x % 64 < 2 || y % 64 < 2) v -= 2.0f;  // grout lines every 32 cm
        }
      break;
    }
    case Texture::kWood: {
      std::vector<float> warp(static_cast<std::size_t>(N * N), 0.f);
      add_value_noise(warp, 2, 8, 1.f, rng);
      add_value_noise(img, 64, 4, 0.3f, rng);
      for (int y = 0; y < N; ++y)
        for (int x = 0; x < N; ++x) {
          const float w = warp[static_cast<std::size_t>(y * N + x)];
          img[static_cast<std::size_t>(y * N + x)] +=
              std::sin(kTwoPi * (static_cast<float>(y) * 12.f / N + 0.8f * w));  // grain along s
        }
      break;
    }
    case Texture::kCarpet:
      add_value_noise(img, 128, 128, 1.0f, rng);
      add_value_noise(img, 32, 32, 0.5f, rng);
      add_value_noise(img, 8, 8, 0.4f, rng);
      break;
    case Texture::kConcrete: {
      add_value_noise(img, 8, 8, 0.6f, rng);
      add_value_noise(img, 32, 32, 0.5f, rng);
      add_value_noise(img, 128, 128, 0.35f, rng);
      for (int i = 0; i < 600; ++i) {  // pores and pebbles
        const int x = rng.integer(0, N - 1), y = rng.integer(0, N - 1);
        const float a = rng.uniform(-2.f, 1.5f);
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx)
            img[static_cast<std::size_t>(((y + dy + N) % N) * N + (x + dx + N) % N)] +=
                a * ((dx == 0 && dy == 0) ? 1.f : 0.4f);
      }
      break;
    }
    case Texture::kFabric:
      add_value_noise(img, 16, 16, 0.5f, rng);
      for (int y = 0; y < N; ++y)
        for (int x = 0; x < N; ++x)
          img[static_cast<std::size_t>(y * N + x)] += 0.6f * std::sin(kTwoPi * static_cast<float>(x) / 4.f) *
                                                      std::sin(kTwoPi * static_cast<float>(y) / 4.f);
      break;
    case Texture::kCount: break;
  }
  normalise(img);
  return img;
}

}  // namespace

const float* texture(Texture t) {
  static const std::vector<std::vector<float>> all = [] {
    std::vector<std::vector<float>> v;
    for (int i = 0; i < static_cast<int>(Texture::kCount); ++i) v.push_back(make(static_cast<Texture>(i)));
    return v;
  }();
  const int i = static_cast<int>(t);
  return all[static_cast<std::size_t>(i < static_cast<int>(Texture::kCount) ? i : 0)].data();
}

const float* gaussian_table() {
  static const std::vector<float> table = [] {
    std::vector<float> g(kGaussianMask + 1);
    Rng rng(0x6a055u);
    for (auto& v : g) v = rng.normal();
    normalise(g);
    return g;
  }();
  return table.data();
}

}  // namespace stairguide::synth::detail
