// Config loader: the shipped file, and each kind of invalid input with file, line and key.
#include <gtest/gtest.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <future>
#include <string>

#include "stairguide/config/config_loader.hpp"

using namespace stairguide;

namespace {

const std::string kShipped = std::string(STAIRGUIDE_SOURCE_DIR) + "/config/stairguide.yaml";

std::string write_tmp(const std::string& name, const std::string& text) {
  const std::string path = std::string(STAIRGUIDE_BINARY_DIR) + "/test_config_" + name + ".yaml";
  std::ofstream(path) << text;
  return path;
}

/// Loads text that must fail and returns the message.
std::string error_of(const std::string& name, const std::string& text) {
  const std::string path = write_tmp(name, text);
  try {
    load_config(path);
  } catch (const ConfigError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no error for " << name;
  return "";
}

}  // namespace

TEST(Config, ShippedFileEqualsStructDefaultsAndNamesEveryKey) {
  ConfigLoadReport report;
  const PipelineConfig loaded = load_config(kShipped, &report);
  std::string diff;
  EXPECT_TRUE(config_equal(loaded, PipelineConfig{}, &diff)) << "first difference: " << diff;
  EXPECT_TRUE(report.missing_keys.empty()) << "shipped file lacks " << report.missing_keys.front();
}

TEST(Config, PaperValuesAreTheDefaults) {
  const PipelineConfig c;
  EXPECT_FLOAT_EQ(c.segmentation.voxel_size, 0.04f);
  EXPECT_FLOAT_EQ(c.segmentation.normal_radius, 0.05f);
  EXPECT_NEAR(c.segmentation.region_angle, 6.0 * M_PI / 180.0, 1e-6);
  EXPECT_FLOAT_EQ(c.segmentation.region_curvature, 0.5f);
  EXPECT_EQ(c.segmentation.region_min_points, 50);
  EXPECT_FLOAT_EQ(c.segmentation.planarity_min_inliers, 0.8f);
  // The floor gate is any chest or waist rig's (issue 34: 0.5-1.8 m, 15-80 deg, with a margin for
  // a walk's wobble), not the paper's 20-70 deg and 1-1.6 m (config/profiles/paper.yaml;
  // Config.PaperProfileIsTheSpanishCode).
  EXPECT_NEAR(c.floor.tilt_min, 10.0 * M_PI / 180.0, 1e-6);
  EXPECT_NEAR(c.floor.tilt_max, 85.0 * M_PI / 180.0, 1e-6);
  EXPECT_FLOAT_EQ(c.floor.height_min, 0.4f);
  EXPECT_FLOAT_EQ(c.floor.height_max, 1.9f);
  EXPECT_NEAR(c.classification.parallel_threshold, 10.0 * M_PI / 180.0, 1e-6);
  // The building code is the world's, not the paper's Spanish one (config/profiles/paper.yaml
  // holds that; Config.PaperProfileIsTheSpanishCode).
  EXPECT_FLOAT_EQ(c.classification.step_height_min, 0.10f);
  EXPECT_FLOAT_EQ(c.classification.step_height_max, 0.22f);
  EXPECT_FLOAT_EQ(c.stair_detection.same_level_tolerance, 0.03f);
  EXPECT_FLOAT_EQ(c.stair_detection.connection_radius, 0.5f);
  EXPECT_EQ(c.stair_detection.connection_min_points, 10);
  EXPECT_FLOAT_EQ(c.odometry.sigma_intensity, 5.0f);
  EXPECT_FLOAT_EQ(c.odometry.sigma_inv_depth, 0.0025f);
  EXPECT_FLOAT_EQ(c.odometry.student_nu, 5.0f);
  // The paper's 3 levels lose a 14 cm / 7 deg inter-frame motion (a dropped frame, a fast turn);
  // two more coarse levels cost little, so 5 is the shipped default (see OdometryConfig).
  EXPECT_EQ(c.odometry.pyramid_levels, 5);
  EXPECT_EQ(c.odometry.iterations, 10);
}

// The defaults accept the stairs of the world's building codes (../shared/data/SOURCES.md); the
// paper's profile loads and restores its Spanish code (CTE DB-SUA), every other key left at its
// default.
TEST(Config, PaperProfileIsTheSpanishCode) {
  const PipelineConfig d;
  EXPECT_FLOAT_EQ(d.stair_modelling.riser_min, 0.10f);
  EXPECT_FLOAT_EQ(d.stair_modelling.riser_max, 0.22f);
  EXPECT_FLOAT_EQ(d.stair_modelling.tread_min, 0.20f);
  EXPECT_FLOAT_EQ(d.stair_modelling.blondel_min, 0.50f);
  EXPECT_FLOAT_EQ(d.stair_modelling.blondel_max, 0.72f);
  EXPECT_FLOAT_EQ(d.stair_modelling.width_min, 0.60f);
  ConfigLoadReport report;
  const PipelineConfig p =
      load_config(std::string(STAIRGUIDE_SOURCE_DIR) + "/config/profiles/paper.yaml", &report);
  EXPECT_FLOAT_EQ(p.classification.step_height_min, 0.13f);
  EXPECT_FLOAT_EQ(p.classification.step_height_max, 0.185f);
  EXPECT_FLOAT_EQ(p.stair_modelling.riser_min, 0.13f);
  EXPECT_FLOAT_EQ(p.stair_modelling.riser_max, 0.185f);
  EXPECT_FLOAT_EQ(p.stair_modelling.tread_min, 0.28f);
  EXPECT_FLOAT_EQ(p.stair_modelling.blondel_min, 0.54f);
  EXPECT_FLOAT_EQ(p.stair_modelling.blondel_max, 0.70f);
  EXPECT_FLOAT_EQ(p.stair_modelling.width_min, 0.60f);
  // ... and the paper's chest-camera floor gate (3.2.1).
  EXPECT_NEAR(p.floor.tilt_min, 20.0 * M_PI / 180.0, 1e-6);
  EXPECT_NEAR(p.floor.tilt_max, 70.0 * M_PI / 180.0, 1e-6);
  EXPECT_FLOAT_EQ(p.floor.height_min, 1.0f);
  EXPECT_FLOAT_EQ(p.floor.height_max, 1.6f);
  // Nothing else moves: put the twelve keys back and the profile is the defaults.
  PipelineConfig back = p;
  back.classification.step_height_min = d.classification.step_height_min;
  back.classification.step_height_max = d.classification.step_height_max;
  back.stair_modelling = d.stair_modelling;
  back.floor.tilt_min = d.floor.tilt_min;
  back.floor.tilt_max = d.floor.tilt_max;
  back.floor.height_min = d.floor.height_min;
  back.floor.height_max = d.floor.height_max;
  std::string diff;
  EXPECT_TRUE(config_equal(back, d, &diff)) << "the profile also changes " << diff;
}

TEST(Config, UnitsAreConvertedToSi) {
  const PipelineConfig c = load_config_text(
      "segmentation:\n  voxel_size_cm: 3\nfloor:\n  tilt_min_deg: 30\nodometry:\n  min_valid_percent: 10\n",
      "inline.yaml");
  EXPECT_FLOAT_EQ(c.segmentation.voxel_size, 0.03f);
  EXPECT_NEAR(c.floor.tilt_min, 30.0 * M_PI / 180.0, 1e-6);
  EXPECT_FLOAT_EQ(c.odometry.min_valid_fraction, 0.10f);
  // Untouched keys keep their defaults.
  EXPECT_FLOAT_EQ(c.segmentation.normal_radius, 0.05f);
}

TEST(Config, DumpLoadsBackEqual) {
  PipelineConfig c;
  c.segmentation.voxel_size = 0.025f;
  c.odometry.iterations = 7;
  c.runtime.log_level = "debug";
  c.feedback.haptic_enabled = false;
  const PipelineConfig back = load_config_text(dump_config_yaml(c), "dump.yaml");
  std::string diff;
  EXPECT_TRUE(config_equal(back, c, &diff)) << diff;
  EXPECT_FALSE(config_equal(back, PipelineConfig{}, &diff));
  EXPECT_EQ(diff, "segmentation.voxel_size_cm");
}

TEST(Config, UnknownKeyNamesFileLineAndKey) {
  const std::string e = error_of("unknown", "floor:\n  tilt_min_deg: 20\n  tilt_mni_deg: 30\n");
  EXPECT_NE(e.find("test_config_unknown.yaml:3"), std::string::npos) << e;
  EXPECT_NE(e.find("floor.tilt_mni_deg"), std::string::npos) << e;
  EXPECT_NE(e.find("unknown key"), std::string::npos) << e;
}

TEST(Config, UnknownSectionIsRejected) {
  const std::string e = error_of("section", "flor:\n  tilt_min_deg: 20\n");
  EXPECT_NE(e.find(":1"), std::string::npos) << e;
  EXPECT_NE(e.find("'flor'"), std::string::npos) << e;
}

TEST(Config, WrongTypeNamesFileLineAndKey) {
  std::string e = error_of("type", "segmentation:\n  voxel_size_cm: four\n");
  EXPECT_NE(e.find("test_config_type.yaml:2"), std::string::npos) << e;
  EXPECT_NE(e.find("segmentation.voxel_size_cm"), std::string::npos) << e;
  EXPECT_NE(e.find("expected a number"), std::string::npos) << e;
  e = error_of("int", "odometry:\n  iterations: 2.5\n");
  EXPECT_NE(e.find("odometry.iterations"), std::string::npos) << e;
  EXPECT_NE(e.find("whole number"), std::string::npos) << e;
  e = error_of("bool", "capture:\n  mirroring: maybe\n");
  EXPECT_NE(e.find("capture.mirroring"), std::string::npos) << e;
  e = error_of("list", "floor:\n  height_min_m: [1, 2]\n");
  EXPECT_NE(e.find("floor.height_min_m"), std::string::npos) << e;
  e = error_of("choice", "runtime:\n  log_level: loud\n");
  EXPECT_NE(e.find("runtime.log_level"), std::string::npos) << e;
  EXPECT_NE(e.find("not one of"), std::string::npos) << e;
}

TEST(Config, OutOfRangeNamesFileLineKeyAndRange) {
  const std::string e = error_of("range", "# comment\nfloor:\n  tilt_max_deg: 120\n");
  EXPECT_NE(e.find("test_config_range.yaml:3"), std::string::npos) << e;
  EXPECT_NE(e.find("floor.tilt_max_deg"), std::string::npos) << e;
  EXPECT_NE(e.find("out of range [0, 90] deg"), std::string::npos) << e;
}

TEST(Config, InconsistentPairIsRejected) {
  const std::string e = error_of("order", "floor:\n  height_min_m: 1.5\n  height_max_m: 1.2\n");
  EXPECT_NE(e.find("floor.height_min_m"), std::string::npos) << e;
  EXPECT_NE(e.find("floor.height_max_m"), std::string::npos) << e;
}

TEST(Config, FixedThresholdsOfTheMethodAreNoKeys) {
  // The method's own thresholds (the floor detector's tread and curb checks, the Manhattan frame's
  // wall rules...) are named constants with units in config.hpp, not keys a technician sets: a file
  // that names one is refused, the key named, like any unknown key.
  const std::string e = error_of("fixed", "manhattan:\n  riser_min_height_cm: 25\n");
  EXPECT_NE(e.find("manhattan.riser_min_height_cm"), std::string::npos) << e;
  const std::string f = error_of("fixed2", "floor:\n  ambiguous_rise_min_cm: 10\n");
  EXPECT_NE(f.find("floor.ambiguous_rise_min_cm"), std::string::npos) << f;
}

TEST(Config, MissingFileIsNamed) {
  const std::string path = std::string(STAIRGUIDE_BINARY_DIR) + "/no_such_config.yaml";
  try {
    load_config(path);
    FAIL() << "no error";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("cannot open"), std::string::npos) << e.what();
  }
  EXPECT_THROW(load_config(STAIRGUIDE_BINARY_DIR), ConfigError);  // a directory
}

