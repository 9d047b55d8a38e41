#include "stairguide/core/config.hpp"

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <string>
#include <type_traits>

namespace stairguide {

double unit_to_si(Unit u) {
  switch (u) {
    case Unit::kCentimetre: return 0.01;
    case Unit::kMillimetre: return 0.001;
    case Unit::kDegree: return M_PI / 180.0;
    case Unit::kPercent: return 0.01;
    case Unit::kMillisecond: return 0.001;
    default: return 1.0;
  }
}

const char* unit_name(Unit u) {
  switch (u) {
    case Unit::kMetre: return "m";
    case Unit::kCentimetre: return "cm";
    case Unit::kMillimetre: return "mm";
    case Unit::kDegree: return "deg";
    case Unit::kPercent: return "%";
    case Unit::kSecond: return "s";
    case Unit::kMillisecond: return "ms";
    case Unit::kHertz: return "Hz";
    case Unit::kPerMetre: return "1/m";
    case Unit::kPixel: return "px";
    case Unit::kCount: return "";
    case Unit::kNone: return "";
  }
  return "";
}

namespace {

/// Walks two configs side by side; `b_fields` holds b's values in visit order.
struct Collector {
  std::vector<double> nums;
  std::vector<std::string> texts;
  template <class T>
  void num(T& f, const char*, Unit, double, double, const char*) {
    nums.push_back(static_cast<double>(f));
  }
  void flag(bool& f, const char*, const char*) { nums.push_back(f ? 1.0 : 0.0); }
  void text(std::string& f, const char*, std::initializer_list<const char*>, const char*) {
    texts.push_back(f);
  }
  template <class S>
  void section(const char*, const char*, S& s) {
    s.visit(*this);
  }
};

struct Comparer {
  const Collector& other;
  std::string prefix;
  std::size_t ni = 0, ti = 0;
  std::string diff;
  template <class T>
  void num(T& f, const char* key, Unit, double, double, const char*) {
    const double a = static_cast<double>(f), b = other.nums[ni++];
    const bool same = std::is_floating_point<T>::value
                          ? std::fabs(a - b) <= 1e-6 * std::max(1.0, std::max(std::fabs(a), std::fabs(b)))
                          : a == b;
    if (!same && diff.empty()) diff = prefix + key;
  }
  void flag(bool& f, const char* key, const char*) {
    if ((f ? 1.0 : 0.0) != other.nums[ni++] && diff.empty()) diff = prefix + key;
  }
  void text(std::string& f, const char* key, std::initializer_list<const char*>, const char*) {
    if (f != other.texts[ti++] && diff.empty()) diff = prefix + key;
  }
  template <class S>
  void section(const char* name, const char*, S& s) {
    const std::string saved = prefix;
    prefix = saved + name + ".";
    s.visit(*this);
    prefix = saved;
  }
};

}  // namespace

bool config_equal(const PipelineConfig& a, const PipelineConfig& b, std::string* first_difference) {
  Collector cb;
  const_cast<PipelineConfig&>(b).visit(cb);
  Comparer cmp{cb, "", 0, 0, {}};
  const_cast<PipelineConfig&>(a).visit(cmp);
  if (first_difference) *first_difference = cmp.diff;
  return cmp.diff.empty();
}

std::vector<ConfigInconsistency> find_inconsistencies(const PipelineConfig& c) {
  std::vector<ConfigInconsistency> out;
  auto order = [&](double lo, double hi, const char* klo, const char* khi) {
    if (lo > hi) out.push_back({klo, khi, std::string(klo) + " must not exceed " + khi});
  };
  // An empty depth range would make every reading no reading: every frame blank, silently.
  if (!(c.capture.min_range < c.capture.max_range))
    out.push_back({"capture.min_range_m", "capture.max_range_m",
                   "capture.min_range_m must be below capture.max_range_m (no depth would be left)"});
  order(c.capture.retry_min, c.capture.retry_max, "capture.retry_min_s", "capture.retry_max_s");
  order(c.floor.tilt_min, c.floor.tilt_max, "floor.tilt_min_deg", "floor.tilt_max_deg");
  order(c.floor.height_min, c.floor.height_max, "floor.height_min_m", "floor.height_max_m");
  order(c.floor.usual_tilt_min, c.floor.usual_tilt_max, "floor.usual_tilt_min_deg",
        "floor.usual_tilt_max_deg");
  order(c.floor.usual_height_min, c.floor.usual_height_max, "floor.usual_height_min_m",
        "floor.usual_height_max_m");
  order(c.classification.step_height_min, c.classification.step_height_max,
        "classification.step_height_min_cm", "classification.step_height_max_cm");
  order(c.stair_detection.floorless_tilt_min, c.stair_detection.floorless_tilt_max,
        "stair_detection.floorless_tilt_min_deg", "stair_detection.floorless_tilt_max_deg");
  order(c.stair_modelling.riser_min, c.stair_modelling.riser_max, "stair_modelling.riser_min_cm",
        "stair_modelling.riser_max_cm");
  order(c.stair_modelling.blondel_min, c.stair_modelling.blondel_max, "stair_modelling.blondel_min_cm",
        "stair_modelling.blondel_max_cm");
  // The approach beep quickens as the edge nears: the near interval is the shorter, the near
  // distance inside the range (a range of 0 turns the beep off and leaves them unused).
  order(c.feedback.approach_interval_near, c.feedback.approach_interval_far,
        "feedback.approach_interval_near_s", "feedback.approach_interval_far_s");
  order(c.feedback.battery_critical, c.feedback.battery_low, "feedback.battery_critical_percent",
        "feedback.battery_low_percent");
  // The button: a bounce shorter than the gap of a double press, and not the buzzer's own line.
  if (!(c.feedback.button_debounce < c.feedback.button_double_press))
    out.push_back({"feedback.button_debounce_s", "feedback.button_double_press_s",
                   "feedback.button_debounce_s must be below feedback.button_double_press_s"});
  if (c.feedback.button_enabled && c.feedback.haptic_enabled &&
      c.feedback.button_chip == c.feedback.gpio_chip && c.feedback.button_line == c.feedback.gpio_line &&
      c.feedback.button_chip.rfind("file:", 0) != 0)
    out.push_back(
        {"feedback.gpio_line", "feedback.button_line",
         "feedback.button_line is the buzzer's line (feedback.gpio_chip, feedback.gpio_line): one line "
         "cannot be both"});
  // The language names a folder under sounds_dir: a plain name ("es", "pt-br"), never a path.
  const std::string& lang = c.feedback.language;
  const bool lang_ok =
      !lang.empty() && lang.size() <= 16 && std::all_of(lang.begin(), lang.end(), [](char ch) {
        return (ch >= 'a' && ch <= 'z') || (ch >= '0' && ch <= '9') || ch == '-' || ch == '_';
      });
  if (!lang_ok)
    out.push_back({"feedback.language", "feedback.language",
                   "feedback.language '" + lang +
                       "' is not a language name (lower-case letters, digits, '-': en, es, de, fr)"});
  if (c.feedback.approach_range > 0.f && !(c.feedback.approach_near < c.feedback.approach_range))
    out.push_back({"feedback.approach_near_m", "feedback.approach_range_m",
                   "feedback.approach_near_m must be below feedback.approach_range_m (or the range 0: off)"});
  return out;
}

std::vector<std::string> check_consistency(const PipelineConfig& c) {
  std::vector<std::string> out;
  for (const auto& p : find_inconsistencies(c)) out.push_back(p.message);
  return out;
}

}  // namespace stairguide
