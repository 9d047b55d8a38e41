// Drop-offs told per frame, scored against the synthetic truth (issue 42 item 4).
#include <cmath>
#include <cstdio>
#include <string>

#include "stairguide/core/json.hpp"
#include "stairguide/eval/stair_eval.hpp"

namespace stairguide {

namespace {

bool descent_in_view(const FrameTruth& t) {
  for (const StairTruth& s : t.stairs)
    if (s.goes_down() && s.user_step == 0 && (s.first_edge_visible || !s.visible_steps.empty())) return true;
  return false;
}

void add_to(DropEvalSummary& s, const DropSummary& told, const FrameTruth& truth, float near_m,
            bool floor_found) {
  ++s.frames;
  const bool yes = told.detected;
  if (truth.drop_in_view && truth.drop_distance_m <= near_m) {
    ++s.near;
    s.near_no_floor += !yes && !floor_found;
    if (!yes) return;
    ++s.near_told;
    s.distance.add(told.distance_m - truth.drop_distance_m);
    double db = rad2deg(told.bearing_rad - truth.drop_bearing_rad);
    s.bearing_deg.add(std::remainder(db, 360.0));
  } else if (truth.drop_in_view) {
    ++s.far;
    s.far_told += yes;
  } else if (truth.drop_depth_m > 0.f) {
    ++s.hidden;
    s.hidden_told += yes;
  } else if (descent_in_view(truth)) {
    ++s.descent;
    s.descent_told += yes;
    s.descent_by_stairs += told.by_stairs;
  } else {
    ++s.none;
    s.none_told += yes;
  }
}

std::string summary_json(const DropEvalSummary& s) {
  auto n = [](double v) { return json_number(v); };
  return "{\"frames\": " + n(s.frames) + ", \"near\": " + n(s.near) + ", \"near_told\": " + n(s.near_told) +
         ", \"near_rate\": " + n(s.near_rate()) + ", \"near_no_floor\": " + n(s.near_no_floor) +
         ", \"far\": " + n(s.far) + ", \"far_told\": " + n(s.far_told) + ", \"none\": " + n(s.none) +
         ", \"none_told\": " + n(s.none_told) + ", \"hidden\": " + n(s.hidden) +
         ", \"hidden_told\": " + n(s.hidden_told) + ", \"descent\": " + n(s.descent) +
         ", \"descent_told\": " + n(s.descent_told) + ", \"descent_by_stairs\": " + n(s.descent_by_stairs) +
         ", \"distance_err_mean_m\": " + n(s.distance.mean()) +
         ", \"distance_err_sigma_m\": " + n(s.distance.sigma()) +
         ", \"bearing_err_mean_abs_deg\": " + n(s.bearing_deg.mean_abs()) + "}";
}

std::string line(const std::string& name, const DropEvalSummary& s) {
  char b[320];
  std::snprintf(
      b, sizeof b,
      "%-28s %6d  %4d/%-4d %6.1f%% %3d  %4d/%-4d  %4d/%-4d  %4d/%-4d (%d by stairs)  %+6.2f %5.2f  %5.1f\n",
      name.c_str(), s.frames, s.near_told, s.near, 100.0 * s.near_rate(), s.near_no_floor, s.far_told, s.far,
      s.none_told, s.none, s.descent_told, s.descent, s.descent_by_stairs, s.distance.mean(),
      s.distance.sigma(), s.bearing_deg.mean_abs());
  return b;
}

}  // namespace

void DropEvalTable::add(const DropSummary& told, const FrameTruth& truth, const std::string& scene,
                        bool floor_found) {
  add_to(all, told, truth, near_m, floor_found);
  add_to(by_scene[scene], told, truth, near_m, floor_found);
}

std::string DropEvalTable::to_json() const {
  std::string o = summary_json(all);
  o.pop_back();
  o += ", \"near_m\": " + json_number(near_m) + ", \"by_scene\": {";
  bool first = true;
  for (const auto& [k, v] : by_scene) {
    o += (first ? "" : ", ") + json_quote(k) + ": " + summary_json(v);
    first = false;
  }
  return o + "}}";
}

std::string DropEvalTable::to_text() const {
  char head[400];
  std::snprintf(head, sizeof head,
                "\ndrops: told / frames (near: edge in view within %.1f m, nf: of its misses, no floor "
                "found; none: no drop "
                "nor descent in view)\n"
                "%-28s %6s  %-9s %7s %3s  %-9s  %-9s  %-9s                %6s %5s  %5s\n",
                static_cast<double>(near_m), "scene", "frames", "near", "rate", "nf", "far", "none",
                "descent", "d_err", "sd", "b_err");
  std::string o = head;
  for (const auto& [k, v] : by_scene) o += line(k, v);
  return o + line("all", all);
}

}  // namespace stairguide
