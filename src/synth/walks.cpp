// The traversal walks (issue 32, synth::walk_presets()): climbs and descents of 3, 8 and 14 steps
// onto a landing, one pausing and turning on the flight, one past a person on it.
#include <algorithm>
#include <cmath>

#include "presets_internal.hpp"

namespace stairguide::synth::detail {

using namespace presets;

namespace {

struct FlightWalk {
  StairKind kind = StairKind::kAscending;
  int steps = 8;
  float rate_lo = 0.8f, rate_hi = 1.0f;  // steps per second on the flight
  bool pause_turn = false;               // stop halfway up (or down) and look round to the left and back
  bool person = false;                   // a person standing at one side of the flight, facing the user
};

// Stand, walk ~2 m to the first edge, take the flight at the preset's rate (one tread per step),
// walk on along the landing, stand. With `pause_turn`, the walker stops on the middle tread for
// 2.4 s and turns 40 deg to the left and back while standing there.
void flight_walk(Rng& rng, const SynthOptions& o, PresetBuild& b, const FlightWalk& fw) {
  StairParams p;
  p.kind = fw.kind;
  p.steps = fw.steps;
  p.riser_m = rng.uniform(0.155f, 0.18f);
  p.tread_m = rng.uniform(0.28f, 0.32f);
  p.width_m = rng.uniform(1.1f, 1.5f);
  p.side_walls = true;
  p.handrails = rng.chance(0.5f);
  p.wall_start_m = -0.8f;
  p.top_depth_m = rng.uniform(1.8f, 2.6f);  // the landing (ascending) or the lower floor (descending)
  const bool down = fw.kind == StairKind::kDescending;
  const float edge_x = 2.4f;
  const float N = static_cast<float>(p.steps);
  p.T_world_stair = stair_pose(edge_x, 0.f, 0.f, down ? 0.f : p.riser_m);
  const float total = N * p.riser_m;
  const float end = edge_x + (N - 1.f) * p.tread_m + p.top_depth_m;
  if (down) {
    add_room_walls(b.scene, V2(-2.f, -2.4f), V2(end + 0.1f, 2.4f), -total - 0.2f, 2.9f + total,
                   wall_material(rng));
  } else {
    floor_and_room(b.scene, rng, V2(-2.f, -2.2f), V2(end + 0.1f, 2.2f));
  }
  add_crate(b.scene, V3(0.8f, down ? 1.9f : -1.7f, 0.f), 0.2f, V3(0.5f, 0.4f, 0.45f), wood_material(rng),
            "clutter");
  const int id = add_staircase(b.scene, p, rng);
  const StairSpec& st = b.scene.stairs[static_cast<std::size_t>(id)];
  float walker_y = 0.f;
  if (fw.person) {
    // At one side, two thirds of the way along the flight, facing down the flight toward the user;
    // the walker keeps to the other side.
    const float side = rng.chance(0.5f) ? 1.f : -1.f;
    const int k = std::max(2, (2 * p.steps) / 3);
    const V3 feet(edge_x + (static_cast<float>(k) - 0.5f) * st.tread_m, side * (0.5f * st.width_m - 0.28f),
                  st.tread_height(k));
    add_person(b.scene, feet, 3.14159265f + rng.uniform(-0.3f, 0.3f), rng.uniform(1.6f, 1.85f), rng);
    walker_y = -side * 0.22f;
  }
  WalkSpec& w = start_walk(rng, o, b);
  w.start = V3(0.f, walker_y, 0.f);
  stair_walk(w, st, edge_x);
  const float rate = rng.uniform(fw.rate_lo, fw.rate_hi);
  const double step_s = 1.0 / rate;
  const float stop = edge_x - (down ? 0.25f : 0.35f);
  const float last = edge_x + (N - 1.f) * p.tread_m + 0.35f;  // on the landing, past the last edge
  const double t_walk0 = 0.6, t_walk1 = 2.6, t_cross0 = 3.0;
  const double cross_s = step_s * static_cast<double>(p.steps);
  // The pause: on the middle tread's centre.
  const int mid = std::max(1, p.steps / 2);
  const float s_pause = edge_x + (static_cast<float>(mid) - 0.5f) * p.tread_m;
  const double f_pause = (s_pause - stop) / (last - stop);
  const double pause_s = fw.pause_turn ? 2.4 : 0.0;
  const double t_pause0 = t_cross0 + f_pause * cross_s, t_pause1 = t_pause0 + pause_s;
  const double t_cross1 = t_cross0 + cross_s + pause_s;
  w.duration_s = static_cast<float>(t_cross1 + 2.5);
  w.distance = [=](double t) -> float {
    if (t < t_cross0)
      return stop *
             smooth_ramp(static_cast<float>(t), static_cast<float>(t_walk0), static_cast<float>(t_walk1));
    double u = t - t_cross0;  // time walking on the flight
    if (t >= t_pause0) u -= std::min(t - t_pause0, pause_s);
    if (u < cross_s) return stop + (last - stop) * static_cast<float>(u / cross_s);
    return last + 1.0f * smooth_ramp(static_cast<float>(t), static_cast<float>(t_cross1),
                                     static_cast<float>(t_cross1 + 2.0));
  };
  const bool turn = fw.pause_turn;
  w.heading = [=](double t) {
    float h = deg2rad(3.f) * static_cast<float>(std::sin(0.6 * t));
    if (turn && t >= t_pause0 && t <= t_pause1) {
      const float tt = static_cast<float>(t);
      h += deg2rad(40.f) *
           (smooth_ramp(tt, static_cast<float>(t_pause0 + 0.2), static_cast<float>(t_pause0 + 0.9)) -
            smooth_ramp(tt, static_cast<float>(t_pause1 - 0.9), static_cast<float>(t_pause1 - 0.2)));
    }
    return h;
  };
}

// Frames a flight walk takes at 30 Hz (its slowest rate).
long flight_frames(const FlightWalk& fw) {
  const double cross = static_cast<double>(fw.steps) / fw.rate_lo + (fw.pause_turn ? 2.4 : 0.0);
  return static_cast<long>(std::ceil((3.0 + cross + 2.5) * 30.0));
}

PresetDef flight_def(const char* name, const char* summary, const FlightWalk& fw) {
  return def(name, summary, flight_frames(fw), true,
             [fw](Rng& r, const SynthOptions& o, PresetBuild& b) { flight_walk(r, o, b, fw); });
}

FlightWalk flight(StairKind kind, int steps, float rate_lo, float rate_hi, bool pause_turn = false,
                  bool person = false) {
  FlightWalk f;
  f.kind = kind;
  f.steps = steps;
  f.rate_lo = rate_lo;
  f.rate_hi = rate_hi;
  f.pause_turn = pause_turn;
  f.person = person;
  return f;
}

}  // namespace

const std::vector<PresetDef>& walk_defs() {
  static const std::vector<PresetDef> defs = {
      // Traversal walks (issue 32): the step under the body is each frame's truth (user_step).
      flight_def("climb_3_steps", "walk ~2 m to a 3-step flight, climb it at 0.5-0.7 steps/s onto a landing",
                 flight(StairKind::kAscending, 3, 0.5f, 0.7f)),
      flight_def("climb_8_steps", "walk ~2 m to an 8-step flight, climb it at 0.8-1.0 steps/s onto a landing",
                 flight(StairKind::kAscending, 8, 0.8f, 1.0f)),
      flight_def("climb_14_steps",
                 "walk ~2 m to a 14-step flight, climb it at 1.0-1.2 steps/s onto a landing",
                 flight(StairKind::kAscending, 14, 1.0f, 1.2f)),
      flight_def("climb_8_pause_turn",
                 "climb 8 steps at 0.7-0.9 steps/s, stopping on the middle one to look 40 deg left and back",
                 flight(StairKind::kAscending, 8, 0.7f, 0.9f, true)),
      flight_def("climb_8_person",
                 "climb 8 steps at 0.8-1.0 steps/s past a person standing at one side of the flight",
                 flight(StairKind::kAscending, 8, 0.8f, 1.0f, false, true)),
      flight_def("descend_3_steps", "walk ~2 m to the top of a 3-step flight, go down at 0.5-0.7 steps/s",
                 flight(StairKind::kDescending, 3, 0.5f, 0.7f)),
      flight_def("descend_8_steps", "walk ~2 m to the top of an 8-step flight, go down at 0.8-1.0 steps/s",
                 flight(StairKind::kDescending, 8, 0.8f, 1.0f)),
      flight_def("descend_14_steps", "walk ~2 m to the top of a 14-step flight, go down at 1.0-1.2 steps/s",
                 flight(StairKind::kDescending, 14, 1.0f, 1.2f)),
      flight_def(
          "descend_8_pause_turn",
          "go down 8 steps at 0.7-0.9 steps/s, stopping on the middle one to look 40 deg left and back",
          flight(StairKind::kDescending, 8, 0.7f, 0.9f, true)),
      flight_def("descend_8_person",
                 "go down 8 steps at 0.8-1.0 steps/s past a person standing at one side of the flight",
                 flight(StairKind::kDescending, 8, 0.8f, 1.0f, false, true)),
  };
  return defs;
}

}  // namespace stairguide::synth::detail
