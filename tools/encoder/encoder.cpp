// stipple host — encoder pipeline; the file is written by core/spg_writer (docs/format.md).
#include "tools/encoder/encoder.h"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cmath>
#include <cstring>
#include <filesystem>

#include "core/spg_format.h"
#include "core/spg_writer.h"
#include "platform/file_io.h"
#include "tools/embedded/options.h"
#include "tools/encoder/merge.h"
#include "tools/encoder/normals.h"
#include "tools/scan/ply_io.h"

namespace stipple {
Vec3 stored_origin(const std::vector<Vec3>& points, int version) {
  if (version < 2 || points.empty()) return Vec3::Zero();
  const Box3 box = bounding_box(points);
  const double extent = (box.max - box.min).maxCoeff();
  const double far = std::max(box.min.cwiseAbs().maxCoeff(), box.max.cwiseAbs().maxCoeff());
  return far > 1024 * extent ? Vec3((box.min + box.max) / 2) : Vec3::Zero();
}

void stored_bounding_box(const std::vector<Vec3>& points, const Vec3& origin, float min[3], float max[3]) {
  const Box3 box = bounding_box(points);
  for (int a = 0; a < 3; ++a) {
    const double l = box.min[a] - origin[a], h = box.max[a] - origin[a];
    float lo = static_cast<float>(l), hi = static_cast<float>(h);
    if (static_cast<double>(lo) > l) lo = std::nextafter(lo, -INFINITY);
    if (static_cast<double>(hi) < h) hi = std::nextafter(hi, INFINITY);
    min[a] = lo;
    max[a] = hi;
  }
}

ScanFrame prepare_scan(PointCloud& cloud, const EncodeOptions& o, const std::function<void(double, const char*)>& progress) {
  const bool estimate = o.normals && !cloud.has_normals();
  if (estimate && !cloud.triangles.empty()) estimate_normals(cloud, o.normal_neighbours, ScanFrame{}, progress, o.tree.threads);
  OrientOptions orient = o.orient;
  if (cloud.has_viewpoint && !orient.has_viewpoint) {  // the file's sensor position, unless an option gives one
    orient.has_viewpoint = true;
    orient.viewpoint = cloud.viewpoint;
  }
  const ScanFrame frame = analyse_scan(cloud.positions, orient, cloud.has_normals() ? &cloud.normals : nullptr);
  if (estimate && !cloud.has_normals()) estimate_normals(cloud, o.normal_neighbours, frame, progress, o.tree.threads);
  return frame;
}

namespace {

// A folder for partition files, removed with all it holds when it goes out
// of scope: after a success, an error or an exception alike.
class TempFolder {
 public:
  TempFolder() = default;
  TempFolder(const TempFolder&) = delete;
  TempFolder& operator=(const TempFolder&) = delete;
  ~TempFolder() {
    std::error_code ec;
    if (!path_.empty()) std::filesystem::remove_all(path_, ec);
  }
  bool create(const std::string& base, std::string& error) {
    static std::atomic<unsigned> serial{0};
    const std::filesystem::path folder = base.empty() ? std::filesystem::path(".") : std::filesystem::path(base);
    const std::string name = "stipple-parts." + std::to_string(static_cast<long>(getpid())) + "." + std::to_string(serial++);
    std::error_code ec;
    const std::filesystem::path path = folder / name;
    if (!std::filesystem::create_directory(path, ec))
      return error = path.string() + ": cannot create the partitions' folder: " + (ec ? ec.message() : "it exists") + " (--tmp DIR puts it elsewhere)", false;
    path_ = path.string();
    return true;
  }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

// The encoder's one path (tools/encoder/partition.h): plan, jobs, merge.
bool encode_through(PointCloud& cloud, const EncodeOptions& o, const std::string& output, const ByteSink& sink,
                    EncodeReport& report, std::string& error, ProgressBar* progress) {
  report = EncodeReport{};
  const double start = monotonic_seconds();
  PointCloud copy;
  PointCloud* scan = &cloud;
  if (!o.consume_scan) {
    copy = cloud;
    scan = &copy;
  }
  PartitionPlan plan;
  if (!make_plan(*scan, o, plan, error, progress)) return false;
  const int threads = o.tree.threads;
  std::vector<std::unique_ptr<PartNodes>> parts;
  TempFolder folder;
  if (plan.partitions() == 1) {
    const double plan_seconds = monotonic_seconds() - start;
    const double tree_start = plan.estimate ? 0.3 : 0.02;
    parts.push_back(run_part(*scan, scan->size(), plan, 0, threads, [&](double f) {
      if (!progress) return;
      if (plan.estimate && f < 0.3) progress->update(f, "estimating normals");
      else progress->update(tree_start + (0.85 - tree_start) * (plan.estimate ? (f - 0.3) / 0.7 : f), "building hierarchy");
    }));
    report.seconds.normals = plan_seconds + parts[0]->summary().normals_seconds;
    report.seconds.hierarchy = parts[0]->summary().tree_seconds;
  } else {
    std::string base = o.tmp_dir;
    if (base.empty()) {
      const std::filesystem::path out(output);
      base = !output.empty() ? (out.has_parent_path() ? out.parent_path().string() : std::string("."))
                             : std::filesystem::temp_directory_path().string();
    }
    if (!folder.create(base, error)) return false;
    if (!route_points(*scan, plan, folder.path(), error, progress)) return false;
    *scan = PointCloud{};  // the points are in the partitions now
    report.seconds.normals = monotonic_seconds() - start;
    const double jobs_start = monotonic_seconds();
    uint64_t done = 0;
    for (uint32_t i = 0; i < plan.partitions(); ++i) {
      if (progress)
        progress->update(0.3 + 0.55 * static_cast<double>(done) / static_cast<double>(plan.points),
                         ("partition " + std::to_string(i + 1) + " of " + std::to_string(plan.partitions())).c_str());
      if (!run_part_file(folder.path(), plan, i, threads, error)) return false;
      std::unique_ptr<PartNodes> part = open_part_file(folder.path(), plan, i, error);
      if (!part) return false;
      parts.push_back(std::move(part));
      done += plan.part_points[i];
    }
    report.seconds.hierarchy = monotonic_seconds() - jobs_start;
  }
  const EncodeReport::Stages seconds = report.seconds;
  if (!merge_parts(plan, parts, threads, sink, report, error, progress)) return false;
  report.seconds.normals = seconds.normals;
  report.seconds.hierarchy = seconds.hierarchy;
  report.partitions = plan.partitions();
  if (progress) progress->update(1.0, "done");
  return true;
}

}  // namespace

bool encode_cloud(PointCloud& cloud, const EncodeOptions& o, std::vector<uint8_t>& spg, EncodeReport& report,
                  std::string& error, ProgressBar* progress) {
  spg.clear();
  const ByteSink sink = [&spg](const uint8_t* data, size_t size, std::string&) {
    spg.insert(spg.end(), data, data + size);
    return true;
  };
  if (!encode_through(cloud, o, "", sink, report, error, progress)) return false;
  // The reader's checks on the bytes written: never a file it refuses.
  SpgView view;
  if (const SpgResult r = spg_parse(spg.data(), spg.size(), &view); !r.ok())
    return error = std::string("encoder: wrote a file the reader refuses (") + spg_error_text(r.error) + ")", false;
  return true;
}

bool encode_to_file(PointCloud& cloud, const EncodeOptions& o, const std::string& path, EncodeReport& report,
                    std::string& error, ProgressBar* progress) {
  AtomicFileWriter file;
  if (!file.open(path, error)) return false;
  const ByteSink sink = [&file, &path](const uint8_t* data, size_t size, std::string& why) {
    if (file.write(data, size)) return true;
    why = path + ": write failed: " + std::strerror(errno);
    return false;
  };
  if (!encode_through(cloud, o, path, sink, report, error, progress)) return false;
  const double start = monotonic_seconds();
  if (!file.commit(error)) return false;
  report.seconds.write += monotonic_seconds() - start;
  return true;
}

bool read_model(const std::string& path, std::vector<uint8_t>& spg, std::string& error) {
  if (!read_file(path, spg, error)) return false;
  if (spg.size() >= 4 && std::memcmp(spg.data(), kSpgMagic, 4) == 0) return true;  // a .spg: validated by its reader
  std::vector<uint8_t> bytes;
  bytes.swap(spg);
  PointCloud cloud;
  if (!parse_point_cloud(path, bytes.data(), bytes.size(), cloud, error)) return false;
  bytes = {};
  for (const std::string& w : cloud.warnings) std::fprintf(stderr, "stipple: warning: %s\n", w.c_str());
  const auto start = std::chrono::steady_clock::now();
  ProgressBar progress("encode " + path, true);
  EncodeReport report;
  EncodeOptions options;
  options.consume_scan = true;  // the scan is not needed after
  if (!encode_cloud(cloud, options, spg, report, error, &progress)) return error = path + ": " + error, false;
  progress.finish();
  // The model's name: the scan's, in the current folder (the scan's own may be read-only).
  std::string stem = path.substr(path.find_last_of('/') + 1);
  if (const size_t dot = stem.find_last_of('.'); dot != std::string::npos && dot > 0) stem.resize(dot);
  std::fprintf(stderr, "stipple: %s: a scan, encoded in memory: %s nodes in %.2f s (stipple encode %s -o %s.spg keeps it)\n",
               path.c_str(), cli::with_commas(report.nodes).c_str(),
               std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), path.c_str(), stem.c_str());
  return true;
}

}  // namespace stipple