TEST(Config, YamlSyntaxErrorHasLine) {
  const std::string e = error_of("syntax", "floor:\n  tilt_min_deg: 20\n  tilt_max_deg: [70\n");
  EXPECT_NE(e.find("test_config_syntax.yaml:"), std::string::npos) << e;
  EXPECT_NE(e.find("YAML syntax error"), std::string::npos) << e;
}

// Issue 41: an empty file (an editor that truncates before writing, then a SIGHUP) put every key
// back to its default, silently. Empty, blank and comment-only files are refused, naming the file;
// an explicit empty mapping still asks for the defaults.
TEST(Config, EmptyFileIsRefusedNamingTheFile) {
  for (const char* text : {"", "   \n\n\t\n", "# nothing\n# at all\n", "---\n", "\n# only a comment\n  \n"}) {
    const std::string path = write_tmp("empty", text);
    try {
      load_config(path);
      FAIL() << "an empty config was taken: '" << text << "'";
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find(path + ": the config is empty"), std::string::npos) << e.what();
    }
  }
  const PipelineConfig c = load_config(write_tmp("braces", "{}\n"));
  EXPECT_TRUE(config_equal(c, PipelineConfig{}));
}

// Issue 41: ring_capacity 1024 was in range, and with a slow odometry 1.4 GB of frames queued and
// the poses came 20 s late. The range holds at most about a second of frames at 30 Hz.
TEST(Config, RingCapacityHoldsAtMostASecondOfFrames) {
  for (const char* v : {"1024", "31", "64"}) {
    const std::string e = error_of("ring", std::string("runtime:\n  ring_capacity: ") + v + "\n");
    EXPECT_NE(e.find("key 'runtime.ring_capacity': value " + std::string(v) + " is out of range [2, 30]"),
              std::string::npos)
        << e;
  }
  EXPECT_EQ(load_config_text("runtime:\n  ring_capacity: 30\n", "ok.yaml").runtime.ring_capacity, 30);
}

