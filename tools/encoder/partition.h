// stipple host — the encoder in partitions (../shared/DESIGN.md "Beyond one
// machine"; docs/encoder.md "Partitions").
//
//   plan:  bounds, the scan's frame (normal orientation, view hint) and a
//          deterministic sample; the top of the tree from the sample, each
//          split a plane (2-means whose two centres share the parent's
//          metric), down to nodes of at most `partition_points` points.
//   route: every point goes down the planes into its partition's file; for
//          a scan whose normals are estimated, points near a plane also go
//          to the other side's halo file (neighbours, not members).
//   job:   one partition: normals (with its halo), its subtree (build_tree),
//          its nodes' statistics and moments, written to its node file.
//   merge: the top nodes from their children's moments, the sigma classes
//          from a sample of the nodes, the .spg written breadth-first
//          (tools/encoder/merge.h).
//
// A scan of at most `partition_points` points is one partition: its job is
// today's in-core build, so the file is the one encode_cloud always wrote.
// Every step is deterministic: the same plan and parts give the same bytes
// whatever the thread count and wherever the jobs ran.
//
// Files in a partition folder (docs/encoder.md lists their layouts):
//   plan.bin          the plan (this struct), CRC-32 at its end
//   jobs.txt          one line a job: "<id> <points> <halo points>"
//   part-NNNNN.pts    a partition's points; part-NNNNN.halo its halo
//   part-NNNNN.nodes  a job's result, CRC-32 at its end
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "tools/encoder/encoder.h"

