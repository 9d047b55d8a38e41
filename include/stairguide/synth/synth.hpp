#pragma once
/// \file synth.hpp
/// The synthetic stair world: scenes of simple solids, a chest-mounted camera on a trajectory,
/// a Kinect-like sensor model, and per-frame ground truth. The project's ground truth for every
/// accuracy claim (the seed's real datasets cannot be had here).

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "stairguide/core/ground_truth.hpp"
#include "stairguide/core/source_error.hpp"
#include "stairguide/core/types.hpp"
#include "stairguide/synth/render.hpp"
#include "stairguide/synth/scene.hpp"
#include "stairguide/synth/trajectory.hpp"

namespace stairguide::synth {

/// One line per preset: name and what it shows.
struct PresetInfo {
  std::string name;
  std::string summary;
  long default_frames = 1;  ///< frames a full run of the preset takes (1 for a static view)
};

/// All presets (at least 20, covering ascending, descending, open risers, single step, curb,
/// distractors, occluding people, rotated staircase, ...).
const std::vector<PresetInfo>& presets();

/// The world's stairs: presets that draw riser, tread, width, nosing, open risers and landings
/// from the range of the building codes of the world (../shared/data/SOURCES.md: risers 10-22 cm,
/// treads 20-45 cm, 2R+T 50-72 cm, widths 0.65-2.6 m, 2-14 steps) rather than the paper's. Not in
/// presets(): the suites' figures rest on those draws. Every synth: input and make_source take
/// their names.
const std::vector<PresetInfo>& world_presets();
/// The traversal walks (issue 32): climbs and descents of 3, 8 and 14 steps onto a landing, one
/// pausing and turning on the flight, one past a person on it, each frame's truth giving the step
/// under the body (StairTruth::user_step). Every name that climbs says "climb", every one that goes
/// down "descen". Kept out of presets() so the suites that run every preset keep their figures;
/// make_source() and build_preset_frame() know them.
const std::vector<PresetInfo>& walk_presets();
/// Views from any chest or waist rig (issue 34): the camera 0.5-1.8 m high, tilted 15-80 deg, in an
/// empty room or before a table, bed, bench or raised landing 0.4-0.8 m below it. Kept out of
/// presets() so the suites that run every preset keep their figures.
const std::vector<PresetInfo>& rig_presets();
/// The second world (issue 39): what real stairs have and the first world lacked, and stair-free
/// furniture a looser decision could take for stairs. Static views, one drawn per frame: L- and
/// U-shaped stairs seen from their landing, low-riser and steep flights, carpeted and cluttered
/// flights, the wearer's own legs in view, low (waist or hip) rigs, and shelves, stacked boxes, a
/// sofa, a bench, a low table and a bed. Every parameter is drawn from the real world's range
/// (docs/synthetic.md), never from what the detector accepts. Kept out of presets() and
/// world_presets() so the suites that run those keep their figures.
const std::vector<PresetInfo>& world2_presets();
/// Drop-offs (issue 42 item 4): a platform edge, a loading dock, a hole, a sunken floor (static
/// views) and a walk towards a platform edge; FrameTruth's drop_* fields label them. Kept out of
/// the other lists so the suites that run those keep their figures.
const std::vector<PresetInfo>& drop_presets();
/// A preset or walk by name; nullptr when there is none.
const PresetInfo* find_preset_info(const std::string& name);

/// Sensor and trajectory options common to every preset.
struct SynthOptions {
  bool noise = true;  ///< Kinect-like depth noise, quantisation, holes
  int width = 640;
  int height = 480;
  /// Overrides of the camera mounting; NaN keeps the preset's (seeded) value.
  float camera_height_m = std::numeric_limits<float>::quiet_NaN();
  float camera_tilt_deg = std::numeric_limits<float>::quiet_NaN();
  float camera_roll_deg = std::numeric_limits<float>::quiet_NaN();
  /// Draws the sensor noise afresh for the same view (0: the frame's own noise): a wearer standing
  /// still sees one scene through a new noise on every frame.
  std::uint32_t noise_salt = 0;