// ---- issue 35: hostile config files ----

TEST(Config, DuplicateKeyIsRefusedWithBothLines) {
  // yaml-cpp keeps the first value and drops the later one unseen: `0` was never validated.
  const std::string e =
      error_of("dup", "segmentation:\n  voxel_size_cm: 3\n  normal_radius_cm: 5\n  voxel_size_cm: 0\n");
  EXPECT_NE(e.find("test_config_dup.yaml:4"), std::string::npos) << e;
  EXPECT_NE(e.find("key 'segmentation.voxel_size_cm'"), std::string::npos) << e;
  EXPECT_NE(e.find("given twice (first on line 2)"), std::string::npos) << e;
  const std::string s = error_of("dup_section",
                                 "floor:\n  tilt_min_deg: 20\nodometry:\n  iterations: 5\nfloor:\n"
                                 "  tilt_max_deg: 60\n");
  EXPECT_NE(s.find("test_config_dup_section.yaml:5"), std::string::npos) << s;
  EXPECT_NE(s.find("key 'floor' given twice (first on line 1)"), std::string::npos) << s;
  // The same key in two sections is no duplicate.
  EXPECT_NO_THROW(
      load_config_text("floor:\n  min_area_m2: 0.3\nmanhattan:\n  min_area_m2: 0.05\n", "ok.yaml"));
}

