// stipple host — the encoder in partitions. See partition.h.
#include "tools/encoder/partition.h"

#include <algorithm>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "core/spg_format.h"
#include "platform/file_io.h"
#include "tools/encoder/normals.h"
#include "tools/scan/kdtree.h"
#include "tools/scan/ply_io.h"

namespace stipple {

static_assert(std::endian::native == std::endian::little, "partition files are written in the host's byte order");

namespace {

// Bytes a job holds a point at its peak, for the partition size a memory
// budget allows (measured: docs/encoder.md "Partitions").
constexpr uint64_t kJobBytesPerPoint = 256;
// The plan's sample: at most this many points (all of a smaller scan).
constexpr uint64_t kSampleSize = uint64_t{1} << 20;
// More partitions than this is a memory budget too small for the scan.
constexpr uint32_t kMaxPartitions = 4096;
// 2: the variance stop and the position widths (a tolerance).
constexpr char kPlanMagic[8] = {'S', 'P', 'G', 'P', 'L', 'A', 'N', '2'};
constexpr char kNodesMagic[8] = {'S', 'P', 'G', 'N', 'O', 'D', 'E', '2'};  // 2: the turn (curvature sign) in the statistics
constexpr size_t kStatsDoubles = 43;

// Little binary records: plain values in the host's (little-endian) order.
class Out {
 public:
  template <class T>
  void put(const T& v) {
    const auto* p = reinterpret_cast<const uint8_t*>(&v);
    bytes.insert(bytes.end(), p, p + sizeof v);
  }
  void vec(const Vec3& v) { put_doubles(v.data(), 3); }
  void mat(const Mat3& m) { put_doubles(m.data(), 9); }
  void put_doubles(const double* d, size_t n) {
    for (size_t i = 0; i < n; ++i) put(d[i]);
  }
  void str(const std::string& s) {
    put(static_cast<uint32_t>(s.size()));
    bytes.insert(bytes.end(), s.begin(), s.end());
  }
  std::vector<uint8_t> bytes;
};

class In {
 public:
  In(const uint8_t* data, size_t size) : p_(data), left_(size) {}
  template <class T>
  T get() {
    T v{};
    if (left_ < sizeof v) {
      ok_ = false;
      return v;
    }
    std::memcpy(&v, p_, sizeof v);
    p_ += sizeof v;
    left_ -= sizeof v;
    return v;
  }
  Vec3 vec() {
    Vec3 v;
    for (int i = 0; i < 3; ++i) v[i] = get<double>();
    return v;
  }
  Mat3 mat() {
    Mat3 m;
    for (int i = 0; i < 9; ++i) m.data()[i] = get<double>();
    return m;
  }
  std::string str() {
    const uint32_t n = get<uint32_t>();
    if (!ok_ || n > left_) return ok_ = false, std::string();
    std::string s(reinterpret_cast<const char*>(p_), n);
    p_ += n;
    left_ -= n;
    return s;
  }
  bool ok() const { return ok_; }
  size_t left() const { return left_; }

