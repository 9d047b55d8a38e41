// `stairguide bench perception [--frames INPUT] [--count N] [--json] [--checksum]`: segmentation + floor +
// Manhattan + classification per frame, against a reference built from PCL's own classes with the
// paper's parameters (section 3.1: VoxelGrid 4 cm, NormalEstimation r = 5 cm, RegionGrowing
// 6 deg / 0.5 / 50, RANSAC planarity > 80 %, EuclideanClusterExtraction), on the same frames in
// the same process, one thread. Wall time (steady clock) and thread CPU time are both reported:
// on a shared machine the CPU time is the steadier of the two. The drop-off stage, which the
// runtime runs on every perceived frame after these (stairs/drop_detection.hpp), is timed on its
// own on each frame's scene and given as its share of ours (medians of the same run).
// INPUT: anything `analyze` reads (a dataset folder, FILE.oni, FILE.pcd, ...), a folder of .pcd
// frames, or a list file (.txt / .list: one such input per line, relative to the list, # for
// comments), so that single real frames can be benchmarked together.
#include <pcl/features/normal_3d.h>
#include <pcl/filters/extract_indices.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/sample_consensus/method_types.h>
#include <pcl/sample_consensus/model_types.h>
#include <pcl/search/kdtree.h>
#include <pcl/segmentation/extract_clusters.h>
#include <pcl/segmentation/region_growing.h>
#include <pcl/segmentation/sac_segmentation.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "cli/bench_util.hpp"
#include "cli/command.hpp"
#include "cli/open_input.hpp"
#include "stairguide/capture/frame_source.hpp"
#include "stairguide/capture/synth_source.hpp"
#include "stairguide/perception/perception.hpp"
#include "stairguide/stairs/drop_detection.hpp"

namespace stairguide::cli {
namespace {

/// The paper's segmentation built from PCL classes; returns the planar regions (points only) and
/// the number of clusters.
struct Reference {
  SegmentationConfig cfg;
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud{new pcl::PointCloud<pcl::PointXYZ>};
  pcl::PointCloud<pcl::PointXYZ>::Ptr down{new pcl::PointCloud<pcl::PointXYZ>};
  pcl::PointCloud<pcl::Normal>::Ptr normals{new pcl::PointCloud<pcl::Normal>};
  double voxel_ms = 0, normals_ms = 0, growing_ms = 0, ransac_ms = 0, clusters_ms = 0;
  int clusters = 0;