TEST(Config, SecondDocumentIsRefused) {
  const std::string e = error_of("docs", "floor:\n  tilt_min_deg: 20\n---\nfloor:\n  tilt_min_deg: 0\n");
  EXPECT_NE(e.find("test_config_docs.yaml:3"), std::string::npos) << e;
  EXPECT_NE(e.find("second YAML document"), std::string::npos) << e;
}

TEST(Config, HugeOrSpecialFilesAreRefusedWithoutReadingThem) {
  // 5 MB of a flow list: refused by size before yaml-cpp sees it (it took 1.3 GB to parse).
  std::string big = "floor:\n  tilt_min_deg: [";
  while (big.size() < 5u << 20) big += "0,0,0,0,0,0,0,0,";
  big += "0]\n";
  std::string e = error_of("big", big);
  EXPECT_NE(e.find("test_config_big.yaml"), std::string::npos) << e;
  EXPECT_NE(e.find("bigger than 1048576 bytes"), std::string::npos) << e;
  // Under the size limit, a list of 200000 items is still far more nodes than a config holds.
  std::string many = "floor:\n  tilt_min_deg: [";
  for (int i = 0; i < 200000; ++i) many += "0,";
  many += "0]\n";
  e = error_of("many", many);
  EXPECT_NE(e.find("test_config_many.yaml:2"), std::string::npos) << e;
  EXPECT_NE(e.find("more than 20000 YAML nodes"), std::string::npos) << e;
  // Deep nesting.
  e = error_of("deep", "floor: " + std::string(100, '[') + std::string(100, ']') + "\n");
  EXPECT_NE(e.find("nested deeper than 8"), std::string::npos) << e;
  // /dev/zero never ends; a FIFO with no writer blocks a plain read forever.
  try {
    load_config("/dev/zero");
    ADD_FAILURE() << "/dev/zero accepted";
  } catch (const ConfigError& x) {
    EXPECT_NE(std::string(x.what()).find("/dev/zero: config file is a character device"), std::string::npos)
        << x.what();
  }
  const std::string fifo = std::string(STAIRGUIDE_BINARY_DIR) + "/test_config_fifo.yaml";
  std::remove(fifo.c_str());
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  try {
    load_config(fifo);
    ADD_FAILURE() << "FIFO accepted";
  } catch (const ConfigError& x) {
    EXPECT_NE(std::string(x.what()).find(fifo + ": config file is a FIFO"), std::string::npos) << x.what();
  }
  std::remove(fifo.c_str());
}