  // ---- sensor model (Kinect v1 class); the range limits apply even with noise off ----
  float min_range_m = 0.5f;          ///< m, nearer surfaces give no reading
  float max_range_m = 5.0f;          ///< m, farther surfaces give no reading
  float grazing_max_deg = 78.f;      ///< deg, incidence beyond this gives no reading
  float sigma_coeff = 1.425e-3f;     ///< 1/m, depth sigma = sigma_coeff * z^2 (total, all effects)
  float disparity_focal_px = 580.f;  ///< px, focal length of the sensor's own IR camera (640 wide)
  float baseline_m = 0.075f;         ///< m, projector-camera baseline
  float disparity_step_px = 0.125f;  ///< px, disparity quantisation (1/8 px)
  float depth_step_m = 0.001f;       ///< m, depth rounding of the driver (OpenNI: 1 mm)
  bool shadows = true;               ///< holes where the projector cannot see (occlusion shadows)
  float edge_jump_abs_m = 0.02f;     ///< m, a neighbour nearer by more than abs + rel*z ...
  float edge_jump_rel = 0.04f;       ///< ... makes a pixel a hole (mixed pixels at discontinuities)
  float dropout = 0.002f;            ///< fraction of valid pixels dropped at random
  /// Spatial correlation of the disparity noise. A structured-light sensor matches a window of the
  /// speckle pattern, so neighbouring pixels share their error; the default is white noise (each
  /// pixel its own draw). These shares of the Gaussian part's variance are instead blurred over
  /// noise_short_px and noise_long_px (Gaussian sigmas); its total stays the same. 0 and 0: white,
  /// as every figure of the test suite was measured. with_real_kinect_noise() sets what the real
  /// clouds show.
  float noise_short_share = 0.f;
  float noise_short_px = 2.f;  ///< px
  float noise_long_share = 0.f;
  float noise_long_px = 10.f;  ///< px
  // ---- artefacts seen on the real frames; all off by default (the suites were measured without).
  // Not part of the ground truth's visibility (like the random dropout). with_real_artefacts(). ----
  float speckle_holes = 0.f;  ///< share of the image lost in small blobs (radius 1-3 px) at random
  float dark_surface_chance =
      0.f;  ///< chance that a face is dark (half of them) or glossy (the other half) ...
  float dark_surface_range_m = 2.0f;  ///< m, ... a dark face gives no reading beyond this; a glossy one none
                                      ///< where it faces the ray within 12 deg
  float flying_pixels = 0.f;  ///< chance that a pixel beside a depth jump reads a depth between the two sides
  /// Kinect v2 (time of flight) instead of v1 (structured light): Gaussian depth noise of sigma
  /// tof_sigma_m + tof_sigma_per_m2 * z^2 rounded to depth_step_m, no disparity quantisation and no
  /// projector shadows; grazing and jump holes as before.
  bool time_of_flight = false;
  float tof_sigma_m = 0.0015f;       ///< m
  float tof_sigma_per_m2 = 0.0005f;  ///< 1/m
  /// Time of flight only: multipath interference near concave corners (light reaching one
  /// surface by way of the other comes back late), the depth reading up to multipath_m too far at
  /// the corner and fading linearly to nothing multipath_range_m away from it. 0: none (every
  /// suite before the second world).
  float multipath_m = 0.f;
  float multipath_range_m = 0.15f;  ///< m
  /// px, the band lost on the far side of a depth jump (a structured-light matcher's window
  /// straddling the jump); 1 = the neighbouring pixel only, as every suite before it was measured.
  int edge_hole_px = 1;
  /// px, focal length (fx = fy) at the output size; NaN: 525 px at 640x480 scaled with the size
  /// (synthetic_intrinsics). A Kinect v2's own depth camera: about 365 px at 512x424.
  float focal_px = std::numeric_limits<float>::quiet_NaN();
  float color_noise = 2.0f;  ///< grey levels, sigma of the colour noise
  double fps = 30.0;         ///< Hz, frame rate of the timestamps
};

/// `o` with depth noise correlated in space as the real Kinect clouds' (shared data
/// pcl-kinect-clouds): the residuals of their 12 big planes correlate 0.73 between neighbouring
/// pixels, 0.39 at 4 px and 0.14 at 8 px on average, where the default white noise gives 0.05 and
/// less. Shares 0.6 over 2 px and 0.4 over 10 px give 0.77, 0.40 and 0.22 (PerceptionRealData.
/// SyntheticNoiseCorrelatedAsTheRealClouds).
SynthOptions with_real_kinect_noise(SynthOptions o = {});

/// Which real sensor's artefacts with_real_artefacts() adds. kKinectV2Native and
/// kStructuredLight (the second world, issue 39) add what the first two left out: the Kinect v2's
/// own depth camera (512x424, f 365 px, 70 x 60 deg) with multipath near concave corners, and a
/// structured-light sensor's matcher losing a 3-px band behind depth edges.
enum class RealSensor { kKinectV1, kKinectV2, kKinectV2Native, kStructuredLight };

/// `o` with the artefacts of the real frames of ../shared/data: speckle holes (0.5% of the image),
/// dark or glossy faces (one in ten: a dark one reads nothing beyond 2 m, a glossy one nothing
/// where it faces the ray), flying pixels at depth jumps (30%);
/// Kinect v1: the real-like correlated noise (with_real_kinect_noise) and its disparity
/// quantisation; Kinect v2: time of flight at 512x424.
SynthOptions with_real_artefacts(RealSensor sensor, SynthOptions o = {});

/// The sensor model a synth: input's NOISE field names, applied to `o`: "white" (the defaults),
/// "kinect" (with_real_kinect_noise), "real-v1" / "real-v2" (with_real_artefacts, Kinect v1 / v2),
/// "tof-v2" (kKinectV2Native: the Kinect v2's own camera, multipath) and "sl-v1"
/// (kStructuredLight: real-v1 with the matcher's 3-px band lost behind depth edges). False for
/// any other name (`o` unchanged).
bool sensor_options(const std::string& noise, SynthOptions& o);
/// The names sensor_options() knows, for messages.
const char* sensor_names();

/// Everything needed to render one frame of a preset: the scene and the walker's state.
struct PresetFrame {
  Scene scene;
  WalkerState walker;
};

/// Builds the scene and camera state of frame `index` of `preset` (no rendering). Static presets
/// draw a new scene and view for every index; sequences keep one scene and follow a trajectory.
/// Throws SourceError for an unknown preset.
PresetFrame build_preset_frame(const std::string& preset, long index, std::uint32_t seed,
                               const SynthOptions& options = {});

/// Ground truth of a rendered frame, read off the ideal render (`ideal`: the noise-free render of
/// `scene` from `walker.T_world_camera`):
///  - camera_height_m: camera height above the tread/floor under the user's body (walker.support_z);
///  - floor_visible: >= 5% of the pixels see, within the sensor's range, an upward surface at that height;
///  - per staircase: T_camera_stair; visible_steps: treads 1..steps (tread `steps` = the landing or
///    floor after the last riser) with >= 200 pixels within range that keep a depth reading under the
///    sensor model (its holes at grazing incidence, depth jumps and shadows; not its random dropout),
///    visible_pixels their counts; first_edge_visible: an unoccluded
///    stretch of at least min(0.5 m, half the width) of the first edge is in view and in range (an
///    edge point is seen when a pixel of its 3x3 neighbourhood has its depth within 1 cm + 1%);
///    both_ends_visible: both ends (2-3 cm inside) are seen; user_step: tread under the body.
FrameTruth compute_truth(const Scene& scene, const WalkerState& walker, const RenderBuffers& ideal,
                         const CameraIntrinsics& K, const SynthOptions& options);

/// Renders frame `index` of `preset` into `frame` (depth, colour, grey, timestamp, intrinsics) and
/// its ground truth into `truth`. What a synthetic FrameSource does for each read.
void render_preset_frame(const std::string& preset, long index, std::uint32_t seed,
                         const SynthOptions& options, RgbdFrame& frame, FrameTruth& truth);

/// Intrinsics of the synthetic camera: fx = fy = 525, cx = 319.5, cy = 239.5 at 640x480,
/// scaled to options.width x options.height.
CameraIntrinsics synthetic_intrinsics(const SynthOptions& options);

namespace detail {
struct PresetDef;
}  // namespace detail

/// Renders the frames of one preset in turn, keeping a sequence's scene and walk between frames:
/// what the synthetic FrameSource (capture/synth_source.hpp, `synth:` inputs) reads.
class PresetRenderer {
 public:
  /// `frames` <= 0 takes the preset's default_frames; a sequence asked for more frames than its
  /// default holds its final pose. Throws SourceError for an unknown preset name (the message lists
  /// the known ones) or bad options.
  PresetRenderer(const std::string& preset, long frames, std::uint32_t seed,
                 const SynthOptions& options = {});

  /// Renders frame `index` (0 .. frames() - 1) into `frame` (depth, colour, grey, timestamp
  /// index / fps, intrinsics) and its ground truth into `truth`.
  void render(long index, RgbdFrame& frame, FrameTruth& truth);

  long frames() const { return frames_; }
  /// True for a walk (one scene, a trajectory); false for a static preset, which draws a new scene
  /// and view for every index (consecutive frames are unrelated).
  bool sequence() const;
  const PresetInfo& info() const;
  CameraIntrinsics intrinsics() const { return synthetic_intrinsics(options_); }

 private:
  const detail::PresetDef* def_;
  std::uint32_t seed_;
  SynthOptions options_;
  long frames_ = 1;
  Scene scene_;  // sequences: built once
  Walk walk_;
  RenderBuffers buf_;
};

}  // namespace stairguide::synth
