#pragma once
// Small helpers shared by the capture sources (private to src/capture).
#include <opencv2/core.hpp>
#include <string>

namespace YAML {
class Node;
}

namespace stairguide {

std::string trim(const std::string& s);
/// Whole-string number parse (no trailing junk); false on failure or non-finite.
bool parse_double(const std::string& s, double& out);
/// Shortest round-trip text of a number ("525", "319.5", "0.001").
std::string fmt_num(double v);
/// "16-bit 1-channel", "8-bit 3-channel", "empty".
std::string describe_mat_type(const cv::Mat& m);
/// Metres (CV_32FC1, 0 = none) to CV_16UC1 units: round(d * scale); NaN, <= 0 and > 65535 units -> 0.
cv::Mat depth_to_u16(const cv::Mat& depth_m, double scale);
/// "missing (no such file)" when `why` (why_unreadable) says so, else "cannot read WHAT (why)":
/// the words for a file that could not be opened, its cause named.
std::string unreadable_words(const std::string& why, const std::string& what);
/// Lower-case file extension with the dot (".oni"), "" when none.
std::string lower_extension(const std::string& path);
/// A labels.yaml (per-frame or whole-folder) read strictly (strict_yaml.hpp: one document, no key
/// twice, bounded size and nodes); throws SourceError naming the file.
YAML::Node load_labels_file(const std::string& path);

}  // namespace stairguide