TEST(Config, TheDefaultPathIsProbedWithoutOpeningAFifoThere) {
  // A FIFO at /etc/stairguide/stairguide.yaml blocked the daemon before it logged a line: the
  // probe opened it to see whether it was readable. It is chosen by stat alone, then refused.
  const std::string fifo = std::string(STAIRGUIDE_BINARY_DIR) + "/test_config_probe_fifo.yaml";
  std::remove(fifo.c_str());
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  auto probe = std::async(std::launch::async, [&] {
    return first_config_path({"", std::string(STAIRGUIDE_BINARY_DIR) + "/absent.yaml", fifo,
                              std::string(STAIRGUIDE_SOURCE_DIR) + "/config/stairguide.yaml"});
  });
  if (probe.wait_for(std::chrono::seconds(5)) != std::future_status::ready) {
    const int fd = ::open(fifo.c_str(), O_RDWR);  // a writer releases the blocked open
    probe.wait();
    if (fd >= 0) ::close(fd);
    FAIL() << "probing the config path blocked on a FIFO";
  }
  EXPECT_EQ(probe.get(), fifo);
  EXPECT_THROW(load_config(fifo), ConfigError);
  // A directory is skipped; an absent path is skipped; nothing there gives "" (built-in defaults).
  EXPECT_EQ(first_config_path(
                {STAIRGUIDE_BINARY_DIR, std::string(STAIRGUIDE_SOURCE_DIR) + "/config/stairguide.yaml"}),
            std::string(STAIRGUIDE_SOURCE_DIR) + "/config/stairguide.yaml");
  EXPECT_EQ(first_config_path({std::string(STAIRGUIDE_BINARY_DIR) + "/absent.yaml"}), "");
  std::remove(fifo.c_str());
}