namespace stipple {

// The hash that picks the plan's sample points and the classes' sample
// nodes by index (SplitMix64's finalizer): the same samples however the
// scan is read or the jobs are run.
inline uint64_t mix64(uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

// A top-tree node: internal (two children, a plane) or a partition.
struct TopNode {
  uint32_t parent = 0;       // the root's is itself
  uint32_t first_child = 0;  // 0 for a partition; children are adjacent
  uint32_t part = 0;         // a partition's index
  uint16_t depth = 0;
  Vec3 normal = Vec3::Zero();  // plane: a point p goes to the second child when normal . p > offset
  double offset = 0;
  bool leaf() const { return first_child == 0; }
};

struct PartitionPlan {
  uint64_t points = 0;
  int version = kSpgVersion;
  bool normals = true;         // the file stores normals
  bool colors = false;         // ... and colours
  bool estimate = false;       // jobs estimate normals (k-NN) with a halo
  bool count_duplicates = false;  // jobs count repeated positions (the scan was read in chunks)
  bool curvature_sign = true;  // sigma_n classes signed (EncodeOptions::curvature_sign)
  int normal_neighbours = 12;
  std::string normals_source;  // "file", "faces", "k-NN", "none"
  int classes[3] = {0, 0, 0};  // options: 0 automatic
  uint64_t class_sample = uint64_t{1} << 21;  // EncodeOptions::class_sample
  ScanFrame frame;
  TreeOptions tree;            // stats: sigma floor, normals, colours set for the scan
  uint8_t position_bits[3] = {0, 0, 0};  // the mean's field widths from a tolerance; 0: the paper's
  Vec3 origin = Vec3::Zero();
  float bmin[3] = {0, 0, 0}, bmax[3] = {0, 0, 0};
  double halo = 0;             // distance from a plane within which a point joins the other side's halo
  std::vector<TopNode> top;    // breadth-first, root first
  std::vector<uint64_t> part_points, part_halo;
  uint32_t partitions() const { return static_cast<uint32_t>(part_points.size()); }
  // The partition a position belongs to, down the planes.
  uint32_t route(const Vec3& p) const;
};

// The points a partition holds per point, as stored: position, then normal
// and colour where the plan has them (doubles).
size_t partition_point_bytes(const PartitionPlan& plan);

// The encode options' own checks (class counts, version, leaf size, balance).
bool check_encode_options(const EncodeOptions& options, std::string& error);

// The plan's pass over the scan, a chunk at a time in file order: the
// count, the bounds, and a deterministic sample of at most 2^20 points —
// every point of a smaller scan, else those whose index hashes under a
// threshold halved whenever the sample overflows (so the sample depends on
// the scan alone, not on how it was read).
struct PlanSampler {
  uint64_t count = 0;
  Box3 box;
  std::vector<Vec3> positions, normals;  // the sample (normals where the scan has them)
  void add(const PointCloud& chunk);

 private:
  std::vector<uint64_t> hashes;
  uint64_t threshold = ~uint64_t{0};
};

// What the plan needs to know of the scan besides its points.
struct ScanFacts {
  bool normals = false, colors = false;  // the file has them
  std::string normals_source;            // "file", "faces", "k-NN", "none"
  bool has_viewpoint = false;
  Vec3 viewpoint = Vec3::Zero();
  bool count_duplicates = false;  // jobs count repeated positions (a reader in chunks could not)
};

// The plan from the sampler's pass: frame, box, top tree, halo.
// `partition_points` 0 means from `options.memory`.
bool finish_plan(PlanSampler& sampler, const ScanFacts& facts, const EncodeOptions& options, PartitionPlan& plan,
                 std::string& error);

// The plan for a scan in memory (validated as encode_cloud validates).
// Normals from faces are computed here (they need the whole mesh); k-NN
// normals are left to the jobs.
bool make_plan(PointCloud& cloud, const EncodeOptions& options, PartitionPlan& plan, std::string& error,
               ProgressBar* progress = nullptr);

// Writes plan.bin and jobs.txt into `dir`; reads them back.
bool write_plan(const PartitionPlan& plan, const std::string& dir, std::string& error);
bool read_plan(const std::string& dir, PartitionPlan& plan, std::string& error);

// Sends points to their partitions' files in `dir` (and their halos), a
// chunk at a time in file order; finish() flushes and fills
// plan.part_points and part_halo.
class PartitionRouter {
 public:
  PartitionRouter(PartitionPlan& plan, const std::string& dir);
  ~PartitionRouter();
  // Points [begin, end) of `chunk`, in order.
  bool add(const PointCloud& chunk, std::string& error, size_t begin = 0, size_t end = SIZE_MAX);
  bool finish(std::string& error);

 private:
  struct Writer;
  PartitionPlan& plan_;
  std::vector<Writer> own_, halo_;
  std::vector<uint32_t> stack_;
};

// All of `cloud` through a router.
bool route_points(const PointCloud& cloud, PartitionPlan& plan, const std::string& dir, std::string& error,
                  ProgressBar* progress = nullptr);

std::string part_path(const std::string& dir, uint32_t part, const char* suffix);  // dir/part-00012.<suffix>

// What the merge needs of a partition besides its nodes.
struct PartSummary {
  uint64_t nodes = 0, leaves = 0, points = 0;
  int depth = 0;                      // of its subtree, its root 0
  std::vector<uint64_t> level_begin;  // nodes of local level d: [level_begin[d], level_begin[d + 1])
  // The root's moments: positions', the normals' sum, colours'.
  Moments position;
  Vec3 normal_sum = Vec3::Zero();
  Moments color;
  NodeStats root;
  TreeReport report;
  PartitionRatioAccumulator ratios;
  uint64_t duplicates = 0;  // repeated positions, when the plan counts them
  double normals_seconds = 0, tree_seconds = 0;  // a job run in this process (not in the file)
};

// A job's nodes, breadth-first as build_tree made them, read by ranges.
class PartNodes {
 public:
  virtual ~PartNodes() = default;
  virtual const PartSummary& summary() const = 0;
  // Nodes [begin, begin + count): child counts, point counts, statistics
  // (any may be null). False with `error` naming the file when it cannot.
  virtual bool read(uint64_t begin, uint64_t count, uint8_t* child_counts, uint32_t* points, NodeStats* stats,
                    std::string& error) = 0;
};

// A partition's points from its files: its own first (`own` of them), then
// its halo.
bool load_part_points(const std::string& dir, const PartitionPlan& plan, uint32_t part, PointCloud& points,
                      size_t& own, std::string& error);

// The normals a job gives its points when the scan has none: k nearest
// neighbours among the partition and its halo, oriented by the plan's frame;
// then the halo is dropped (points keeps its first `own`).
void estimate_part_normals(PointCloud& points, size_t own, const PartitionPlan& plan, int threads,
                           const std::function<void(double)>& progress = {});

// Runs partition `part` on `points`: its first `own` points are members, the
// rest its halo (neighbours for normals only). `points` is consumed.
std::unique_ptr<PartNodes> run_part(PointCloud& points, size_t own, const PartitionPlan& plan, uint32_t part,
                                    int threads, const std::function<void(double)>& progress = {});

// A job from files: reads part-N.pts (and .halo), runs it, writes
// part-N.nodes (atomically). The error names the file and what is wrong.
bool run_part_file(const std::string& dir, const PartitionPlan& plan, uint32_t part, int threads, std::string& error,
                   uint32_t* crc = nullptr);

// Opens part-N.nodes, checking its size, header and CRC-32 against the plan.
std::unique_ptr<PartNodes> open_part_file(const std::string& dir, const PartitionPlan& plan, uint32_t part,
                                          std::string& error);

}  // namespace stipple