 private:
  const uint8_t* p_;
  size_t left_;
  bool ok_ = true;
};

void put_stats(Out& out, const NodeStats& s) {
  out.vec(s.position.mean);
  out.mat(s.position.frame);
  out.vec(s.position.sigma);
  out.mat(s.normal_frame);
  out.put(s.sigma_n[0]);
  out.put(s.sigma_n[1]);
  out.put(s.turn[0]);
  out.put(s.turn[1]);
  out.vec(s.color.mean);
  out.mat(s.color.frame);
  out.vec(s.color.sigma);
}

void get_stats(const double* d, NodeStats& s) {
  std::memcpy(s.position.mean.data(), d, 3 * 8);
  std::memcpy(s.position.frame.data(), d + 3, 9 * 8);
  std::memcpy(s.position.sigma.data(), d + 12, 3 * 8);
  std::memcpy(s.normal_frame.data(), d + 15, 9 * 8);
  std::memcpy(s.sigma_n.data(), d + 24, 2 * 8);
  std::memcpy(s.turn.data(), d + 26, 2 * 8);
  std::memcpy(s.color.mean.data(), d + 28, 3 * 8);
  std::memcpy(s.color.frame.data(), d + 31, 9 * 8);
  std::memcpy(s.color.sigma.data(), d + 40, 3 * 8);
}

std::string errno_text() { return std::strerror(errno); }

// The plane splitting a top node's sample points: 2-means whose centres share
// the node's metric (its PCA, axes clamped at 1e-3 sigma1 as the hierarchy
// clamps them), so the boundary is the plane normal . p = offset. A split
// leaving less than a tenth on one side falls back to the median along the
// major axis. False when the points cannot be split (all equal).
bool split_plane(const std::vector<Vec3>& sample, std::vector<uint32_t>& ids, Vec3& normal, double& offset,
                 size_t& left_count) {
  const size_t n = ids.size();
  const Gaussian3 g = pca3(sample.data(), ids.data(), n);
  if (!(g.sigma[0] > 0)) return false;
  Mat3 metric = Mat3::Zero();
  for (int k = 0; k < 3; ++k) {
    const double s = std::max(g.sigma[k], 1e-3 * g.sigma[0]);
    metric += g.frame.col(k) * g.frame.col(k).transpose() / (s * s);
  }
  Vec3 lo = g.mean - 0.8 * g.sigma[0] * g.frame.col(0), hi = g.mean + 0.8 * g.sigma[0] * g.frame.col(0);
  std::vector<uint8_t> side(n, 2);
  size_t right = 0;
  for (int it = 0; it < 30; ++it) {
    normal = 2 * metric * (hi - lo);
    offset = hi.dot(metric * hi) - lo.dot(metric * lo);
    bool changed = false;
    Vec3 sum[2] = {Vec3::Zero(), Vec3::Zero()};
    size_t count[2] = {0, 0};
    for (size_t i = 0; i < n; ++i) {
      const Vec3& p = sample[ids[i]];
      const uint8_t s = normal.dot(p) > offset;
      changed |= s != side[i];
      side[i] = s;
      sum[s] += p;
      ++count[s];
    }
    right = count[1];
    if (!changed || count[0] == 0 || count[1] == 0) break;
    lo = sum[0] / static_cast<double>(count[0]);
    hi = sum[1] / static_cast<double>(count[1]);
  }
  const double length = normal.norm();
  if (std::min(right, n - right) < n / 10 || !(length > 0) || !std::isfinite(length)) {
    normal = g.frame.col(0);
    std::vector<double> along(n);
    for (size_t i = 0; i < n; ++i) along[i] = normal.dot(sample[ids[i]]);
    std::nth_element(along.begin(), along.begin() + static_cast<std::ptrdiff_t>(n / 2), along.end());
    offset = along[n / 2];
  } else {
    normal /= length;
    offset /= length;
  }
  // Left first, each side in sample order (stable).
  std::vector<uint32_t> sorted;
  sorted.reserve(n);
  for (const uint32_t i : ids)
    if (!(normal.dot(sample[i]) > offset)) sorted.push_back(i);
  left_count = sorted.size();
  for (const uint32_t i : ids)
    if (normal.dot(sample[i]) > offset) sorted.push_back(i);
  ids.swap(sorted);
  return left_count > 0 && left_count < n;
}

// The distance within which a point's k nearest neighbours lie, from the
// sample: its 90th percentile nearest-neighbour distance scaled to the
// whole scan's density (a surface: distances shrink as the square root of
// the points), times 2 for safety.
double halo_distance(const std::vector<Vec3>& sample, uint64_t points, int k) {
  if (sample.size() < 3) return 0;
  const KdTree tree(sample);
  std::vector<double> d;
  std::vector<uint32_t> nb;
  const size_t queries = std::min<size_t>(2000, sample.size());
  for (size_t q = 0; q < queries; ++q) {
    const Vec3& p = sample[q * sample.size() / queries];
    tree.knearest(p, 2, nb);
    if (nb.size() == 2) d.push_back((sample[nb[1]] - p).norm());
  }
  if (d.empty()) return 0;
  std::sort(d.begin(), d.end());
  const double p90 = d[d.size() * 9 / 10];
  return 2 * p90 * std::sqrt(static_cast<double>(k) * static_cast<double>(sample.size()) / static_cast<double>(points));
}

}  // namespace

uint64_t partition_points_for(const EncodeOptions& o) {
  if (o.partition_points) return o.partition_points;
  uint64_t memory = o.memory;
  if (memory == 0) memory = std::max<uint64_t>(physical_memory_bytes() / 2, uint64_t{1} << 30);
  return std::max<uint64_t>(memory / kJobBytesPerPoint, uint64_t{1} << 16);
}

uint32_t PartitionPlan::route(const Vec3& p) const {
  uint32_t t = 0;
  while (!top[t].leaf()) t = top[t].first_child + (top[t].normal.dot(p) > top[t].offset);
  return top[t].part;
}

size_t partition_point_bytes(const PartitionPlan& plan) {
  return 24 + (plan.normals && !plan.estimate ? 24 : 0) + (plan.colors ? 24 : 0);
}

std::string part_path(const std::string& dir, uint32_t part, const char* suffix) {
  char name[32];
  std::snprintf(name, sizeof name, "part-%05u.%s", part, suffix);
  return (std::filesystem::path(dir) / name).string();
}

bool check_encode_options(const EncodeOptions& o, std::string& error) {
  if (o.classes_p < 0 || o.classes_p > 4096) return error = "--classes: sigma_p classes must be 1..4096", false;
  if (o.classes_n < 0 || o.classes_n > 4096) return error = "--classes: sigma_n classes must be 1..4096", false;
  if (o.classes_c < 0 || o.classes_c > 64) return error = "--classes: sigma_c classes must be 1..64", false;
  if (o.format_version < kSpgOldestVersion || o.format_version > kSpgVersion)
    return error = "--format-version: expected " + std::to_string(kSpgOldestVersion) + " or " + std::to_string(kSpgVersion), false;
  if (o.tree.leaf_size < 2) return error = "--leaf-size must be at least 2", false;
  if (!(o.tolerance >= 0) || !std::isfinite(o.tolerance)) return error = "--tolerance must be a positive length", false;
  if (!(o.tree.balance >= 0 && o.tree.balance <= 0.5)) return error = "--balance must be in [0, 0.5]", false;
  return true;
}

void PlanSampler::add(const PointCloud& chunk) {
  const size_t n = chunk.positions.size();
  if (count == 0 && n > 0) box.min = box.max = chunk.positions[0];
  for (size_t i = 0; i < n; ++i) {
    const Vec3& p = chunk.positions[i];
    box.min = box.min.cwiseMin(p);
    box.max = box.max.cwiseMax(p);
    const uint64_t hash = mix64(count + i);
    if (hash > threshold) continue;
    positions.push_back(p);
    if (chunk.has_normals()) normals.push_back(chunk.normals[i]);
    hashes.push_back(hash);
  }
  count += n;
  // Over capacity: halve the threshold and keep the points still under it
  // (the sample is then those of the whole scan under the final threshold,
  // however it was read).
  while (positions.size() > kSampleSize) {
    threshold >>= 1;
    size_t kept = 0;
    for (size_t i = 0; i < positions.size(); ++i) {
      if (hashes[i] > threshold) continue;
      positions[kept] = positions[i];
      if (!normals.empty()) normals[kept] = normals[i];
      hashes[kept++] = hashes[i];
    }
    positions.resize(kept);
    if (!normals.empty()) normals.resize(kept);
    hashes.resize(kept);
  }
}

bool make_plan(PointCloud& cloud, const EncodeOptions& o, PartitionPlan& plan, std::string& error,
               ProgressBar* progress) {
  if (!check_encode_options(o, error)) return false;
  if (cloud.size() == 0) return error = "the scan has no points", false;
  if (std::string what = beyond_float_range(cloud.positions); !what.empty()) return error = "the scan's " + what, false;
  const std::string source = !o.normals ? "none" : cloud.has_normals() ? "file" : !cloud.triangles.empty() ? "faces" : "k-NN";
  // Faces give their normals first: they need the whole mesh.
  if (o.normals && !cloud.has_normals() && !cloud.triangles.empty()) {
    const auto normals_progress = [&](double f, const char* phase) {
      if (progress) progress->update(0.3 * f, phase);
    };
    estimate_normals(cloud, o.normal_neighbours, ScanFrame{}, normals_progress, o.tree.threads);
  }
  if (!o.normals) cloud.normals.clear();
  PlanSampler sampler;
  sampler.add(cloud);
  ScanFacts facts;
  facts.normals = cloud.has_normals();
  facts.colors = cloud.has_colors();
  facts.normals_source = source;
  facts.has_viewpoint = cloud.has_viewpoint;
  facts.viewpoint = cloud.viewpoint;
  return finish_plan(sampler, facts, o, plan, error);
}

bool finish_plan(PlanSampler& sampler, const ScanFacts& facts, const EncodeOptions& o, PartitionPlan& plan,
                 std::string& error) {
  const uint64_t n = sampler.count;
  if (n == 0) return error = "the scan has no points", false;
  if (n > 0xFFFFFFFFu)
    return error = "the scan has " + std::to_string(n) + " points; a .spg counts them in 32 bits (at most 4,294,967,295)", false;
  plan = PartitionPlan{};
  plan.points = n;
  plan.version = o.format_version;
  plan.normals = o.normals;
  plan.curvature_sign = o.normals && o.curvature_sign && o.format_version >= 2;
  plan.colors = o.colors && facts.colors;
  plan.estimate = o.normals && !facts.normals;
  plan.count_duplicates = facts.count_duplicates;
  plan.normal_neighbours = o.normal_neighbours;
  plan.classes[0] = o.classes_p;
  plan.classes[1] = o.classes_n;
  plan.classes[2] = o.classes_c;
  plan.class_sample = o.class_sample;
  plan.normals_source = facts.normals_source;
  const uint64_t limit = partition_points_for(o);
  const std::vector<Vec3>& positions = sampler.positions;
  const std::vector<Vec3>* normals = facts.normals && o.normals ? &sampler.normals : nullptr;
  OrientOptions orient = o.orient;
  if (facts.has_viewpoint && !orient.has_viewpoint) {  // the file's sensor position, unless an option gives one
    orient.has_viewpoint = true;
    orient.viewpoint = facts.viewpoint;
  }
  plan.frame = analyse_scan(positions, orient, normals);

  plan.origin = stored_origin(sampler.box, plan.version);
  stored_bounding_box(sampler.box, plan.origin, plan.bmin, plan.bmax);
  double diag = 0;
  for (int a = 0; a < 3; ++a) diag += (double(plan.bmax[a]) - plan.bmin[a]) * (double(plan.bmax[a]) - plan.bmin[a]);
  diag = std::sqrt(diag);
  plan.tree = o.tree;
  plan.tree.stats.normals = plan.normals;
  plan.tree.stats.colors = plan.colors;
  plan.tree.stats.sigma_floor = 1e-15 * std::max(diag, 1e-30);
  if (o.tolerance > 0) {
    // The variance stop at the tolerance, and a position cell at most half
    // of it along each axis (docs/encoder.md "Tolerance").
    const double tolerance = o.tolerance_relative ? o.tolerance * diag : o.tolerance;
    plan.tree.leaf_sigma = tolerance;
    for (int a = 0; a < 3; ++a) {
      const double extent = double(plan.bmax[a]) - plan.bmin[a];
      int bits = 1;
      while (bits < kMaxFieldBits && extent / std::ldexp(1.0, bits) > tolerance / 2) ++bits;
      plan.position_bits[a] = static_cast<uint8_t>(bits);
    }
  }

  // The top tree, breadth-first: a node splits while its share of the
  // sample stands for more than `limit` points.
  plan.top.push_back(TopNode{});
  std::vector<std::vector<uint32_t>> ids(1);
  if (n > limit) {
    if (o.tree.octree) return error = "--octree builds in one partition: give it --memory for the whole scan", false;
    ids[0].resize(positions.size());
    for (size_t i = 0; i < ids[0].size(); ++i) ids[0][i] = static_cast<uint32_t>(i);
  }
  const double scale = static_cast<double>(n) / static_cast<double>(std::max<size_t>(positions.size(), 1));
  uint32_t parts = 0;
  for (size_t t = 0; t < plan.top.size(); ++t) {
    std::vector<uint32_t> mine = std::move(ids[t]);
    size_t left = 0;
    Vec3 normal;
    double offset = 0;
    if (static_cast<double>(mine.size()) * scale > static_cast<double>(limit) && plan.top[t].depth < 60 &&
        split_plane(positions, mine, normal, offset, left)) {
      plan.top[t].normal = normal;
      plan.top[t].offset = offset;
      plan.top[t].first_child = static_cast<uint32_t>(plan.top.size());
      for (int c = 0; c < 2; ++c) {
        TopNode child;
        child.parent = static_cast<uint32_t>(t);
        child.depth = static_cast<uint16_t>(plan.top[t].depth + 1);
        plan.top.push_back(child);
        ids.emplace_back(c == 0 ? std::vector<uint32_t>(mine.begin(), mine.begin() + static_cast<std::ptrdiff_t>(left))
                                : std::vector<uint32_t>(mine.begin() + static_cast<std::ptrdiff_t>(left), mine.end()));
      }
    } else {
      plan.top[t].part = parts++;
    }
  }
  if (parts > kMaxPartitions)
    return error = "--memory: " + std::to_string(parts) + " partitions of at most " + std::to_string(limit) +
                   " points; give more memory (at most " + std::to_string(kMaxPartitions) + " partitions)", false;
  plan.part_points.assign(parts, 0);
  plan.part_halo.assign(parts, 0);
  if (parts == 1) plan.part_points[0] = n;
  if (parts > 1 && plan.estimate) {
    plan.halo = halo_distance(positions, n, o.normal_neighbours);
    // Outward normals: every job seeds its components facing away from the
    // whole scan's centre, not its own.
    plan.frame.has_centre = true;
    for (const Vec3& p : positions) plan.frame.centre += p;
    plan.frame.centre /= static_cast<double>(positions.size());
  }
  return true;
}

bool write_plan(const PartitionPlan& p, const std::string& dir, std::string& error) {
  Out out;
  out.bytes.assign(kPlanMagic, kPlanMagic + 8);
  out.put(p.points);
  out.put(static_cast<int32_t>(p.version));
  out.put(static_cast<uint8_t>(p.normals | p.colors << 1 | p.estimate << 2 | p.count_duplicates << 3 |
                               p.curvature_sign << 4));
  out.put(static_cast<int32_t>(p.normal_neighbours));
  out.str(p.normals_source);
  for (int c = 0; c < 3; ++c) out.put(static_cast<int32_t>(p.classes[c]));
  out.put(p.class_sample);
  const ScanFrame& f = p.frame;
  out.put(static_cast<uint8_t>(f.kind));
  out.put(static_cast<uint8_t>(f.orient));
  out.vec(f.viewpoint);
  out.vec(f.up);
  out.put(f.hint.encode());
  out.put(f.visible_share);
  out.put(f.spacing_slope);
  out.put(static_cast<uint8_t>(f.has_centre));
  out.vec(f.centre);
  out.str(f.reason);
  const TreeOptions& t = p.tree;
  out.put(t.leaf_size);
  out.put(t.leaf_sigma);
  for (uint8_t b : p.position_bits) out.put(b);
  out.put(t.balance);
  out.put(static_cast<uint8_t>(t.octree));
  out.put(static_cast<int32_t>(t.max_iterations));
  out.put(t.tolerance);
  out.put(t.init_step);
  out.put(static_cast<int32_t>(t.max_depth));
  out.put(t.wide_node);
  const StatsOptions& s = t.stats;
  out.put(s.sigma_floor);
  out.put(s.spread_floor);
  out.put(s.vanish_ratio);
  out.put(static_cast<uint8_t>(s.normals | s.colors << 1));
  out.put(s.shrink_eta0);
  out.put(s.shrink_eta1);
  out.vec(p.origin);
  for (int a = 0; a < 3; ++a) out.put(p.bmin[a]);
  for (int a = 0; a < 3; ++a) out.put(p.bmax[a]);
  out.put(p.halo);
  out.put(static_cast<uint32_t>(p.top.size()));
  for (const TopNode& n : p.top) {
    out.put(n.parent);
    out.put(n.first_child);
    out.put(n.part);
    out.put(n.depth);
    out.vec(n.normal);
    out.put(n.offset);
  }
  out.put(p.partitions());
  for (uint32_t i = 0; i < p.partitions(); ++i) {
    out.put(p.part_points[i]);
    out.put(p.part_halo[i]);
  }
  out.put(crc32(out.bytes.data(), out.bytes.size()));
  if (!write_file_atomic((std::filesystem::path(dir) / "plan.bin").string(), out.bytes, error)) return false;
  std::string jobs = "# stipple encode plan: one job a line, \"<id> <points> <halo points>\"; run each with\n"
                     "#   stipple encode-part " + dir + " <id>\n";
  for (uint32_t i = 0; i < p.partitions(); ++i)
    jobs += std::to_string(i) + " " + std::to_string(p.part_points[i]) + " " + std::to_string(p.part_halo[i]) + "\n";
  return write_file_atomic((std::filesystem::path(dir) / "jobs.txt").string(), std::vector<uint8_t>(jobs.begin(), jobs.end()), error);
}

bool read_plan(const std::string& dir, PartitionPlan& p, std::string& error) {
  const std::string path = (std::filesystem::path(dir) / "plan.bin").string();
  std::vector<uint8_t> bytes;
  if (!read_file(path, bytes, error, uint64_t{1} << 30)) return false;
  if (bytes.size() >= 8 && std::memcmp(bytes.data(), "SPGPLAN1", 8) == 0)
    return error = path + ": a plan of an older stipple (SPGPLAN1; this one reads SPGPLAN2): plan the scan again", false;
  if (bytes.size() < 12 || std::memcmp(bytes.data(), kPlanMagic, 8) != 0)
    return error = path + ": not a stipple encode plan (no SPGPLAN2 at byte 0)", false;
  if (load_u32le(bytes.data() + bytes.size() - 4) != crc32(bytes.data(), bytes.size() - 4))
    return error = path + ": CRC-32 mismatch: the plan is corrupt or was cut short", false;
  In in(bytes.data() + 8, bytes.size() - 12);
  p = PartitionPlan{};
  p.points = in.get<uint64_t>();
  p.version = in.get<int32_t>();
  const uint8_t flags = in.get<uint8_t>();
  p.normals = flags & 1;
  p.colors = flags & 2;
  p.estimate = flags & 4;
  p.count_duplicates = flags & 8;
  p.curvature_sign = flags & 16;
  p.normal_neighbours = in.get<int32_t>();
  p.normals_source = in.str();
  for (int c = 0; c < 3; ++c) p.classes[c] = in.get<int32_t>();
  p.class_sample = in.get<uint64_t>();
  ScanFrame& f = p.frame;
  f.kind = static_cast<ScanKind>(in.get<uint8_t>());
  f.orient = static_cast<OrientMode>(in.get<uint8_t>());
  f.viewpoint = in.vec();
  f.up = in.vec();
  const uint16_t hint = in.get<uint16_t>();
  f.hint.up = static_cast<SpgAxis>(hint & 7);
  f.hint.sensor_side = static_cast<SpgAxis>((hint >> 3) & 7);
  f.hint.sensor_at_origin = (hint >> 6) & 1;
  f.visible_share = in.get<double>();
  f.spacing_slope = in.get<double>();
  f.has_centre = in.get<uint8_t>();
  f.centre = in.vec();
  f.reason = in.str();
  TreeOptions& t = p.tree;
  t.leaf_size = in.get<uint32_t>();
  t.leaf_sigma = in.get<double>();
  for (uint8_t& b : p.position_bits) b = in.get<uint8_t>();
  t.balance = in.get<double>();
  t.octree = in.get<uint8_t>();
  t.max_iterations = in.get<int32_t>();
  t.tolerance = in.get<double>();
  t.init_step = in.get<double>();
  t.max_depth = in.get<int32_t>();
  t.wide_node = in.get<uint32_t>();
  StatsOptions& s = t.stats;
  s.sigma_floor = in.get<double>();
  s.spread_floor = in.get<double>();
  s.vanish_ratio = in.get<double>();
  const uint8_t sflags = in.get<uint8_t>();
  s.normals = sflags & 1;
  s.colors = sflags & 2;
  s.shrink_eta0 = in.get<double>();
  s.shrink_eta1 = in.get<double>();
  p.origin = in.vec();
  for (int a = 0; a < 3; ++a) p.bmin[a] = in.get<float>();
  for (int a = 0; a < 3; ++a) p.bmax[a] = in.get<float>();
  p.halo = in.get<double>();
  const uint32_t top = in.get<uint32_t>();
  if (!in.ok() || top == 0 || top > in.left() / 50) return error = path + ": the top tree's node count is wrong", false;
  p.top.resize(top);
  for (TopNode& n : p.top) {
    n.parent = in.get<uint32_t>();
    n.first_child = in.get<uint32_t>();
    n.part = in.get<uint32_t>();
    n.depth = in.get<uint16_t>();
    n.normal = in.vec();
    n.offset = in.get<double>();
  }
  const uint32_t parts = in.get<uint32_t>();
  if (!in.ok() || parts == 0 || parts > kMaxPartitions || in.left() != size_t{parts} * 16)
    return error = path + ": the partition count is wrong", false;
  p.part_points.resize(parts);
  p.part_halo.resize(parts);
  for (uint32_t i = 0; i < parts; ++i) {
    p.part_points[i] = in.get<uint64_t>();
    p.part_halo[i] = in.get<uint64_t>();
  }
  // The top tree must be a tree whose leaves number the partitions.
  uint32_t leaves = 0;
  for (size_t i = 0; i < top; ++i) {
    const TopNode& n = p.top[i];
    if (n.leaf() ? n.part != leaves++ : (n.first_child <= i || n.first_child + 1 >= top))
      return error = path + ": top node " + std::to_string(i) + " is malformed", false;
  }
  if (leaves != parts || !in.ok()) return error = path + ": the top tree does not match its partitions", false;
  return true;
}

// Appends points to a partition's file through a buffer, opening the file
// only to flush (thousands of partitions would pass the open-file limit).
struct PartitionRouter::Writer {
  std::string path;
  std::vector<uint8_t> buffer;
  uint64_t count = 0;
  bool created = false;
  void add(const PointCloud& cloud, size_t i, bool normals, bool colors) {
    const auto put = [&](const Vec3& v) {
      const auto* b = reinterpret_cast<const uint8_t*>(v.data());
      buffer.insert(buffer.end(), b, b + 24);
    };
    put(cloud.positions[i]);
    if (normals) put(cloud.normals[i]);
    if (colors) put(cloud.colors[i]);
    ++count;
  }
  bool full() const { return buffer.size() >= (size_t{1} << 16); }
  bool flush(std::string& error) {
    if (buffer.empty() && created) return true;
    std::FILE* f = std::fopen(path.c_str(), created ? "ab" : "wb");
    if (!f) return error = path + ": " + errno_text(), false;
    created = true;
    const bool wrote = buffer.empty() || std::fwrite(buffer.data(), 1, buffer.size(), f) == buffer.size();
    const int why = wrote ? 0 : errno;
    const bool closed = std::fclose(f) == 0;
    if (!wrote || !closed)
      return error = path + ": write failed: " + std::strerror(why ? why : errno ? errno : EIO), false;
    buffer.clear();
    return true;
  }
};

PartitionRouter::PartitionRouter(PartitionPlan& plan, const std::string& dir) : plan_(plan) {
  for (uint32_t i = 0; i < plan.partitions(); ++i) {
    own_.push_back(Writer{part_path(dir, i, "pts"), {}, 0, false});
    halo_.push_back(Writer{part_path(dir, i, "halo"), {}, 0, false});
  }
}

PartitionRouter::~PartitionRouter() = default;

bool PartitionRouter::add(const PointCloud& cloud, std::string& error, size_t begin, size_t end) {
  const bool normals = plan_.normals && !plan_.estimate, colors = plan_.colors;
  if ((normals && cloud.normals.size() != cloud.size()) || (colors && cloud.colors.size() != cloud.size()))
    return error = "the scan's chunk lacks the normals or colours its plan has", false;
  for (size_t i = begin; i < std::min(end, cloud.size()); ++i) {
    const Vec3& p = cloud.positions[i];
    const uint32_t home = plan_.route(p);
    own_[home].add(cloud, i, normals, colors);
    if (own_[home].full() && !own_[home].flush(error)) return false;
    if (plan_.halo > 0) {
      // Every partition within `halo` of the point across some plane.
      stack_.assign(1, 0);
      while (!stack_.empty()) {
        const TopNode& t = plan_.top[stack_.back()];
        stack_.pop_back();
        if (t.leaf()) {
          if (t.part != home) {
            halo_[t.part].add(cloud, i, normals, colors);
            if (halo_[t.part].full() && !halo_[t.part].flush(error)) return false;
          }
          continue;
        }
        const double s = t.normal.dot(p) - t.offset;
        if (s > -plan_.halo) stack_.push_back(t.first_child + 1);
        if (s <= plan_.halo) stack_.push_back(t.first_child);
      }
    }
  }
  return true;
}

bool PartitionRouter::finish(std::string& error) {
  for (uint32_t i = 0; i < plan_.partitions(); ++i) {
    if (!own_[i].flush(error) || (halo_[i].count > 0 && !halo_[i].flush(error))) return false;
    plan_.part_points[i] = own_[i].count;
    plan_.part_halo[i] = halo_[i].count;
  }
  return true;
}

bool route_points(const PointCloud& cloud, PartitionPlan& plan, const std::string& dir, std::string& error,
                  ProgressBar* progress) {
  PartitionRouter router(plan, dir);
  for (size_t at = 0; at < cloud.size(); at += kScanChunk) {
    const size_t end = std::min(cloud.size(), at + kScanChunk);
    if (!router.add(cloud, error, at, end)) return false;
    if (progress) progress->update(0.3 * static_cast<double>(end) / static_cast<double>(cloud.size()), "routing points to partitions");
  }
  return router.finish(error);
}

namespace {

class MemoryPart final : public PartNodes {
 public:
  MemoryPart(Tree tree, PartSummary summary) : tree_(std::move(tree)), summary_(std::move(summary)) {}
  const PartSummary& summary() const override { return summary_; }
  bool read(uint64_t begin, uint64_t count, uint8_t* child_counts, uint32_t* points, NodeStats* stats,
            std::string&) override {
    for (uint64_t i = 0; i < count; ++i) {
      const TreeNode& node = tree_.nodes[begin + i];
      if (child_counts) child_counts[i] = node.child_count;
      if (points) points[i] = node.count();
      if (stats) stats[i] = node.stats;
    }
    return true;
  }

