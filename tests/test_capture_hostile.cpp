// Capture inputs a hostile or careless user could hand over (issue 35): PCD headers that lie
// about their size, YAML files with a key given twice or a second document, non-finite or absurd
// poses, FIFOs and devices in place of files. Each is refused with the file (and line) named,
// before anything is allocated from what the file claims.
#include <gtest/gtest.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>

#include "capture_test_util.hpp"
#include "file_test_util.hpp"
#include "stairguide/capture/dataset.hpp"
#include "stairguide/capture/frame_source.hpp"
#include "stairguide/capture/oni.hpp"

namespace fs = std::filesystem;
using namespace stairguide;
using test::error_of;
using test::read_file;

namespace {

fs::path scratch(const std::string& name) { return test::scratch("capture_hostile", name); }

void write_bytes(const fs::path& p, const std::string& s) {
  std::ofstream o(p, std::ios::binary);
  o << s;
}

std::string le32(std::uint32_t v) {
  std::string s(4, '\0');
  for (int i = 0; i < 4; ++i) s[static_cast<std::size_t>(i)] = static_cast<char>((v >> (8 * i)) & 0xff);
  return s;
}

std::string pcd_header(const std::string& fields_size_type_count, int w, int h, long points,
                       const char* data) {
  return "# .PCD v0.7\nVERSION 0.7\n" + fields_size_type_count + "WIDTH " + std::to_string(w) + "\nHEIGHT " +
         std::to_string(h) + "\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " + std::to_string(points) + "\nDATA " +
         data + "\n";
}
const std::string kXyz = "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n";

/// A valid organized w x h cloud, every point at z = 1.5 m.
pcl::PointCloud<pcl::PointXYZ> organized(int w, int h) {
  pcl::PointCloud<pcl::PointXYZ> c(static_cast<std::uint32_t>(w), static_cast<std::uint32_t>(h));
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u) c.at(u, v) = pcl::PointXYZ((u - w / 2) * 0.003f, (v - h / 2) * 0.003f, 1.5f);
  return c;
}

fs::path labels_dir(const std::string& name) {
  const fs::path d = scratch(name);
  const auto frames = test::make_frames(1, 32, 24, 3, 3000, 1.0);
  FrameTruth t;
  t.scene = "x";
  t.T_world_camera = Pose::Identity();
  StairTruth s;
  s.kind = StairKind::kAscending;
  s.steps = 3;
  s.T_camera_stair = Pose::Identity();
  t.stairs.push_back(s);
  DatasetWriter w(d.string(), frames[0].intrinsics);
  w.write(frames[0], &t);
  w.close();
  return d;
}

/// Replaces the first `from` in the file with `to`; false when it is not there.
bool edit(const fs::path& p, const std::string& from, const std::string& to) {
  std::string s = read_file(p);
  const auto at = s.find(from);
  if (at == std::string::npos) return false;
  s.replace(at, from.size(), to);
  write_bytes(p, s);
  return true;
}

}  // namespace

TEST(HostilePcd, CompressedBodyWithAWrongUncompressedSizeIsRefusedBeforePclReadsIt) {
  const fs::path d = scratch("pcd_compressed");
  fs::create_directories(d);
  // A real compressed cloud, then its uncompressed-size word set to 0: PCL's readBodyBinary
  // segfaulted on it (analyze, detect, eval and the daemon's replay).
  const fs::path good = d / "good.pcd";
  ASSERT_EQ(pcl::io::savePCDFileBinaryCompressed(good.string(), organized(16, 12)), 0);
  const RgbdFrame f = read_pcd_frame(good.string());
  EXPECT_EQ(f.depth.cols, 16);
  EXPECT_FLOAT_EQ(f.depth.at<float>(5, 5), 1.5f);
  std::string bytes = read_file(good);
  const auto data = bytes.find("DATA binary_compressed\n");
  ASSERT_NE(data, std::string::npos);
  const std::size_t body = data + std::string("DATA binary_compressed\n").size();
  std::string zero = bytes;
  zero.replace(body + 4, 4, le32(0));
  write_bytes(d / "zero.pcd", zero);
  std::string e = error_of([&] { read_pcd_frame((d / "zero.pcd").string()); });
  EXPECT_NE(e.find("zero.pcd: corrupt PCD (compressed body says 0 bytes uncompressed"), std::string::npos)
      << e;
  EXPECT_NE(e.find("192 points of 12 bytes are 2304"), std::string::npos) << e;
  // A compressed size beyond the end of the file.
  std::string longer = bytes;
  longer.replace(body, 4, le32(1u << 30));
  write_bytes(d / "beyond.pcd", longer);
  e = error_of([&] { read_pcd_frame((d / "beyond.pcd").string()); });
  EXPECT_NE(e.find("beyond.pcd: truncated or corrupt PCD (compressed body of 1073741824 bytes"),
            std::string::npos)
      << e;
  // The same through open_frame_source (what every command uses).
  e = error_of([&] { open_frame_source((d / "zero.pcd").string(), CaptureConfig{}); });
  EXPECT_NE(e.find("zero.pcd"), std::string::npos) << e;
}