  void run(const RgbdFrame& f, std::vector<PlaneRegion>& regions) {
    const CameraIntrinsics& K = f.intrinsics;
    cloud->clear();
    for (int v = 0; v < f.depth.rows; ++v)
      for (int u = 0; u < f.depth.cols; ++u) {
        const float z = f.depth.at<float>(v, u);
        if (z > 0.f) cloud->push_back(pcl::PointXYZ((u - K.cx) / K.fx * z, (v - K.cy) / K.fy * z, z));
      }
    Timer t;
    pcl::VoxelGrid<pcl::PointXYZ> vg;
    vg.setInputCloud(cloud);
    vg.setLeafSize(cfg.voxel_size, cfg.voxel_size, cfg.voxel_size);
    vg.filter(*down);
    voxel_ms = t.wall();
    t = Timer();
    pcl::search::KdTree<pcl::PointXYZ>::Ptr tree(new pcl::search::KdTree<pcl::PointXYZ>);
    pcl::NormalEstimation<pcl::PointXYZ, pcl::Normal> ne;
    ne.setInputCloud(down);
    ne.setSearchMethod(tree);
    ne.setRadiusSearch(cfg.normal_radius);
    ne.setViewPoint(0.f, 0.f, 0.f);
    ne.compute(*normals);
    normals_ms = t.wall();
    t = Timer();
    pcl::RegionGrowing<pcl::PointXYZ, pcl::Normal> rg;
    rg.setMinClusterSize(cfg.region_min_points);
    rg.setMaxClusterSize(10000000);
    rg.setSearchMethod(tree);
    rg.setNumberOfNeighbours(30);
    rg.setInputCloud(down);
    rg.setInputNormals(normals);
    rg.setSmoothnessThreshold(cfg.region_angle);
    rg.setCurvatureThreshold(cfg.region_curvature);
    std::vector<pcl::PointIndices> found;
    rg.extract(found);
    growing_ms = t.wall();
    t = Timer();
    regions.clear();
    std::vector<bool> used(down->size(), false);
    for (const auto& idx : found) {
      pcl::PointIndices::Ptr in(new pcl::PointIndices(idx));
      pcl::SACSegmentation<pcl::PointXYZ> sac;
      sac.setModelType(pcl::SACMODEL_PLANE);
      sac.setMethodType(pcl::SAC_RANSAC);
      sac.setDistanceThreshold(cfg.voxel_size);
      sac.setMaxIterations(100);
      sac.setInputCloud(down);
      sac.setIndices(in);
      pcl::PointIndices inliers;
      pcl::ModelCoefficients coeff;
      sac.segment(inliers, coeff);
      if (inliers.indices.size() < cfg.planarity_min_inliers * idx.indices.size()) continue;
      PlaneRegion r;
      Eigen::Vector3f n(coeff.values[0], coeff.values[1], coeff.values[2]);
      float d = coeff.values[3];
      if (d < 0) n = -n, d = -d;
      r.normal = n;
      r.offset = d;
      Eigen::Vector3d c = Eigen::Vector3d::Zero();
      for (int i : idx.indices) {
        used[static_cast<std::size_t>(i)] = true;
        r.points.push_back((*down)[static_cast<std::size_t>(i)].getVector3fMap());
        c += r.points.back().cast<double>();
      }
      r.centroid = (c / static_cast<double>(idx.indices.size())).cast<float>();
      r.pixel_count = static_cast<int>(idx.indices.size());
      r.area = static_cast<float>(idx.indices.size()) * cfg.voxel_size * cfg.voxel_size;
      r.id = static_cast<int>(regions.size());
      regions.push_back(std::move(r));
    }
    ransac_ms = t.wall();
    t = Timer();
    pcl::PointIndices::Ptr rest(new pcl::PointIndices);
    for (std::size_t i = 0; i < used.size(); ++i)
      if (!used[i]) rest->indices.push_back(static_cast<int>(i));
    pcl::EuclideanClusterExtraction<pcl::PointXYZ> ec;
    ec.setClusterTolerance(cfg.cluster_tolerance);
    ec.setMinClusterSize(cfg.cluster_min_points);
    ec.setMaxClusterSize(10000000);
    ec.setSearchMethod(tree);
    ec.setInputCloud(down);
    ec.setIndices(rest);
    std::vector<pcl::PointIndices> cl;
    ec.extract(cl);
    clusters = static_cast<int>(cl.size());
    clusters_ms = t.wall();
  }
};

/// FNV-1a over raw bytes: `--checksum` hashes every region and cluster bit for bit, so that a
/// speed change can show it leaves the output exactly as it was.
struct Fnv {
  std::uint64_t h = 1469598103934665603ull;
  void bytes(const void* p, std::size_t n) {
    const auto* b = static_cast<const unsigned char*>(p);
    for (std::size_t i = 0; i < n; ++i) h = (h ^ b[i]) * 1099511628211ull;
  }
  template <class T>
  void pod(const T& v) {
    bytes(&v, sizeof(T));
  }
  template <class T>
  void vec(const std::vector<T>& v) {
    pod(v.size());
    if (!v.empty()) bytes(v.data(), v.size() * sizeof(T));
  }
};

std::uint64_t scene_checksum(const SceneResult& s) {
  Fnv f;
  f.pod(s.regions.size());
  for (const PlaneRegion& r : s.regions) {
    f.pod(r.id), f.pod(r.normal), f.pod(r.offset), f.pod(r.centroid), f.vec(r.points), f.vec(r.pixels);
    f.pod(r.pixel_count), f.pod(r.area), f.pod(r.curvature), f.pod(r.rect_center), f.pod(r.rect_axis_major);
    f.pod(r.rect_axis_minor), f.pod(r.rect_length_major), f.pod(r.rect_length_minor), f.pod(r.hull_extent);
    f.pod(r.cls), f.pod(r.height);
  }
  f.pod(s.clusters.size());
  for (const ObstacleCluster& c : s.clusters) f.vec(c.points), f.pod(c.centroid), f.pod(c.min), f.pod(c.max);
  f.pod(s.floor_found), f.pod(s.manhattan_found);
  if (s.manhattan_found) f.pod(s.manhattan_yaw);  // a change to the Manhattan stage shows here too
  f.bytes(s.T_floor_camera.matrix().data(), 16 * sizeof(float));
  return f.h;
}

/// The inputs `--frames ARG` names (see the file comment). Throws UsageError naming the file and
/// line when a list is unreadable or names nothing that exists.
std::vector<std::string> frame_inputs(const std::string& arg) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::is_directory(arg, ec)) {
    std::vector<std::string> pcds;
    for (const auto& e : fs::directory_iterator(arg, ec))
      if (e.is_regular_file() && e.path().extension() == ".pcd") pcds.push_back(e.path().string());
    std::sort(pcds.begin(), pcds.end());
    if (!pcds.empty()) return pcds;
    return {arg};  // a dataset folder
  }
  const std::string ext = fs::path(arg).extension().string();
  if (ext != ".txt" && ext != ".list") return {arg};
  std::ifstream in(arg);
  if (!in) throw UsageError("--frames " + arg + ": cannot read this list file");
  std::vector<std::string> out;
  std::string line;
  for (int n = 1; std::getline(in, line); ++n) {
    const auto b = line.find_first_not_of(" \t\r");
    if (b == std::string::npos || line[b] == '#') continue;
    const auto e = line.find_last_not_of(" \t\r");
    fs::path p(line.substr(b, e - b + 1));
    if (p.is_relative()) p = fs::path(arg).parent_path() / p;
    if (!fs::exists(p, ec))
      throw UsageError("--frames " + arg + " line " + std::to_string(n) + ": '" + p.string() +
                       "' does not exist");
    out.push_back(p.string());
  }
  if (out.empty()) throw UsageError("--frames " + arg + ": the list names no input");
  return out;
}