 private:
  Tree tree_;
  PartSummary summary_;
};

}  // namespace

void estimate_part_normals(PointCloud& cloud, size_t own, const PartitionPlan& plan, int threads,
                           const std::function<void(double)>& progress) {
  if (plan.estimate) {
    // Normals from the partition and its halo; the halo's own are dropped.
    const auto normals_progress = [&](double f, const char*) {
      if (progress) progress(0.3 * f);
    };
    estimate_normals(cloud, plan.normal_neighbours, plan.frame, normals_progress, threads);
  }
  cloud.positions.resize(own);
  if (cloud.has_normals()) cloud.normals.resize(own);
  if (cloud.has_colors()) cloud.colors.resize(own);
  cloud.triangles.clear();
}

std::unique_ptr<PartNodes> run_part(PointCloud& cloud, size_t own, const PartitionPlan& plan, uint32_t part,
                                    int threads, const std::function<void(double)>& progress) {
  uint16_t top_depth = 0;
  for (const TopNode& t : plan.top)
    if (t.leaf() && t.part == part) top_depth = t.depth;
  const double start = monotonic_seconds();
  estimate_part_normals(cloud, own, plan, threads, progress);
  PartSummary s;
  s.normals_seconds = monotonic_seconds() - start;
  s.points = own;
  // Equal positions always share a partition, so the parts' counts add up
  // to the scan's.
  if (plan.count_duplicates) s.duplicates = count_duplicate_positions(cloud.positions);
  s.position = moments_of(cloud.positions.data(), own);
  for (const Vec3& v : cloud.normals) s.normal_sum += v;
  if (plan.colors && cloud.has_colors()) s.color = moments_of(cloud.colors.data(), own);
  TreeOptions options = plan.tree;
  options.threads = threads;
  options.max_depth = std::max(0, plan.tree.max_depth - top_depth);
  const auto tree_progress = [&](double f) {
    if (progress) progress((plan.estimate ? 0.3 : 0.0) + (plan.estimate ? 0.7 : 1.0) * f);
  };
  const double tree_start = monotonic_seconds();
  Tree tree = build_tree_consuming(cloud, options, tree_progress);
  s.tree_seconds = monotonic_seconds() - tree_start;
  tree.order = {};
  s.nodes = tree.nodes.size();
  s.leaves = tree.leaf_count();
  s.depth = tree.depth;
  s.level_begin.assign(static_cast<size_t>(tree.depth) + 2, s.nodes);
  for (size_t i = tree.nodes.size(); i-- > 0;) s.level_begin[tree.nodes[i].depth] = i;
  s.root = tree.nodes[0].stats;
  s.report = tree.report;
  s.ratios = partition_ratio_sums(tree);
  return std::make_unique<MemoryPart>(std::move(tree), std::move(s));
}

namespace {

// The node file: magic, header, the child counts (u8), the point counts
// (u32), the statistics (43 doubles) of every node, then CRC-32.
size_t nodes_header_bytes(size_t levels) { return 8 + 4 + 8 * 3 + 4 + 8 * levels + 8 * (3 + 9 + 3 + 1 + 3 + 9) + 5 * 8 + 2 * 8 + 2 * 8 + 8; }

bool read_points_file(const std::string& path, uint64_t expected, const PartitionPlan& plan, PointCloud& cloud,
                      std::string& error) {
  MappedFile file;
  const size_t stride = partition_point_bytes(plan);
  if (!file.open(path, error)) return false;
  if (file.size() != expected * stride)
    return error = path + ": " + std::to_string(file.size()) + " bytes where the plan has " + std::to_string(expected) +
                   " points of " + std::to_string(stride) + " (" + std::to_string(expected * stride) +
                   " bytes): cut short, or from another plan", false;
  const bool normals = plan.normals && !plan.estimate;
  cloud.positions.reserve(cloud.positions.size() + expected);
  if (normals) cloud.normals.reserve(cloud.normals.size() + expected);
  if (plan.colors) cloud.colors.reserve(cloud.colors.size() + expected);
  const uint8_t* bytes = file.data();
  for (size_t at = 0; at < file.size(); at += stride) {
    Vec3 v;
    std::memcpy(v.data(), bytes + at, 24);
    cloud.positions.push_back(v);
    size_t o = 24;
    if (normals) {
      std::memcpy(v.data(), bytes + at + o, 24);
      cloud.normals.push_back(v);
      o += 24;
    }
    if (plan.colors) {
      std::memcpy(v.data(), bytes + at + o, 24);
      cloud.colors.push_back(v);
    }
    file.release_before(at);
  }
  return true;
}

class FilePart final : public PartNodes {
 public:
  ~FilePart() override {
    if (file_) std::fclose(file_);
  }
  const PartSummary& summary() const override { return summary_; }
  bool read(uint64_t begin, uint64_t count, uint8_t* child_counts, uint32_t* points, NodeStats* stats,
            std::string& error) override {
    const uint64_t n = summary_.nodes;
    const auto section = [&](uint64_t offset, size_t size, void* out) {
      if (fseeko(file_, static_cast<off_t>(offset), SEEK_SET) != 0 || std::fread(out, 1, size, file_) != size)
        return error = path_ + ": read failed at byte " + std::to_string(offset), false;
      return true;
    };
    if (child_counts && !section(header_ + begin, count, child_counts)) return false;
    if (points && !section(header_ + n + 4 * begin, 4 * count, points)) return false;
    if (stats) {
      buffer_.resize(count * kStatsDoubles);
      if (!section(header_ + 5 * n + 8 * kStatsDoubles * begin, 8 * kStatsDoubles * count, buffer_.data())) return false;
      for (uint64_t i = 0; i < count; ++i) get_stats(buffer_.data() + i * kStatsDoubles, stats[i]);
      if (points)
        for (uint64_t i = 0; i < count; ++i) stats[i].count = points[i];
    }
    return true;
  }