TEST(HostilePcd, HeadersClaimingHugeSizesAreRefusedWithTheFileNamed) {
  const fs::path d = scratch("pcd_huge");
  fs::create_directories(d);
  struct Case {
    const char* name;
    std::string text;
    const char* expect;
  };
  const Case cases[] = {
      // 8.5 GB of RSS before: ascii and compressed bodies were allocated from the header.
      {"wide.pcd", pcd_header(kXyz, 60000, 60000, 3600000000L, "ascii") + "0 0 1\n",
       "PCD WIDTH 60000 x HEIGHT 60000 is out of range [1, 16384] each"},
      {"many.pcd",
       pcd_header(kXyz, 16000, 16000, 256000000L, "binary_compressed") + le32(10) + le32(0) + "0123456789",
       "PCD of 256000000 points is more than 16777216"},
      {"ascii_short.pcd", pcd_header(kXyz, 640, 480, 307200, "ascii") + "0 0 1\n",
       "truncated PCD (ascii data of 6 bytes cannot hold 307200 points of 3 values)"},
      // std::bad_alloc with no file named before.
      {"count.pcd",
       pcd_header("FIELDS x y z d\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 1000000\n", 4, 4, 16, "ascii") +
           "0 0 1 1\n",
       "PCD field 'd' COUNT 1000000 is out of range [1, 1024]"},
      {"size.pcd", pcd_header("FIELDS x y z\nSIZE 4 4 3\nTYPE F F F\nCOUNT 1 1 1\n", 4, 4, 16, "ascii"),
       "field 'z' SIZE 3; 1, 2, 4 or 8 expected"},
      {"bignum.pcd",
       "VERSION 0.7\n" + kXyz + "WIDTH 99999999999999999999999\nHEIGHT 2\nPOINTS 4\nDATA ascii\n",
       "WIDTH '99999999999999999999999' is not a whole number"},
      {"nodata.pcd", "VERSION 0.7\n" + kXyz + "WIDTH 2\nHEIGHT 2\nPOINTS 4\n" + std::string(70000, 'x'),
       "header has no DATA line"},
      // Found by tools/fuzz: PCL took "VIrmat" for a header key, its parse went wrong and it crashed.
      {"vi.pcd", "# .PCD v0.7\nVIrmat\nVERSION 0.7\n" + kXyz + "WIDTH 2\nHEIGHT 2\nPOINTS 4\nDATA ascii\n",
       "corrupt PCD header (unknown line 'VIrmat')"},
      {"twice.pcd", "VERSION 0.7\n" + kXyz + "WIDTH 2\nWIDTH 4000\nHEIGHT 2\nPOINTS 4\nDATA ascii\n",
       "WIDTH given twice"},
  };
  for (const auto& c : cases) {
    write_bytes(d / c.name, c.text);
    const std::string e = error_of([&] { read_pcd_frame((d / c.name).string()); });
    EXPECT_NE(e.find((d / c.name).string() + ": "), std::string::npos) << c.name << ": " << e;
    EXPECT_NE(e.find(c.expect), std::string::npos) << c.name << ": " << e;
  }
  // A valid ascii cloud still reads.
  ASSERT_EQ(pcl::io::savePCDFileASCII((d / "ascii.pcd").string(), organized(8, 6)), 0);
  EXPECT_EQ(read_pcd_frame((d / "ascii.pcd").string()).depth.rows, 6);
}