int bench_perception(Context& ctx) {
  const bool json = ctx.flag("--json");
  const bool checksum = ctx.flag("--checksum");
  const auto dir = ctx.option("--frames");
  const long count = ctx.int_option("--count", 1, 100000).value_or(0);
  ctx.positionals(0, 0);

  std::vector<RgbdFrame> frames;
  if (dir) {
    const long limit = count > 0 ? count : 30;
    for (const std::string& input : frame_inputs(*dir)) {
      const std::unique_ptr<FrameSource> src =
          open_input(input, ctx.config.capture, "stairguide bench perception");
      if (!src) return 1;
      RgbdFrame f;
      while (static_cast<long>(frames.size()) < limit) {
        const ReadResult r = src->read(f);
        if (!r.ok()) {
          if (r.status == ReadStatus::kError) {
            std::fprintf(stderr, "stairguide bench perception: %s\n", r.message.c_str());
            return 1;
          }
          break;
        }
        frames.push_back(f.clone());
      }
      if (static_cast<long>(frames.size()) >= limit) break;
    }
  } else {
    const long per = count > 0 ? count : 8;
    for (const char* preset :
         {"ascending_static", "descending_static", "corridor_static", "room_clutter_static"}) {
      auto src = synth::make_source(preset, per, 3);
      RgbdFrame f;
      while (src->read(f).ok()) frames.push_back(f.clone());
    }
  }
  if (frames.empty()) {
    std::fprintf(stderr, "stairguide bench perception: no frames\n");
    return 1;
  }

  Perception ours(ctx.config);
  SceneResult scene;
  ours.process(frames[0], scene);  // warm-up: buffers reach their size
  if (checksum) {
    // Ours only, no timing: one hash per frame and one over all of them.
    Fnv all;
    for (std::size_t i = 0; i < frames.size(); ++i) {
      ours.reset();
      ours.process(frames[i], scene);
      const std::uint64_t h = scene_checksum(scene);
      all.pod(h);
      long px = 0;
      for (const PlaneRegion& r : scene.regions) px += r.pixel_count;
      std::printf("frame %3zu  regions %3zu  region pixels %6ld  clusters %3zu  floor %d  %016llx\n", i,
                  scene.regions.size(), px, scene.clusters.size(), scene.floor_found ? 1 : 0,
                  static_cast<unsigned long long>(h));
    }
    std::printf("checksum over %zu frames: %016llx\n", frames.size(), static_cast<unsigned long long>(all.h));
    return 0;
  }

  std::vector<double> o_wall, o_cpu, o_seg, o_floor, o_man, o_cls;
  std::vector<double> s_cells, s_seeds, s_strips;
  std::vector<double> s_bp, s_grow, s_merge, s_refine, s_fin, s_cl, o_regions, r_regions;
  std::vector<double> d_wall, d_cpu;  // the drop stage
  int floors = 0, drops = 0;
  Reference ref;
  ref.cfg = ctx.config.segmentation;
  FloorDetector ref_floor(ctx.config.floor);
  ManhattanTracker ref_man(ctx.config.manhattan, ctx.config.capture.max_range);
  std::vector<double> r_wall, r_cpu, r_vox, r_norm, r_grow, r_ransac, r_clu;
  SceneResult rs;
  int ref_floors = 0;
  auto run_ours = [&](const RgbdFrame& f) {
    ours.reset();
    Timer t;
    ours.process(f, scene);
    o_cpu.push_back(t.cpu());
    o_wall.push_back(t.wall());
    o_seg.push_back(scene.timings.segmentation_ms);
    o_floor.push_back(scene.timings.floor_ms);
    o_man.push_back(scene.timings.manhattan_ms);
    o_cls.push_back(scene.timings.classification_ms);
    const auto& st = ours.segmentation().stats();
    s_bp.push_back(st.backproject_ms);
    s_grow.push_back(st.grow_ms);
    s_cells.push_back(st.cells_ms);
    s_seeds.push_back(st.seeds_ms);
    s_strips.push_back(st.strips_ms);
    s_merge.push_back(st.merge_ms);
    s_refine.push_back(st.refine_ms);
    s_fin.push_back(st.finalize_ms);
    s_cl.push_back(st.clusters_ms);
    floors += scene.floor_found;
    o_regions.push_back(static_cast<double>(scene.regions.size()));
    // The drop stage as PerceptionStage::step runs it, on this frame's scene (the runtime may
    // carry a floor the frame's own view lacks; here every frame stands alone, as for ours).
    Timer td;
    const DropResult drop = detect_drop(f, scene, ctx.config.drops);
    d_cpu.push_back(td.cpu());
    d_wall.push_back(td.wall());
    drops += drop.detected;  // edges found by the stage (a descent's is vetoed later, by the stairs')
  };
  auto run_reference = [&](const RgbdFrame& f) {
    ref_floor.reset();
    ref_man.reset();
    Timer t;
    ref.run(f, rs.regions);
    // The same floor / Manhattan / classification stages on the reference's planes.
    const FloorEstimate fe = ref_floor.detect(rs.regions, f);
    rs.floor_found = fe.found;
    rs.T_floor_camera = fe.T_floor_camera;
    rs.floor_region = fe.region;
    rs.camera_height = fe.height;
    if (fe.found) {
      const ManhattanEstimate me = ref_man.estimate(rs.regions, fe.T_floor_camera);
      rs.manhattan_found = me.found;
      rs.T_manhattan_floor = me.T_manhattan_floor;
    }
    classify_regions(rs, ctx.config.classification);
    r_cpu.push_back(t.cpu());
    r_wall.push_back(t.wall());
    r_vox.push_back(ref.voxel_ms);
    r_norm.push_back(ref.normals_ms);
    r_grow.push_back(ref.growing_ms);
    r_ransac.push_back(ref.ransac_ms);
    r_clu.push_back(ref.clusters_ms);
    ref_floors += fe.found;
    r_regions.push_back(static_cast<double>(rs.regions.size()));
  };
  // Ours and the reference take turns frame by frame, so that a burst of load from elsewhere on
  // the machine (a shared, noisy 2-core box) falls on both and the ratio stays fair.
  for (const auto& f : frames) {
    run_ours(f);
    run_reference(f);
  }
  const double med = percentile(o_wall, 0.5), p95 = percentile(o_wall, 0.95);
  const double rmed = percentile(r_wall, 0.5), rp95 = percentile(r_wall, 0.95);
  const double cmed = percentile(o_cpu, 0.5), cp95 = percentile(o_cpu, 0.95), rcmed = percentile(r_cpu, 0.5);
  const double ratio = med > 0 ? rmed / med : 0.0, cratio = cmed > 0 ? rcmed / cmed : 0.0;
  const double dmed = percentile(d_wall, 0.5), dp95 = percentile(d_wall, 0.95),
               dcmed = percentile(d_cpu, 0.5);
  const double dshare = med > 0 ? dmed / med : 0.0, dcshare = cmed > 0 ? dcmed / cmed : 0.0;
  const int W = frames[0].depth.cols, H = frames[0].depth.rows;
  if (json) {
    std::printf(
        "{\"frames\": %zu, \"width\": %d, \"height\": %d, \"ours_median_ms\": %.3f, \"ours_p95_ms\": %.3f, "
        "\"ours_cpu_median_ms\": %.3f, \"ours_cpu_p95_ms\": %.3f, \"reference_median_ms\": %.3f, "
        "\"reference_p95_ms\": %.3f, \"reference_cpu_median_ms\": %.3f, \"ratio\": %.2f, \"cpu_ratio\": "
        "%.2f, "
        "\"ours_segmentation_median_ms\": %.3f, \"ours_floor_median_ms\": %.3f, "
        "\"ours_manhattan_median_ms\": %.3f, "
        "\"ours_classification_median_ms\": %.3f, \"reference_voxel_median_ms\": %.3f, "
        "\"reference_normals_median_ms\": %.3f, \"reference_growing_median_ms\": %.3f, "
        "\"reference_ransac_median_ms\": %.3f, \"reference_clusters_median_ms\": %.3f, "
        "\"ours_floor_found\": %d, \"reference_floor_found\": %d, \"ours_regions_median\": %.0f, "
        "\"reference_regions_median\": %.0f, \"ours_drop_median_ms\": %.3f, \"ours_drop_p95_ms\": %.3f, "
        "\"ours_drop_cpu_median_ms\": %.3f, \"drop_share\": %.4f, \"drop_cpu_share\": %.4f, "
        "\"ours_drop_found\": %d}\n",
        frames.size(), W, H, med, p95, cmed, cp95, rmed, rp95, rcmed, ratio, cratio, percentile(o_seg, 0.5),
        percentile(o_floor, 0.5), percentile(o_man, 0.5), percentile(o_cls, 0.5), percentile(r_vox, 0.5),
        percentile(r_norm, 0.5), percentile(r_grow, 0.5), percentile(r_ransac, 0.5), percentile(r_clu, 0.5),
        floors, ref_floors, percentile(o_regions, 0.5), percentile(r_regions, 0.5), dmed, dp95, dcmed, dshare,
        dcshare, drops);
    return 0;
  }
  std::printf("perception bench: %zu frames %dx%d, one thread\n", frames.size(), W, H);
  std::printf(
      "  ours       wall median %8.3f ms  p95 %8.3f ms | cpu median %8.3f ms  p95 %8.3f ms | floor on %d | "
      "regions median %.0f\n",
      med, p95, cmed, cp95, floors, percentile(o_regions, 0.5));
  std::printf(
      "    segmentation %.3f (backproject %.3f, seeds+growing %.3f [cells %.3f, fine seeds %.3f, "
      "strips+splits %.3f], "
      "merge %.3f, borders %.3f, regions %.3f, clusters %.3f)  floor %.3f  manhattan %.3f  classification "
      "%.3f\n",
      percentile(o_seg, 0.5), percentile(s_bp, 0.5), percentile(s_grow, 0.5), percentile(s_cells, 0.5),
      percentile(s_seeds, 0.5), percentile(s_strips, 0.5), percentile(s_merge, 0.5),
      percentile(s_refine, 0.5), percentile(s_fin, 0.5), percentile(s_cl, 0.5), percentile(o_floor, 0.5),
      percentile(o_man, 0.5), percentile(o_cls, 0.5));
  std::printf(
      "  drop stage wall median %8.3f ms  p95 %8.3f ms | cpu median %8.3f ms | %.1f%% of ours (wall), %.1f%% "
      "(cpu) | drop on %d\n",
      dmed, dp95, dcmed, 100.0 * dshare, 100.0 * dcshare, drops);
  std::printf(
      "  reference  wall median %8.3f ms  p95 %8.3f ms | cpu median %8.3f ms | floor on %d | regions median "
      "%.0f\n",
      rmed, rp95, rcmed, ref_floors, percentile(r_regions, 0.5));
  std::printf("    voxel %.3f  normals %.3f  region growing %.3f  ransac %.3f  euclidean clusters %.3f\n",
              percentile(r_vox, 0.5), percentile(r_norm, 0.5), percentile(r_grow, 0.5),
              percentile(r_ransac, 0.5), percentile(r_clu, 0.5));
  std::printf("  ratio (reference / ours, medians): wall %.1fx  cpu %.1fx\n", ratio, cratio);
  return 0;
}

}  // namespace

SG_BENCH("perception", "perception [--frames DIR|FILE|LIST.txt] [--count N] [--json] [--checksum]",
         "segmentation+floor+Manhattan+classification vs the paper's PCL pipeline; the drop stage's share",
         bench_perception);

}  // namespace stairguide::cli
