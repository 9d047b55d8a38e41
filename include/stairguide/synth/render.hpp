#pragma once
/// \file render.hpp
/// Renderer and sensor model of the synthetic stair world.
///
/// `render` rasterises the scene's planar faces with an inverse-depth buffer (exact per-pixel
/// ray/plane depth at pixel centres: pixel (u, v) looks along ((u-cx)/fx, (v-cy)/fy, 1)), and
/// shades colour with procedural textures and Lambert lighting. `apply_depth_sensor` turns the
/// ideal depth into Kinect-like depth; `apply_color_sensor` adds image noise.

#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "stairguide/synth/scene.hpp"
#include "stairguide/core/types.hpp"

namespace stairguide::synth {

struct SynthOptions;

/// Per-pixel output of the renderer (all CV_* images of the intrinsics' size).
struct RenderBuffers {
  cv::Mat depth;          ///< CV_32FC1, ideal z-depth in m along the optical axis, 0 = no surface
  cv::Mat face;           ///< CV_32SC1, index into Scene::faces(), -1 = no surface
  cv::Mat cos_incidence;  ///< CV_32FC1, |cos| of the angle between the pixel ray and the normal
  cv::Mat color;          ///< CV_8UC3 BGR, noise-free shaded colour (empty when not shaded)
};

/// Renders `scene` seen from `T_world_camera` (camera x right, y down, z forward).
/// Deterministic; prints nothing. `shade` = false skips colour (depth, face and incidence only).
void render(const Scene& scene, const Pose& T_world_camera, const CameraIntrinsics& K, RenderBuffers& out,
            bool shade = true);

/// The pixels the depth sensor loses whatever the noise draws (grazing incidence, the far side of
/// depth discontinuities, projector shadows): `hole` (W*H, row-major) is 1 there. None when
/// `options.noise` is false. Range limits and random dropout are not part of it.
void depth_sensor_holes(const RenderBuffers& ideal, const CameraIntrinsics& K, const SynthOptions& options,
                        std::vector<unsigned char>& hole);

/// Kinect-like depth from the ideal render: holes (outside [min, max] range, grazing incidence,
/// depth discontinuities, projector shadows, random dropouts), disparity noise and quantisation,
/// millimetre rounding. With `options.noise` false only the range limits apply.
/// `seed` selects the noise realisation (same seed => same output).
void apply_depth_sensor(const RenderBuffers& ideal, const CameraIntrinsics& K, const SynthOptions& options,
                        std::uint64_t seed, cv::Mat& depth_out);

/// Colour with sensor noise (a copy of the render when `options.noise` is false) and its grey image.
void apply_color_sensor(const RenderBuffers& ideal, const SynthOptions& options, std::uint64_t seed,
                        cv::Mat& color_out, cv::Mat& gray_out);

/// Depth standard deviation (m) the sensor model exhibits at depth z (m): coefficient * z^2.
float depth_sigma_model(float z, const SynthOptions& options);

/// Standard deviation (px) of the Gaussian disparity noise the model draws at depth z, chosen so
/// that Gaussian noise + disparity quantisation + depth rounding together give
/// depth_sigma_model(z) (quantisation counted as uniform: step^2/12 in variance).
float disparity_noise_sigma(float z, const SynthOptions& options);

}  // namespace stairguide::synth