  std::string path_;
  std::FILE* file_ = nullptr;
  uint64_t header_ = 0;
  PartSummary summary_;
  std::vector<double> buffer_;
};

}  // namespace

bool load_part_points(const std::string& dir, const PartitionPlan& plan, uint32_t part, PointCloud& cloud, size_t& own,
                      std::string& error) {
  if (part >= plan.partitions())
    return error = "partition " + std::to_string(part) + " is not in the plan (it has " + std::to_string(plan.partitions()) + ")", false;
  cloud = PointCloud{};
  own = plan.part_points[part];
  if (!read_points_file(part_path(dir, part, "pts"), plan.part_points[part], plan, cloud, error)) return false;
  return plan.part_halo[part] == 0 || read_points_file(part_path(dir, part, "halo"), plan.part_halo[part], plan, cloud, error);
}

bool run_part_file(const std::string& dir, const PartitionPlan& plan, uint32_t part, int threads, std::string& error,
                   uint32_t* crc_out) {
  PointCloud cloud;
  size_t own = 0;
  if (!load_part_points(dir, plan, part, cloud, own, error)) return false;
  const std::unique_ptr<PartNodes> nodes = run_part(cloud, own, plan, part, threads);
  const PartSummary& s = nodes->summary();

  Out out;
  out.bytes.assign(kNodesMagic, kNodesMagic + 8);
  out.put(part);
  out.put(s.nodes);
  out.put(s.leaves);
  out.put(s.points);
  out.put(static_cast<int32_t>(s.depth));
  for (const uint64_t b : s.level_begin) out.put(b);
  out.vec(s.position.mean);
  out.mat(s.position.m2);
  out.vec(s.normal_sum);
  out.put(s.color.count);
  out.vec(s.color.mean);
  out.mat(s.color.m2);
  for (const uint64_t v : {s.report.splits, s.report.euclidean_fallbacks, s.report.unbalanced, s.report.failed_splits,
                           s.report.two_means_iterations})
    out.put(v);
  out.put(s.ratios.apr_sum);
  out.put(s.ratios.capr_sum);
  out.put(s.ratios.families);
  out.put(s.ratios.capr_families);
  out.put(s.duplicates);
  const std::string path = part_path(dir, part, "nodes");
  AtomicFileWriter file;
  if (!file.open(path, error)) return false;
  uint32_t crc = crc32(out.bytes.data(), out.bytes.size());
  file.write(out.bytes.data(), out.bytes.size());
  constexpr uint64_t kBlock = 1 << 15;
  std::vector<uint8_t> counts(kBlock);
  std::vector<uint32_t> points(kBlock);
  std::vector<NodeStats> stats(kBlock);
  for (int section = 0; section < 3; ++section)
    for (uint64_t begin = 0; begin < s.nodes; begin += kBlock) {
      const uint64_t count = std::min(kBlock, s.nodes - begin);
      nodes->read(begin, count, counts.data(), points.data(), stats.data(), error);
      out.bytes.clear();
      if (section == 0) out.bytes.assign(counts.begin(), counts.begin() + static_cast<std::ptrdiff_t>(count));
      for (uint64_t i = 0; section == 1 && i < count; ++i) out.put(points[i]);
      for (uint64_t i = 0; section == 2 && i < count; ++i) put_stats(out, stats[i]);
      crc = crc32_extend(crc, out.bytes.data(), out.bytes.size());
      file.write(out.bytes.data(), out.bytes.size());
    }
  file.write(&crc, 4);
  if (crc_out) *crc_out = crc;
  return file.commit(error);
}

std::unique_ptr<PartNodes> open_part_file(const std::string& dir, const PartitionPlan& plan, uint32_t part,
                                          std::string& error) {
  auto f = std::make_unique<FilePart>();
  f->path_ = part_path(dir, part, "nodes");
  f->file_ = std::fopen(f->path_.c_str(), "rb");
  if (!f->file_) return error = f->path_ + ": " + errno_text() + " (has its job run? stipple encode-part " + dir + " " + std::to_string(part) + ")", nullptr;
  // The whole file's CRC first: a part cut short or changed is refused
  // before any of it is used.
  uint64_t size = 0;
  if (fseeko(f->file_, 0, SEEK_END) == 0) size = static_cast<uint64_t>(ftello(f->file_));
  std::fseek(f->file_, 0, SEEK_SET);
  uint32_t crc = 0;
  std::vector<uint8_t> head, buffer(1 << 20);
  uint8_t tail[4] = {0, 0, 0, 0};
  for (uint64_t at = 0; size >= 4 && at < size - 4;) {
    const size_t want = static_cast<size_t>(std::min<uint64_t>(buffer.size(), size - 4 - at));
    if (std::fread(buffer.data(), 1, want, f->file_) != want) break;
    crc = crc32_extend(crc, buffer.data(), want);
    if (head.size() < (1 << 16)) head.insert(head.end(), buffer.data(), buffer.data() + std::min<size_t>(want, (1 << 16) - head.size()));
    at += want;
  }
  if (size >= 4 && std::fread(tail, 1, 4, f->file_) != 4) size = 0;
  const auto bad = [&](const std::string& what) {
    error = f->path_ + ": " + what;
    return nullptr;
  };
  if (size < 64 || std::memcmp(head.data(), kNodesMagic, 8) != 0) return bad("not a stipple part of this version (no SPGNODE2 at byte 0)");
  if (load_u32le(tail) != crc) return bad("CRC-32 mismatch: the part is corrupt or was cut short; run its job again");
  In in(head.data() + 8, head.size() - 8);
  PartSummary& s = f->summary_;
  if (in.get<uint32_t>() != part) return bad("is another partition's result");
  s.nodes = in.get<uint64_t>();
  s.leaves = in.get<uint64_t>();
  s.points = in.get<uint64_t>();
  s.depth = in.get<int32_t>();
  if (!in.ok() || s.depth < 0 || s.depth > 1 << 16 || s.points != plan.part_points[part] || s.nodes == 0)
    return bad("its header does not match the plan (" + std::to_string(plan.part_points[part]) + " points)");
  s.level_begin.resize(static_cast<size_t>(s.depth) + 2);
  for (uint64_t& b : s.level_begin) b = in.get<uint64_t>();
  s.position.count = static_cast<double>(s.points);
  s.position.mean = in.vec();
  s.position.m2 = in.mat();
  s.normal_sum = in.vec();
  s.color.count = in.get<double>();
  s.color.mean = in.vec();
  s.color.m2 = in.mat();
  for (uint64_t* v : {&s.report.splits, &s.report.euclidean_fallbacks, &s.report.unbalanced, &s.report.failed_splits,
                      &s.report.two_means_iterations})
    *v = in.get<uint64_t>();
  s.ratios.apr_sum = in.get<double>();
  s.ratios.capr_sum = in.get<double>();
  s.ratios.families = in.get<uint64_t>();
  s.ratios.capr_families = in.get<uint64_t>();
  s.duplicates = in.get<uint64_t>();
  f->header_ = nodes_header_bytes(s.level_begin.size());
  if (!in.ok() || size != f->header_ + s.nodes * (1 + 4 + 8 * kStatsDoubles) + 4)
    return bad("its size does not match its node count (" + std::to_string(s.nodes) + ")");
  uint32_t count = 0;
  if (!f->read(0, 1, nullptr, &count, &s.root, error)) return nullptr;
  return f;
}

}  // namespace stipple