TEST(Config, EveryMinMaxPairIsOrderedAndNamedAtTheLaterKey) {
  struct Case {
    const char* text;
    const char* later;  // "FILE:LINE: key 'K'" of the later key
    const char* what;
  };
  const Case cases[] = {
      {"floor:\n  usual_height_min_m: 1.4\n  usual_height_max_m: 1.2\n", ":3: key 'floor.usual_height_max_m'",
       "floor.usual_height_min_m must not exceed floor.usual_height_max_m"},
      {"floor:\n  usual_tilt_max_deg: 30\n  usual_tilt_min_deg: 40\n", ":3: key 'floor.usual_tilt_min_deg'",
       "floor.usual_tilt_min_deg must not exceed floor.usual_tilt_max_deg"},
      {"stair_detection:\n  floorless_tilt_min_deg: 50\n  floorless_tilt_max_deg: 40\n",
       ":3: key 'stair_detection.floorless_tilt_max_deg'",
       "stair_detection.floorless_tilt_min_deg must not exceed stair_detection.floorless_tilt_max_deg"},
      // Only one of the pair given: named at it.
      {"# x\n\ncapture:\n  min_range_m: 2\n  max_range_m: 2\n", ":5: key 'capture.max_range_m'",
       "capture.min_range_m must be below capture.max_range_m"},
      {"floor:\n  height_min_m: 1.5\n  height_max_m: 1.2\n", ":3: key 'floor.height_max_m'",
       "floor.height_min_m must not exceed floor.height_max_m"},
      {"stair_modelling:\n  blondel_min_cm: 80\n", ":2: key 'stair_modelling.blondel_min_cm'",
       "stair_modelling.blondel_min_cm must not exceed stair_modelling.blondel_max_cm"},
  };
  int i = 0;
  for (const auto& c : cases) {
    const std::string name = "pair" + std::to_string(i++);
    const std::string e = error_of(name, c.text);
    EXPECT_NE(e.find("test_config_" + name + ".yaml" + c.later), std::string::npos) << e;
    EXPECT_NE(e.find(c.what), std::string::npos) << e;
  }
  // Equal bounds stay allowed where they mean something (a single accepted value).
  EXPECT_NO_THROW(
      load_config_text("floor:\n  usual_height_min_m: 1.2\n  usual_height_max_m: 1.2\n", "eq.yaml"));
}

// The button's and the language's keys: ranges, the buzzer's line refused for the button, a
// language that is a path refused; a good set loads in SI.
TEST(Config, ButtonAndLanguageKeysAreValidated) {
  std::string e = error_of("mute", "feedback:\n  mute_s: 0.5\n");
  EXPECT_NE(e.find("test_config_mute.yaml:2: key 'feedback.mute_s': value 0.5 is out of range [1, 7200] s"),
            std::string::npos)
      << e;
  e = error_of("button_line", "feedback:\n  button_enabled: true\n  button_line: 17\n");
  EXPECT_NE(e.find("test_config_button_line.yaml:3: key 'feedback.button_line'"), std::string::npos) << e;
  EXPECT_NE(e.find("is the buzzer's line"), std::string::npos) << e;
  e = error_of("debounce", "feedback:\n  button_debounce_s: 0.2\n  button_double_press_s: 0.15\n");
  EXPECT_NE(e.find("feedback.button_debounce_s must be below feedback.button_double_press_s"),
            std::string::npos)
      << e;
  e = error_of("language", "feedback:\n  language: \"../etc\"\n");
  EXPECT_NE(
      e.find("test_config_language.yaml:2: key 'feedback.language': feedback.language '../etc' is not a "
             "language name"),
      std::string::npos)
      << e;
  const PipelineConfig c = load_config_text(
      "feedback:\n  button_enabled: true\n  button_chip: \"file:/tmp/p\"\n  button_long_press_s: 1.5\n"
      "  mute_s: 600\n  language: \"es\"\n",
      "inline.yaml");
  EXPECT_TRUE(c.feedback.button_enabled);
  EXPECT_EQ(c.feedback.button_chip, "file:/tmp/p");
  EXPECT_FLOAT_EQ(c.feedback.button_long_press, 1.5f);
  EXPECT_FLOAT_EQ(c.feedback.mute, 600.f);
  EXPECT_EQ(c.feedback.language, "es");
}