TEST(HostileYaml, CameraYamlWithADuplicateKeyOrASecondDocumentIsRefused) {
  const fs::path d = scratch("camera");
  fs::create_directories(d);
  const std::string good =
      "fx: 525\nfy: 525\ncx: 319.5\ncy: 239.5\nwidth: 640\nheight: 480\ndepth_scale: 5000\n";
  write_bytes(d / "camera.yaml", good);
  EXPECT_FLOAT_EQ(read_camera_yaml((d / "camera.yaml").string()).intrinsics.fx, 525.f);
  write_bytes(d / "camera.yaml", good + "fx: 0\n");
  std::string e = error_of([&] { read_camera_yaml((d / "camera.yaml").string()); });
  EXPECT_NE(e.find("camera.yaml:8: key 'fx' given twice (first on line 1)"), std::string::npos) << e;
  write_bytes(d / "camera.yaml", good + "---\nfx: 1\n");
  e = error_of([&] { read_camera_yaml((d / "camera.yaml").string()); });
  EXPECT_NE(e.find("camera.yaml:8: a second YAML document"), std::string::npos) << e;
}

TEST(HostileYaml, LabelsWithADuplicateKeyASecondDocumentOrANanPoseAreRefused) {
  const fs::path d = labels_dir("labels");
  const fs::path labels = d / "labels.yaml";
  const std::string original = read_file(labels);
  ASSERT_EQ(read_labels_yaml(labels.string()).size(), 1u);

  ASSERT_TRUE(edit(labels, "        steps: 3\n", "        steps: 3\n        steps: 30\n"));
  std::string e = error_of([&] { read_labels_yaml(labels.string()); });
  EXPECT_NE(e.find("labels.yaml:"), std::string::npos) << e;
  EXPECT_NE(e.find("key 'frames[0].stairs[0].steps' given twice"), std::string::npos) << e;

  write_bytes(labels, original + "---\nformat: stairguide-labels-1\nframes: []\n");
  e = error_of([&] { read_labels_yaml(labels.string()); });
  EXPECT_NE(e.find("second YAML document"), std::string::npos) << e;

  // A NaN in T_camera_stair read as a number and went on into the error statistics.
  write_bytes(labels, original);
  const auto stair_at = original.find("T_camera_stair: [");
  ASSERT_NE(stair_at, std::string::npos);
  std::string nan = original;
  nan.replace(stair_at + std::string("T_camera_stair: [").size(), 1, ".nan");
  write_bytes(labels, nan);
  e = error_of([&] { read_labels_yaml(labels.string()); });
  EXPECT_NE(e.find("T_camera_stair' holds a number that is not finite"), std::string::npos) << e;
  const int nan_line =
      1 + static_cast<int>(std::count(nan.begin(), nan.begin() + static_cast<long>(stair_at), '\n'));
  EXPECT_NE(e.find("labels.yaml:" + std::to_string(nan_line) + ":"), std::string::npos) << e;
  // A scale in place of a rotation, and .inf in a length.
  std::string scaled = original;
  scaled.replace(stair_at + std::string("T_camera_stair: [").size(), 1, "3");
  write_bytes(labels, scaled);
  e = error_of([&] { read_labels_yaml(labels.string()); });
  EXPECT_NE(e.find("T_camera_stair' is not a rigid transform"), std::string::npos) << e;
  write_bytes(labels, original);
  ASSERT_TRUE(edit(labels, "riser_m: ", "riser_m: .inf #"));
  e = error_of([&] { read_labels_yaml(labels.string()); });
  EXPECT_NE(e.find("key 'riser_m' must be a finite number, got '.inf'"), std::string::npos) << e;
}

TEST(HostileGroundTruth, NonFiniteOrAbsurdPosesAreRefusedWithFileAndLine) {
  const fs::path d = scratch("groundtruth");
  fs::create_directories(d);
  const fs::path gt = d / "groundtruth.txt";
  const std::string good = "# t tx ty tz qx qy qz qw\n1.0 0.1 0.2 0.3 0 0 0 1\n";
  write_bytes(gt, good);
  ASSERT_EQ(read_groundtruth(gt.string()).size(), 1u);
  struct Case {
    const char* line;
    const char* expect;
  };
  const Case cases[] = {
      // 1e300 is finite as a double, inf as the float pose: ATE RMSE came out -nan, exit 0.
      {"2.0 1e300 0 0 0 0 0 1", ":3: translation 1e300 m is out of range"},
      {"2.0 0 0 0 1e300 0 0 1", ":3: quaternion component 1e300 is not that of a unit quaternion"},
      {"2.0 0 0 0 0 0 0.5 0.5", ":3: quaternion of norm 0.7071"},
      {"2.0 nan 0 0 0 0 0 1", ":3: expected 'timestamp tx ty tz qx qy qz qw'"},
      {"1e300 0 0 0 0 0 0 1", ":3: timestamp 1e300 is out of range"},
  };
  for (const auto& c : cases) {
    write_bytes(gt, good + c.line + "\n");
    const std::string e = error_of([&] { read_groundtruth(gt.string()); });
    EXPECT_NE(e.find(gt.string() + c.expect), std::string::npos) << c.line << ": " << e;
  }
}

