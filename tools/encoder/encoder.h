// stipple host — the encoder pipeline: scan -> normals -> hierarchy ->
// classification -> quantization -> `.spg` bytes (docs/format.md).
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/spg_format.h"
#include "platform/progress.h"
#include "tools/encoder/hierarchy.h"
#include "tools/encoder/orientation.h"
#include "tools/scan/ply_io.h"

namespace stipple {

struct EncodeOptions {
  TreeOptions tree;
  // Class counts; 0 means automatic: clamp(nodes / 16, 64, 2048) for
  // sigma_p, clamp(nodes / 64, 64, 1024) for sigma_n, 64 for sigma_c (what
  // the picture needs: docs/encoder.md "Classes").
  int classes_p = 0, classes_n = 0, classes_c = 0;
  // An error bound (docs/encoder.md "Tolerance"): the variance stop at it
  // (leaves of sigma1 at most `tolerance`) and position fields wide enough
  // that a cell is at most half of it (up to 16 bits); in the scan's units,
  // or with `tolerance_relative` a fraction of the bounding box's diagonal.
  // 0: none (the paper's 11/11/10-bit positions, leaves by point count).
  double tolerance = 0;
  bool tolerance_relative = false;
  bool normals = true;  // store normals (computed when the scan has none)
  bool colors = true;   // store colours when the scan has them
  // sigma_n with the curvature's sign (kAttrCurvatureSign; docs/encoder.md
  // "Curvature sign"): concave patches shade as such. Version 2 on.
  bool curvature_sign = true;
  bool cut_table = true;  // stipple encode: write MODEL.spg.cut beside the model (tools/embedded/model_file.h)
  int normal_neighbours = 12;
  // The .spg version written: kSpgVersion (16-bit class tables) or 1
  // (float32 tables, for readers that predate version 2).
  int format_version = kSpgVersion;
  // stipple encode --format-version 3: the version 2 file written, then its
  // records coded (tools/encoder/coded_file.h; format_version stays 2).
  bool coded_file = false;
  OrientOptions orient;  // how estimated normals face; also gives the file's view hint (tools/encoder/orientation.h)
  // The encoder may take the scan's positions and normals for the hierarchy
  // instead of copying them (48 bytes a point less at the peak); the cloud
  // is left without them. For callers that are done with the scan.
  bool consume_scan = false;
  // Partitions (tools/encoder/partition.h): a scan of more points than this
  // is encoded in partitions of at most about this many, each its own job.
  // 0: from `memory`.
  uint64_t partition_points = 0;
  // The memory the encoder may use, in bytes; 0: half of this host's.
  uint64_t memory = 0;
  // The sigma classes are fitted to every node's tuples up to this many
  // nodes, to a hashed sample of this many above (docs/encoder.md
  // "Partitions" measures the trade).
  uint64_t class_sample = uint64_t{1} << 21;
  // Where partition files go: "" for a folder beside the output (the
  // system's temporary folder when there is no output file).
  std::string tmp_dir;
};

// The partition size `options` asks for: partition_points, or the memory
// budget over a job's bytes a point.
uint64_t partition_points_for(const EncodeOptions& options);

struct EncodeReport {
  uint64_t points = 0, nodes = 0, leaves = 0;
  int depth = 0;
  uint64_t bytes = 0, record_bytes = 0;
  double bits_per_point = 0;
  std::string normals_source;  // "file", "faces", "k-NN", "none"
  bool colors = false;
  int classes[3] = {0, 0, 0};
  double class_rms_log_error[3] = {0, 0, 0};
  PartitionRatios ratios;
  TreeReport tree;
  ScanFrame frame;  // what analyse_scan decided: normal orientation, view hint
  uint32_t partitions = 1;  // jobs the scan was encoded in (tools/encoder/partition.h)
  uint64_t duplicates = 0;  // repeated positions the jobs counted (a scan read in chunks)
  uint64_t expanded_bytes = 0;  // --format-version 3: the version 2 file's bytes (`bytes` the coded file's)
  std::string cut_table;    // the cut table written beside the model (stipple encode; empty: none)
  uint64_t cut_table_bytes = 0;
  // Wall seconds of each stage: the scan's reading (the caller's), its
  // normals and frame, the hierarchy, the sigma classes, the records and file.
  // The plan's pass (a scan read in chunks: its first reading), the
  // partitions' (routing, or loading one partition), then the jobs.
  struct Stages {
    double read = 0, plan = 0, route = 0, normals = 0, hierarchy = 0, classes = 0, write = 0, coding = 0, cut_table = 0;
  } seconds;
};

// Encodes `cloud` (left as it is unless options.consume_scan), in
// partitions when it has more points than the options allow a job
// (tools/encoder/partition.h; their files go to a temporary folder, removed
// after). Returns false with a message naming the option at fault for
// invalid options.
bool encode_cloud(PointCloud& cloud, const EncodeOptions& options, std::vector<uint8_t>& spg, EncodeReport& report,
                  std::string& error, ProgressBar* progress = nullptr);
// The same written to `path` as it is made, never whole in memory; a
// failure leaves no file (the partitions' folder goes beside it, unless
// options.tmp_dir).
bool encode_to_file(PointCloud& cloud, const EncodeOptions& options, const std::string& path, EncodeReport& report,
                    std::string& error, ProgressBar* progress = nullptr);

// A scan file to a .spg file. PLY, LAS and PCD are read a chunk at a time,
// twice (the plan's pass, then the partitions'), so no more than a
// partition is in memory whatever the scan's size; text and OBJ scans, and
// meshes whose faces give the normals, are read whole. `warn` receives the
// reader's warnings once it has read the scan (and, for a scan read in
// chunks, the repeated positions' at the end). Errors name the file.
bool encode_scan_file(const std::string& scan, const ScanOptions& scan_options, const EncodeOptions& options,
                      const std::string& path, EncodeReport& report, std::string& error, ProgressBar* progress,
                      const std::function<void(const std::vector<std::string>&)>& warn);

// The same as far as the partitions: the plan and the partitions' files in
// `dir` (plan.bin, jobs.txt, part-N.pts), for jobs run elsewhere
// (`stipple encode-part`, tools/cluster/).
struct PartitionPlan;
bool plan_scan_file(const std::string& scan, const ScanOptions& scan_options, const EncodeOptions& options,
                    const std::string& dir, PartitionPlan& plan, std::string& error, ProgressBar* progress,
                    const std::function<void(const std::vector<std::string>&)>& warn);

// A model for the programs that draw (render, the viewers): a .spg file's
// bytes as they are, or — as pcl_viewer opens a scan — any scan
// read_point_cloud reads, encoded in memory with the default options (a
// progress bar on a terminal). For a scan it says so on stderr, with the
// reader's warnings: "stipple: data/bunny.ply: a scan, encoded in memory:
// 6,913 nodes in 0.41 s (stipple encode data/bunny.ply -o bunny.spg keeps
// it)"; a .spg passes silently. The error names the file as the reader or
// the encoder does.
bool read_model(const std::string& path, std::vector<uint8_t>& spg, std::string& error);

// What the encoder does to a scan before its tree: normals where it has none
// (its faces' first, else k nearest neighbours, oriented by analyse_scan's
// rules, which also give the view hint), returned as the scan's frame.
// `progress` (may be empty) sees the estimation's fraction done.
ScanFrame prepare_scan(PointCloud& cloud, const EncodeOptions& options,
                       const std::function<void(double, const char*)>& progress = {});

// The origin a file of `version` stores its box relative to (docs/format.md
// §1): the origin itself in version 1 and for a scan near it; the box's
// centre for one far from it for its size (farther than 1024 extents), so
// the float32 box keeps the scan's precision.
Vec3 stored_origin(const std::vector<Vec3>& points, int version);

// The bounding box as stored: float32, relative to `origin`, rounded
// outwards so it contains every point.
void stored_bounding_box(const std::vector<Vec3>& points, const Vec3& origin, float min[3], float max[3]);
// The same from the points' bounding box.
Vec3 stored_origin(const Box3& box, int version);
void stored_bounding_box(const Box3& box, const Vec3& origin, float min[3], float max[3]);

}  // namespace stipple
