// A whole-folder labels.yaml written by hand (dataset.hpp, read_folder_label_yaml): every frame of
// the folder carries it, without a pose; bad files are refused naming the file, the line and the key.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "capture_test_util.hpp"
#include "stairguide/capture/dataset.hpp"
#include "stairguide/capture/frame_source.hpp"

namespace fs = std::filesystem;
using namespace stairguide;

namespace {

fs::path scratch(const std::string& name) { return test::scratch("capture_folder_label", name); }

fs::path dataset_with_label(const std::string& name, const std::string& label) {
  const fs::path d = scratch(name);
  const auto frames = test::make_frames(3, 32, 24, 9, 4000, 3.0);
  DatasetWriter w(d.string(), frames[0].intrinsics);
  for (const auto& f : frames) w.write(f);
  w.close();
  std::ofstream(d / "labels.yaml") << label;
  return d;
}

const char* kGood =
    "# by hand\n"
    "format: stairguide-labels-1\n"
    "folder:\n"
    "  scene: \"stairwell\"\n"
    "  floor_visible: true\n"
    "  stairs:\n"
    "    - kind: ascending\n"
    "      riser_m: 0.152\n"
    "      tread_m: 0.245\n"
    "      width_m: 1.27\n"
    "      visible_steps: [1, 2, 3]\n"
    "    - kind: curb\n"
    "      down: true\n";

}  // namespace

TEST(FolderLabel, EveryFrameCarriesTheFolderLabelWithoutAPose) {
  const fs::path d = dataset_with_label("good", kGood);
  DatasetSource src(d.string());
  EXPECT_TRUE(src.has_labels());
  EXPECT_NE(src.describe().find("one label for the folder"), std::string::npos) << src.describe();
  RgbdFrame f;
  int n = 0;
  while (src.read(f).ok()) {
    const auto t = src.truth();
    ASSERT_TRUE(t.has_value());
    EXPECT_FALSE(t->pose_known);
    EXPECT_EQ(t->index, f.index);
    EXPECT_DOUBLE_EQ(t->timestamp, f.timestamp);
    EXPECT_EQ(t->scene, "stairwell");
    EXPECT_TRUE(t->floor_visible);
    ASSERT_EQ(t->stairs.size(), 2u);
    const StairTruth& s = t->stairs[0];
    EXPECT_EQ(s.kind, StairKind::kAscending);
    EXPECT_FLOAT_EQ(s.riser_m, 0.152f);
    EXPECT_FLOAT_EQ(s.tread_m, 0.245f);
    EXPECT_FLOAT_EQ(s.width_m, 1.27f);
    EXPECT_EQ(s.visible_steps, (std::vector<int>{1, 2, 3}));
    EXPECT_TRUE(s.first_edge_visible);
    EXPECT_FALSE(s.both_ends_visible);
    EXPECT_FALSE(s.goes_down());
    EXPECT_EQ(t->stairs[1].kind, StairKind::kCurb);
    EXPECT_TRUE(t->stairs[1].goes_down());
    EXPECT_EQ(t->stairs[1].visible_steps, (std::vector<int>{1}));  // one step: one tread by default
    ++n;
  }
  EXPECT_EQ(n, 3);
}

TEST(FolderLabel, APerFrameFileIsStillReadAsOne) {
  FrameTruth t;
  const fs::path d = scratch("per_frame");
  fs::create_directories(d);
  std::ofstream(d / "labels.yaml") << labels_to_yaml({});
  EXPECT_FALSE(read_folder_label_yaml((d / "labels.yaml").string(), t));
  EXPECT_TRUE(t.pose_known);
}

TEST(FolderLabel, BadFilesNameTheFileLineAndKey) {
  struct Case {
    const char* name;
    std::string text;
    const char* expect;
  };
  const std::string head = "format: stairguide-labels-1\nfolder:\n  scene: s\n";
  const Case cases[] = {
      {"unknown", head + "  stairs: []\n  colour: red\n", "unknown key 'colour'"},
      {"per_frame", head + "  stairs: []\n  T_world_camera: [1]\n",
       "key 'T_world_camera' is a per-frame value"},
      {"pose", head + "  stairs:\n    - kind: ascending\n      T_camera_stair: [1]\n",
       "key 'T_camera_stair' is a per-frame value"},
      {"curb", head + "  stairs:\n    - kind: curb\n", "a curb needs 'down: true'"},
      {"kind", head + "  stairs:\n    - kind: ramp\n", "unknown stair kind 'ramp'"},
      {"riser", head + "  stairs:\n    - kind: ascending\n      riser_m: -0.1\n",
       "key 'riser_m' = -0.1 is out of range"},
      {"no_stairs", head, "missing key 'stairs'"},
      {"both", head + "  stairs: []\nframes: []\n", "either 'folder' (one label) or 'frames'"},
      {"format", "format: other\nfolder:\n  scene: s\n  stairs: []\n", "unknown format 'other'"},
      {"down", head + "  stairs:\n    - kind: ascending\n      down: true\n", "cannot go down"},
      // The strict reading of every YAML input (strict_yaml.hpp): the later value is not dropped.
      {"twice", head + "  stairs: []\n  scene: t\n", "key 'folder.scene' given twice (first on line 3)"},
      {"second_document", head + "  stairs: []\n---\nformat: x\n", "document"},
  };
  for (const Case& c : cases) {
    const fs::path d = dataset_with_label(c.name, c.text);
    const std::string e = test::error_of([&] { DatasetSource src(d.string()); });
    EXPECT_NE(e.find("labels.yaml:"), std::string::npos) << c.name << ": " << e;
    EXPECT_NE(e.find(c.expect), std::string::npos) << c.name << ": " << e;
  }
}