TEST(HostileFiles, FifosAndDevicesInPlaceOfDatasetFilesAreRefusedAtOnce) {
  const fs::path d = labels_dir("fifo");
  // A FIFO with no writer would block a plain read forever; /dev/zero never ends.
  fs::remove(d / "groundtruth.txt");
  ASSERT_EQ(mkfifo((d / "groundtruth.txt").c_str(), 0600), 0);
  std::string e = error_of([&] { DatasetSource s(d.string()); });
  EXPECT_NE(e.find("groundtruth.txt: list file is a FIFO, not a regular file"), std::string::npos) << e;
  fs::remove(d / "groundtruth.txt");
  fs::remove(d / "depth.txt");
  fs::create_symlink("/dev/zero", d / "depth.txt");
  e = error_of([&] { DatasetSource s(d.string()); });
  EXPECT_NE(e.find("depth.txt: list file is a character device"), std::string::npos) << e;
  fs::remove(d / "depth.txt");
  fs::remove(d / "camera.yaml");
  fs::create_symlink("/dev/zero", d / "camera.yaml");
  e = error_of([&] { DatasetSource s(d.string()); });
  EXPECT_NE(e.find("camera.yaml"), std::string::npos) << e;
  EXPECT_NE(e.find("not a regular file"), std::string::npos) << e;
}

TEST(HostileOni, RecordsOpenNI2sPlayerWouldTrustAreRefusedBeforeItSeesThem) {
  // Found by tests/fuzz/fuzz_oni: a property record's name and the next record's header
  // overwritten; OpenNI2's player read past its buffers and crashed (exit 139 from the daemon).
  const std::string known =
      std::string(STAIRGUIDE_SOURCE_DIR) + "/tests/fuzz/corpus/oni/crash-player-property.oni";
  std::string e = error_of([&] { OniSource s(known); });
  EXPECT_NE(e.find("crash-player-property.oni: corrupt recording (record at byte 736: name not a string)"),
            std::string::npos)
      << e;
  const fs::path good = scratch("good.oni");
  const auto frames = test::make_frames(2, 32, 24, 1, 3000, 5.0);
  {
    OniWriter w(good.string(), frames[0].intrinsics, true);
    for (const auto& f : frames) w.write(f);
    w.close();
  }
  {
    OniSource s(good.string());
    RgbdFrame f;
    EXPECT_TRUE(s.read(f).ok());
  }
  e = error_of([&] {
    OniSource s(std::string(STAIRGUIDE_SOURCE_DIR) + "/tests/fuzz/corpus/oni/crash-no-cropping.oni");
  });
  EXPECT_NE(e.find("crash-no-cropping.oni: corrupt recording (record at byte 1094: name not a string)"),
            std::string::npos)
      << e;
  const std::string bytes = read_file(good);
  // The colour stream's cropping property renamed: the player crashed once its frames came.
  const auto crop = bytes.rfind("xnCropping");
  ASSERT_NE(crop, std::string::npos);
  struct Case {
    std::size_t at;  // byte to overwrite
    std::string with;
    const char* expect;
  };
  const Case cases[] = {
      {98, "XXXX", "record at byte 98: no NIR signature"},
      {98 + 4, le32(77), "record at byte 98: unknown type 77"},
      {98 + 12, le32(12), "record at byte 98: header size 12"},
      {98 + 28, le32(5000), "record at byte 98: name length 5000"},
      {24 + 16, le32(999), "record at byte 24: a payload on a record that has none"},
      // Also found by fuzz_oni: OpenNI2's player allocated 6 GB for the streams this announced.
      {20, le32(2752514), "the file header announces 2752514 streams"},
      {crop + 9, "G", "stream 2 carries frames but has no xnCropping property before them"},
  };
  for (const auto& c : cases) {
    std::string mutated = bytes;
    mutated.replace(c.at, c.with.size(), c.with);
    const fs::path p = scratch("mutated.oni");
    write_bytes(p, mutated);
    e = error_of([&] { OniSource s(p.string()); });
    EXPECT_NE(e.find("mutated.oni: corrupt recording ("), std::string::npos) << e;
    EXPECT_NE(e.find(c.expect), std::string::npos) << e;
  }
}

