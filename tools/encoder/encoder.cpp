// stipple host — encoder pipeline; the file is written by core/spg_writer (docs/format.md).
#include "tools/embedded/model_file.h"
#include "tools/encoder/encoder.h"

#include <unistd.h>

#include <algorithm>
#include <atomic>
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
#include "tools/encoder/partition.h"
#include "tools/scan/ply_io.h"

namespace stipple {
Vec3 stored_origin(const std::vector<Vec3>& points, int version) {
  if (points.empty()) return Vec3::Zero();
  return stored_origin(bounding_box(points), version);
}

void stored_bounding_box(const std::vector<Vec3>& points, const Vec3& origin, float min[3], float max[3]) {
  stored_bounding_box(bounding_box(points), origin, min, max);
}

Vec3 stored_origin(const Box3& box, int version) {
  if (version < 2) return Vec3::Zero();
  const double extent = (box.max - box.min).maxCoeff();
  const double far = std::max(box.min.cwiseAbs().maxCoeff(), box.max.cwiseAbs().maxCoeff());
  return far > 1024 * extent ? Vec3((box.min + box.max) / 2) : Vec3::Zero();
}

void stored_bounding_box(const Box3& box, const Vec3& origin, float min[3], float max[3]) {
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

// Where the points come from: a scan in memory, or a file read a chunk at a
// time (twice: the plan's pass, then the partitions').
class ScanSource {
 public:
  virtual ~ScanSource() = default;
  virtual bool plan(const EncodeOptions& o, PartitionPlan& plan, std::string& error, ProgressBar* progress) = 0;
  // A plan of one partition: the whole scan, in memory.
  virtual PointCloud* load(const PartitionPlan& plan, std::string& error, ProgressBar* progress) = 0;
  // More: every point into its partition's file.
  virtual bool route(PartitionPlan& plan, const std::string& dir, std::string& error, ProgressBar* progress) = 0;
};

class MemorySource final : public ScanSource {
 public:
  MemorySource(PointCloud& cloud, bool consume) : scan_(&cloud) {
    if (!consume) {
      copy_ = cloud;
      scan_ = &copy_;
    }
  }
  bool plan(const EncodeOptions& o, PartitionPlan& plan, std::string& error, ProgressBar* progress) override {
    return make_plan(*scan_, o, plan, error, progress);
  }
  PointCloud* load(const PartitionPlan&, std::string&, ProgressBar*) override { return scan_; }
  bool route(PartitionPlan& plan, const std::string& dir, std::string& error, ProgressBar* progress) override {
    if (!route_points(*scan_, plan, dir, error, progress)) return false;
    *scan_ = PointCloud{};  // the points are in the partitions now
    return true;
  }

 private:
  PointCloud* scan_;
  PointCloud copy_;
};

// A PLY, LAS or PCD file, memory-mapped and read in chunks: no more of the
// scan is in memory than a chunk (or one partition).
class FileSource final : public ScanSource {
 public:
  FileSource(std::string path, ScanOptions options, const std::function<void(const std::vector<std::string>&)>& warn)
      : path_(std::move(path)), options_(std::move(options)), warn_(warn) {}
  bool plan(const EncodeOptions& o, PartitionPlan& plan, std::string& error, ProgressBar* progress) override {
    if (!check_encode_options(o, error)) return false;
    ScanStream stream;
    bool first = true;
    stream.deliver = [&](PointCloud& chunk, uint64_t, uint64_t bytes, std::string&) {
      if (first) {
        facts_.normals = chunk.has_normals();
        facts_.colors = chunk.has_colors();
        first = false;
      }
      sampler_.add(chunk);
      if (progress) progress->update(0.1 * static_cast<double>(bytes) / static_cast<double>(size_), "planning");
      return true;
    };
    std::error_code ec;  // a file gone since: the reader below says so
    const uint64_t bytes = std::filesystem::file_size(path_, ec);
    size_ = ec ? 1 : std::max<uint64_t>(1, bytes);
    PointCloud rest;
    if (!stream_point_cloud(path_, stream, rest, error, options_)) return false;
    if (!stream.text_columns.empty()) {
      // Columns 4-6 of a text scan, told apart by the whole file: read it
      // again with them named (its warnings are the first reading's).
      if (!parse_text_columns(stream.text_columns, options_.columns, error)) return false;
      const std::vector<std::string> warnings = rest.warnings;
      sampler_ = PlanSampler{};
      first = true;
      stream.delivered = 0;
      stream.text_columns.clear();
      if (!stream_point_cloud(path_, stream, rest, error, options_)) return false;
      rest.warnings = warnings;
    }
    if (stream.triangles > 0 && o.normals && !facts_.normals) {
      // A mesh without normals: its faces give them, and need it whole.
      if (!read_point_cloud(path_, whole_, error, options_)) return false;
      warn_(whole_.warnings);
      memory_ = std::make_unique<MemorySource>(whole_, true);
      return memory_->plan(o, plan, error, progress) || (error = path_ + ": " + error, false);
    }
    warn_(rest.warnings);
    divisor_ = stream.color_divisor;
    facts_.colors = facts_.colors && divisor_ != 0;
    facts_.normals_source = !o.normals ? "none" : facts_.normals ? "file" : "k-NN";
    facts_.has_viewpoint = rest.has_viewpoint;
    facts_.viewpoint = rest.viewpoint;
    facts_.count_duplicates = true;
    if (!finish_plan(sampler_, facts_, o, plan, error)) return error = path_ + ": " + error, false;
    box_ = sampler_.box;
    sampler_ = PlanSampler{};
    return true;
  }
  PointCloud* load(const PartitionPlan& plan, std::string& error, ProgressBar* progress) override {
    if (memory_) return memory_->load(plan, error, progress);
    whole_ = PointCloud{};
    const bool normals = plan.normals && !plan.estimate;
    whole_.positions.reserve(plan.points);
    if (normals) whole_.normals.reserve(plan.points);
    if (plan.colors) whole_.colors.reserve(plan.points);
    if (!pass([&](PointCloud& chunk, std::string&) {
          whole_.positions.insert(whole_.positions.end(), chunk.positions.begin(), chunk.positions.end());
          if (normals) whole_.normals.insert(whole_.normals.end(), chunk.normals.begin(), chunk.normals.end());
          if (plan.colors) whole_.colors.insert(whole_.colors.end(), chunk.colors.begin(), chunk.colors.end());
          return true;
        }, "reading", progress, error))
      return nullptr;
    return &whole_;
  }
  bool route(PartitionPlan& plan, const std::string& dir, std::string& error, ProgressBar* progress) override {
    if (memory_) return memory_->route(plan, dir, error, progress);
    PartitionRouter router(plan, dir);
    return pass([&](PointCloud& chunk, std::string& why) { return router.add(chunk, why); }, "routing points to partitions",
                progress, error) &&
           router.finish(error);
  }
  const Box3& box() const { return box_; }
  bool streamed() const { return !memory_; }

 private:
  // The second pass: every chunk, its colours scaled as the reader said.
  bool pass(const std::function<bool(PointCloud&, std::string&)>& fn, const char* phase, ProgressBar* progress,
            std::string& error) {
    ScanStream stream;
    stream.deliver = [&](PointCloud& chunk, uint64_t, uint64_t bytes, std::string& why) {
      if (divisor_ == 0) chunk.colors.clear();
      else if (divisor_ != 1)
        for (Vec3& c : chunk.colors) c /= divisor_;
      if (progress) progress->update(0.1 + 0.2 * static_cast<double>(bytes) / static_cast<double>(size_), phase);
      return fn(chunk, why);
    };
    PointCloud rest;
    return stream_point_cloud(path_, stream, rest, error, options_);
  }

  std::string path_;
  ScanOptions options_;
  std::function<void(const std::vector<std::string>&)> warn_;
  PlanSampler sampler_;
  ScanFacts facts_;
  Box3 box_;
  double divisor_ = 1;
  uint64_t size_ = 1;
  PointCloud whole_;
  std::unique_ptr<MemorySource> memory_;  // a mesh whose faces give the normals
};

// The encoder's one path (tools/encoder/partition.h): plan, jobs, merge.
bool encode_through(ScanSource& source, const EncodeOptions& o, const std::string& output, const ByteSink& sink,
                    EncodeReport& report, std::string& error, ProgressBar* progress) {
  report = EncodeReport{};
  const double start = monotonic_seconds();
  PartitionPlan plan;
  if (!source.plan(o, plan, error, progress)) return false;
  report.seconds.plan = monotonic_seconds() - start;
  const int threads = o.tree.threads;
  std::vector<std::unique_ptr<PartNodes>> parts;
  TempFolder folder;
  if (plan.partitions() == 1) {
    const double load_start = monotonic_seconds();
    PointCloud* scan = source.load(plan, error, progress);
    if (!scan) return false;
    report.seconds.route = monotonic_seconds() - load_start;
    const double tree_start = plan.estimate ? 0.3 : 0.02;
    parts.push_back(run_part(*scan, scan->size(), plan, 0, threads, [&](double f) {
      if (!progress) return;
      if (plan.estimate && f < 0.3) progress->update(f, "estimating normals");
      else progress->update(tree_start + (0.85 - tree_start) * (plan.estimate ? (f - 0.3) / 0.7 : f), "building hierarchy");
    }));
    report.seconds.normals = parts[0]->summary().normals_seconds;
    report.seconds.hierarchy = parts[0]->summary().tree_seconds;
  } else {
    std::string base = o.tmp_dir;
    if (base.empty()) {
      const std::filesystem::path out(output);
      base = !output.empty() ? (out.has_parent_path() ? out.parent_path().string() : std::string("."))
                             : std::filesystem::temp_directory_path().string();
    }
    if (!folder.create(base, error)) return false;
    const double route_start = monotonic_seconds();
    if (!source.route(plan, folder.path(), error, progress)) return false;
    report.seconds.route = monotonic_seconds() - route_start;
    const double jobs_start = monotonic_seconds();
    uint64_t done = 0;
    for (uint32_t i = 0; i < plan.partitions(); ++i) {
      if (progress)
        progress->update(0.3 + 0.55 * static_cast<double>(done) / static_cast<double>(plan.points),
                         ("partition " + std::to_string(i + 1) + " of " + std::to_string(plan.partitions())).c_str());
      if (!run_part_file(folder.path(), plan, i, threads, error)) return false;
      // Its points are done with: the disk holds a partition's points or
      // its nodes, not both, for each partition.
      std::error_code ec;
      std::filesystem::remove(part_path(folder.path(), i, "pts"), ec);
      std::filesystem::remove(part_path(folder.path(), i, "halo"), ec);
      std::unique_ptr<PartNodes> part = open_part_file(folder.path(), plan, i, error);
      if (!part) return false;
      parts.push_back(std::move(part));
      done += plan.part_points[i];
    }
    report.seconds.hierarchy = monotonic_seconds() - jobs_start;
  }
  const EncodeReport::Stages seconds = report.seconds;
  if (!merge_parts(plan, parts, threads, sink, report, error, progress)) return false;
  report.seconds.plan = seconds.plan;
  report.seconds.route = seconds.route;
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
  MemorySource source(cloud, o.consume_scan);
  if (!encode_through(source, o, "", sink, report, error, progress)) return false;
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
  MemorySource source(cloud, o.consume_scan);
  if (!encode_through(source, o, path, sink_into(file), report, error, progress)) return false;
  const double start = monotonic_seconds();
  if (!file.commit(error)) return false;
  report.seconds.write += monotonic_seconds() - start;
  return true;
}

bool plan_scan_file(const std::string& scan, const ScanOptions& scan_options, const EncodeOptions& o,
                    const std::string& dir, PartitionPlan& plan, std::string& error, ProgressBar* progress,
                    const std::function<void(const std::vector<std::string>&)>& warn) {
  PointCloud cloud;
  std::unique_ptr<ScanSource> source;
  if (scan_streams(scan)) {
    source = std::make_unique<FileSource>(scan, scan_options, warn);
  } else {
    if (!read_point_cloud(scan, cloud, error, scan_options)) return false;
    warn(cloud.warnings);
    source = std::make_unique<MemorySource>(cloud, true);
  }
  return source->plan(o, plan, error, progress) && source->route(plan, dir, error, progress) &&
         write_plan(plan, dir, error);
}

bool encode_scan_file(const std::string& scan, const ScanOptions& scan_options, const EncodeOptions& o,
                      const std::string& path, EncodeReport& report, std::string& error, ProgressBar* progress,
                      const std::function<void(const std::vector<std::string>&)>& warn) {
  const double start = monotonic_seconds();
  if (!scan_streams(scan)) {
    PointCloud cloud;
    if (!read_point_cloud(scan, cloud, error, scan_options)) return false;
    warn(cloud.warnings);
    EncodeOptions consume = o;
    consume.consume_scan = true;
    const double read = monotonic_seconds() - start;
    if (!encode_to_file(cloud, consume, path, report, error, progress)) return false;
    report.seconds.read = read;
    return true;
  }
  AtomicFileWriter file;
  if (!file.open(path, error)) return false;
  FileSource source(scan, scan_options, warn);
  if (!encode_through(source, o, path, sink_into(file), report, error, progress)) return false;
  if (!file.commit(error)) return false;
  if (source.streamed())
    if (std::string w = duplicate_warning(scan, report.duplicates, report.points, source.box()); !w.empty()) warn({w});
  return true;
}

bool read_model(const std::string& path, std::vector<uint8_t>& spg, std::string& error) {
  if (!read_file(path, spg, error)) return false;
  if (spg.size() >= 4 && std::memcmp(spg.data(), kSpgMagic, 4) == 0)  // a .spg: validated by its reader
    return expand_coded_spg(spg, path, error);
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