namespace {

struct OniRecord {
  std::size_t at, size;
  std::uint32_t type, node;
  std::string name;  // of a property record
};

std::uint32_t get32(const std::string& b, std::size_t at) {
  return static_cast<std::uint32_t>(static_cast<unsigned char>(b[at])) |
         static_cast<std::uint32_t>(static_cast<unsigned char>(b[at + 1])) << 8 |
         static_cast<std::uint32_t>(static_cast<unsigned char>(b[at + 2])) << 16 |
         static_cast<std::uint32_t>(static_cast<unsigned char>(b[at + 3])) << 24;
}

std::vector<OniRecord> oni_records(const std::string& b) {
  std::vector<OniRecord> out;
  for (std::size_t pos = 24; pos + 28 <= b.size();) {
    OniRecord r{pos, get32(b, pos + 12) + std::size_t{get32(b, pos + 16)}, get32(b, pos + 4),
                get32(b, pos + 8), ""};
    if (r.type >= 0x03 && r.type <= 0x06) r.name = b.substr(pos + 32, get32(b, pos + 28) - 1);
    out.push_back(r);
    if (r.type == 0x0B) break;
    pos += r.size;
  }
  return out;
}

}  // namespace

// Issue 41: a real Kinect recording that OpenNI2's own player reads was refused as "corrupt (stream 1
// has no xnCropping property)": the check wanted the property before the stream's ready record,
// where OpenNI2's player only needs it before the stream's frames. The same recording as OniWriter
// writes it, with the depth stream's cropping record moved after its ready record (and the colour
// stream's after its data-begin record), plays every frame.
TEST(HostileOni, CroppingAfterTheStreamIsReadyPlaysAsOpenNI2sPlayerDoes) {
  const fs::path good = scratch("late_crop_src.oni");
  const auto frames = test::make_frames(3, 32, 24, 1, 3000, 5.0);
  {
    OniWriter w(good.string(), frames[0].intrinsics, true);
    for (const auto& f : frames) w.write(f);
    w.close();
  }
  std::string b = read_file(good);
  const auto recs = oni_records(b);
  // Moves record i to just after record j (i < j): the records between shift back, nothing else moves.
  auto move_after = [&](std::size_t i, std::size_t j) {
    const std::string rec = b.substr(recs[i].at, recs[i].size);
    const std::size_t end = recs[j].at + recs[j].size;
    const std::string between = b.substr(recs[i].at + recs[i].size, end - recs[i].at - recs[i].size);
    b.replace(recs[i].at, end - recs[i].at, between + rec);
  };
  auto find = [&](std::uint32_t node, std::uint32_t type, const char* name) {
    for (std::size_t i = 0; i < recs.size(); ++i)
      if (recs[i].node == node && recs[i].type == type && (!name || recs[i].name == name)) return i;
    ADD_FAILURE() << "no record " << type << " of node " << node;
    return std::size_t{0};
  };
  // Colour (node 2) first: its records lie after the depth stream's, whose move shifts nothing of them.
  move_after(find(2, 0x06, "xnCropping"), find(2, 0x08, nullptr));
  move_after(find(1, 0x06, "xnCropping"), find(1, 0x09, nullptr));
  const fs::path late = scratch("late_crop.oni");
  write_bytes(late, b);
  OniSource s(late.string());
  RgbdFrame f;
  int n = 0;
  while (s.read(f).ok()) {
    EXPECT_EQ(f.depth.cols, 32);
    EXPECT_FALSE(f.color.empty()) << "frame " << n;
    ++n;
  }
  EXPECT_EQ(n, 3);
}

// Issue 41: permission denied read "missing (no such file)", "depth image missing" or "corrupt", and a
// symlink loop as the input "no such file". Each is named by its cause. Root passes every
// permission check, so as root the readers run in a child that has become `nobody`.
TEST(HostileFiles, PermissionDeniedAndSymlinkLoopsAreNamedByTheirCause) {
  EXPECT_EQ(why_unreadable("/nonexistent/sg"), "no such file");
  EXPECT_EQ(errno_words(EACCES), "permission denied");
  EXPECT_EQ(errno_words(ELOOP), "a symbolic link loop (too many levels of symbolic links)");

  char tmpl[] = "/tmp/sg-perm-XXXXXX";
  ASSERT_NE(mkdtemp(tmpl), nullptr);
  const fs::path root(tmpl);
  fs::permissions(root, fs::perms(0755));
  const auto frames = test::make_frames(1, 32, 24, 3, 3000, 1.0);
  auto dataset = [&](const fs::path& d) {
    DatasetWriter w(d.string(), frames[0].intrinsics);
    w.write(frames[0]);
    w.close();
  };
  const fs::path closed = root / "closed", open_img = root / "open_img", shut = root / "shut";
  dataset(closed);
  dataset(open_img);
  fs::create_directories(shut);
  dataset(shut / "inner");
  fs::path depth_png;
  for (const auto& e : fs::recursive_directory_iterator(open_img))
    if (e.path().extension() == ".png" && e.path().string().find("depth") != std::string::npos)
      depth_png = e.path();
  ASSERT_FALSE(depth_png.empty());
  const fs::path oni = root / "rec.oni";
  {
    OniWriter w(oni.string(), frames[0].intrinsics, false);
    w.write(frames[0]);
    w.close();
  }
  fs::permissions(closed, fs::perms::none);
  fs::permissions(depth_png, fs::perms::none);
  fs::permissions(oni, fs::perms::none);
  fs::permissions(shut, fs::perms::none);

  // The messages, one per line, from whoever may not read these.
  auto messages = [&] {
    std::string out;
    auto say = [&](const std::function<void()>& f) {
      try {
        f();
        out += "(no error)\n";
      } catch (const std::exception& e) {
        out += std::string(e.what()) + "\n";
      }
    };
    const CaptureConfig cc;
    say([&] { DatasetSource s(closed.string()); });
    say([&] {
      DatasetSource s(open_img.string());
      RgbdFrame f;
      const ReadResult r = s.read(f);
      throw std::runtime_error(r.ok() ? "(read)" : r.message);
    });
    say([&] { OniSource s(oni.string()); });
    say([&] { open_frame_source((shut / "inner").string(), cc); });
    return out;
  };
  std::string got;
  if (geteuid() == 0) {
    int p[2];
    ASSERT_EQ(pipe(p), 0);
    const pid_t pid = fork();
    if (pid == 0) {
      close(p[0]);
      if (setgid(65534) != 0 || setuid(65534) != 0) _exit(3);
      const std::string m = messages();
      const ssize_t n = write(p[1], m.data(), m.size());
      _exit(n == static_cast<ssize_t>(m.size()) ? 0 : 4);
    }
    close(p[1]);
    char buf[4096];
    for (ssize_t n; (n = read(p[0], buf, sizeof buf)) > 0;) got.append(buf, static_cast<std::size_t>(n));
    close(p[0]);
    int st = 0;
    waitpid(pid, &st, 0);
    ASSERT_TRUE(WIFEXITED(st) && WEXITSTATUS(st) == 0) << "child status " << st;
  } else {
    got = messages();
  }
  std::istringstream in(got);
  std::vector<std::string> m;
  for (std::string l; std::getline(in, l);) m.push_back(l);
  ASSERT_EQ(m.size(), 4u) << got;
  EXPECT_NE(m[0].find("dataset " + closed.string() + ": cannot read the folder (permission denied)"),
            std::string::npos)
      << m[0];
  EXPECT_NE(m[1].find(depth_png.string() + ": cannot read depth image (permission denied)"),
            std::string::npos)
      << m[1];
  EXPECT_NE(m[2].find("oni " + oni.string() + ": cannot read the recording (permission denied)"),
            std::string::npos)
      << m[2];
  EXPECT_NE(m[3].find("cannot open it (permission denied)"), std::string::npos) << m[3];
  for (const auto& l : m)
    for (const char* wrong : {"no such", "missing", "corrupt"})
      EXPECT_EQ(l.find(wrong), std::string::npos) << l;

  // A symlink loop as the input.
  fs::create_symlink("loop", root / "loop");
  fs::create_symlink("loop.oni", root / "loop.oni");
  for (const char* name : {"loop", "loop.oni"}) {
    std::string e;
    try {
      open_frame_source((root / name).string(), CaptureConfig{});
    } catch (const SourceError& x) {
      e = x.what();
    }
    EXPECT_NE(e.find("a symbolic link loop"), std::string::npos) << name << ": " << e;
  }
  for (const fs::path& p : {closed, shut}) fs::permissions(p, fs::perms(0755));
  fs::remove_all(root);
}
