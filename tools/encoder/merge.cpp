// stipple host — merging partitions into a .spg. See merge.h.
#include "tools/encoder/merge.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "core/spg_format.h"
#include "core/spg_writer.h"
#include "platform/file_io.h"
#include "tools/encoder/classify.h"
#include "tools/encoder/parallel.h"
#include "tools/encoder/quantize.h"

namespace stipple {
namespace {

// Nodes read and packed at a time.
constexpr uint64_t kBlock = uint64_t{1} << 16;

uint32_t f32_bits(float f) {
  uint32_t bits;
  std::memcpy(&bits, &f, 4);
  return bits;
}

// A run of breadth-first nodes: one top node, or one level of a partition.
struct Segment {
  bool top = false;
  uint32_t id = 0;     // top node or partition
  uint32_t level = 0;  // the partition's local level
  uint64_t count = 1;
};

std::vector<Segment> breadth_first_segments(const PartitionPlan& plan, const std::vector<std::unique_ptr<PartNodes>>& parts,
                                            int& depth) {
  const auto of_top = [&](uint32_t t) {
    if (!plan.top[t].leaf()) return Segment{true, t, 0, 1};
    const PartSummary& s = parts[plan.top[t].part]->summary();
    return Segment{false, plan.top[t].part, 0, s.level_begin[1] - s.level_begin[0]};
  };
  std::vector<Segment> out, level{of_top(0)}, next;
  depth = -1;
  while (!level.empty()) {
    ++depth;
    out.insert(out.end(), level.begin(), level.end());
    next.clear();
    for (const Segment& seg : level) {
      if (seg.top) {
        next.push_back(of_top(plan.top[seg.id].first_child));
        next.push_back(of_top(plan.top[seg.id].first_child + 1));
        continue;
      }
      const PartSummary& s = parts[seg.id]->summary();
      const uint32_t d = seg.level + 1;
      if (d <= static_cast<uint32_t>(s.depth)) next.push_back(Segment{false, seg.id, d, s.level_begin[d + 1] - s.level_begin[d]});
    }
    level.swap(next);
  }
  return out;
}

// The file through the sink, with its CRC-32 and size counted on the way.
class Output {
 public:
  Output(const ByteSink& sink, std::string& error) : sink_(sink), error_(error) {}
  bool put(const uint8_t* data, size_t size) {
    if (!ok_ || size == 0) return ok_;
    crc_ = crc32_extend(crc_, data, size);
    bytes_ += size;
    ok_ = sink_(data, size, error_);
    return ok_;
  }
  bool put(const std::vector<uint8_t>& v) { return put(v.data(), v.size()); }
  uint32_t crc() const { return crc_; }
  uint64_t bytes() const { return bytes_; }
  bool ok() const { return ok_; }

 private:
  const ByteSink& sink_;
  std::string& error_;
  uint32_t crc_ = 0;
  uint64_t bytes_ = 0;
  bool ok_ = true;
};

}  // namespace

ByteSink sink_into(AtomicFileWriter& file) {
  return [&file](const uint8_t* data, size_t size, std::string& error) {
    if (file.write(data, size)) return true;
    error = file.failure();
    return false;
  };
}

NormalSpread combine_normal_spreads(const NodeStats* children, const double* counts, size_t n, const Vec3& normal_sum,
                                    const Vec3& fallback_z) {
  double total = 0;
  Vec3 mean = Vec3::Zero();
  for (size_t i = 0; i < n; ++i) {
    total += counts[i];
    mean += counts[i] * children[i].position.mean;
  }
  if (total > 0) mean /= total;
  const LogMapFrame f = log_map_frame(normal_sum, static_cast<size_t>(total), fallback_z);
  Eigen::Matrix<double, 2, 3> tangent;
  tangent.row(0) = f.t1.transpose();
  tangent.row(1) = f.t2.transpose();
  LogMapSums sums;
  double bound = 0;
  for (size_t i = 0; i < n; ++i) {
    const NodeStats& c = children[i];
    const Vec3 m = c.normal_frame.col(2);
    // a a^T and a (mean_c - mean)^T, a the child's mean in the parent's log map.
    LogMapSums offset;
    accumulate_log_map(f, &m, 1, offset, &c.position.mean, mean);
    const Vec3 x0 = c.normal_frame.col(0), x1 = c.normal_frame.col(1);
    const Mat3 own = c.sigma_n[0] * c.sigma_n[0] * x0 * x0.transpose() + c.sigma_n[1] * c.sigma_n[1] * x1 * x1.transpose();
    const Mat3 own_turn = c.turn[0] * x0 * x0.transpose() + c.turn[1] * x1 * x1.transpose();
    sums.cov += counts[i] * (tangent * own * tangent.transpose() + offset.cov);
    sums.turn += counts[i] * (tangent * own_turn + offset.turn);
    const double a = std::sqrt(offset.cov.trace()), s = c.sigma_n.norm();
    bound += counts[i] * (a + s) * (a + s);
  }
  if (total > 0) {
    sums.cov /= total;
    sums.turn /= total;
    bound /= total;
  }
  if (sums.cov.trace() > 0) sums.cov *= bound / sums.cov.trace();
  sums.used = 1;
  return finish_log_map(f, sums);
}

bool merge_parts(const PartitionPlan& plan, std::vector<std::unique_ptr<PartNodes>>& parts, int threads,
                 const ByteSink& sink, EncodeReport& report, std::string& error, ProgressBar* progress) {
  const StatsOptions& so = plan.tree.stats;
  const bool normals = plan.normals, colors = plan.colors;
  // sigma_n as its classes take it: with the curvature's sign, or the spread.
  const auto sigma_n_tuple = [&plan](const NodeStats& s) {
    const Vec2 v = plan.curvature_sign ? signed_sigma_n(s) : s.sigma_n;
    return Vec3(v[0], v[1], 0);
  };
  double stage_start = monotonic_seconds();

  // The top nodes, from the partitions up.
  struct TopMoments {
    Moments position;
    Vec3 normal_sum = Vec3::Zero();
    Moments color;
  };
  const size_t top_count = plan.top.size();
  std::vector<TopMoments> moments(top_count);
  std::vector<NodeStats> top_stats(top_count);
  PartitionRatioAccumulator ratios;
  for (size_t t = top_count; t-- > 0;) {
    const TopNode& node = plan.top[t];
    TopMoments& m = moments[t];
    if (node.leaf()) {
      const PartSummary& s = parts[node.part]->summary();
      m = TopMoments{s.position, s.normal_sum, s.color};
      top_stats[t] = s.root;
      continue;
    }
    const uint32_t c = node.first_child;
    for (uint32_t k = c; k < c + 2; ++k) {
      m.position.add(moments[k].position);
      m.normal_sum += moments[k].normal_sum;
      m.color.add(moments[k].color);
    }
    const Gaussian3 g = gaussian_from_covariance(m.position.mean, m.position.m2 / m.position.count);
    NormalSpread spread;
    const double counts[2] = {moments[c].position.count, moments[c + 1].position.count};
    if (normals) spread = combine_normal_spreads(&top_stats[c], counts, 2, m.normal_sum, g.frame.col(2));
    top_stats[t] = finish_stats(static_cast<size_t>(m.position.count), g, normals ? &spread : nullptr, so);
    set_color_stats(top_stats[t], m.color, so);
    const double sigma1[2] = {top_stats[c].position.sigma[0], top_stats[c + 1].position.sigma[0]};
    ratios.add_family(top_stats[t].position.sigma[0], counts, sigma1, 2);
    ++report.tree.splits;
  }
  for (const auto& p : parts) {
    ratios.add(p->summary().ratios);
    report.tree.add(p->summary().report);
    report.duplicates += p->summary().duplicates;
  }
  report.ratios = ratios.result();

  int depth = 0;
  const std::vector<Segment> segments = breadth_first_segments(plan, parts, depth);
  uint64_t nodes = 0, leaves = 0;
  for (const Segment& s : segments) nodes += s.count;
  for (const auto& p : parts) leaves += p->summary().leaves;
  if (nodes > 0xFFFFFFFFu) return error = "the tree has " + std::to_string(nodes) + " nodes; a .spg counts them in 32 bits", false;
  report.points = plan.points;
  report.nodes = nodes;
  report.leaves = leaves;
  report.depth = depth;
  report.colors = colors;
  report.normals_source = plan.normals_source;
  report.frame = plan.frame;

  // Reads a segment's nodes [begin, begin + count) of its run.
  std::vector<uint8_t> child_counts(kBlock);
  std::vector<uint32_t> points(kBlock);
  std::vector<NodeStats> stats(kBlock);
  const auto read = [&](const Segment& seg, uint64_t begin, uint64_t count, bool want_stats) {
    if (seg.top) {
      child_counts[0] = 2;
      points[0] = static_cast<uint32_t>(moments[seg.id].position.count);
      if (want_stats) stats[0] = top_stats[seg.id];
      return true;
    }
    const uint64_t first = parts[seg.id]->summary().level_begin[seg.level] + begin;
    return parts[seg.id]->read(first, count, child_counts.data(), points.data(), want_stats ? stats.data() : nullptr, error);
  };
  // Every node in file order, a block at a time: fn(nodes before, count).
  const auto walk = [&](bool want_stats, const auto& fn) {
    uint64_t at = 0;
    for (const Segment& seg : segments)
      for (uint64_t begin = 0; begin < seg.count; begin += kBlock) {
        const uint64_t count = std::min(kBlock, seg.count - begin);
        if (!read(seg, begin, count, want_stats)) return false;
        if (!fn(at, count)) return false;
        at += count;
      }
    return true;
  };

  // Classes: every node's tuples, or a hashed sample's.
  if (progress) progress->update(0.85, "classifying sigmas");
  std::vector<Vec3> sp, sn, sc;
  const uint64_t class_sample = std::max<uint64_t>(plan.class_sample, 1);
  const uint64_t threshold = nodes <= class_sample ? ~uint64_t{0}
      : static_cast<uint64_t>(std::ldexp(static_cast<double>(class_sample) / static_cast<double>(nodes), 64));
  if (!walk(true, [&](uint64_t at, uint64_t count) {
        for (uint64_t i = 0; i < count; ++i) {
          if (nodes > class_sample && mix64(at + i) >= threshold) continue;
          sp.push_back(stats[i].position.sigma);
          if (normals) sn.push_back(sigma_n_tuple(stats[i]));
          if (colors) sc.push_back(stats[i].color.sigma);
        }
        return true;
      }))
    return false;
  // Automatic counts (docs/encoder.md "Classes"): what the picture needs,
  // measured; more only cost a view's class pieces and the indices' bits.
  const int auto_p = static_cast<int>(std::clamp<uint64_t>(nodes / 16, 64, 2048));
  const int auto_n = static_cast<int>(std::clamp<uint64_t>(nodes / 64, 64, 1024));
  const SigmaClasses cp(sp, 3, plan.classes[0] ? plan.classes[0] : auto_p, 20, threads);
  const SignedSigmaClasses cn(sn, 2, plan.classes[1] ? plan.classes[1] : auto_n, 20, threads);
  const SigmaClasses cc(sc, 3, plan.classes[2] ? plan.classes[2] : 64, 20, threads);
  sp = {}, sn = {}, sc = {};
  report.classes[0] = static_cast<int>(cp.centers().size());
  report.classes[1] = static_cast<int>(cn.centers().size());
  report.classes[2] = static_cast<int>(cc.centers().size());
  const double now = monotonic_seconds();
  report.seconds.classes = now - stage_start;
  stage_start = now;

  // The header and class tables (docs/format.md §1-§2).
  const float* bmin = plan.bmin;
  const float* bmax = plan.bmax;
  int thin = 0;  // the thinnest axis gets 10 position bits
  for (int a = 1; a < 3; ++a)
    if (double(bmax[a]) - bmin[a] < double(bmax[thin]) - bmin[thin]) thin = a;
  RecordLayout layout = paper_layout(normals, colors, thin);
  for (int a = 0; a < 3; ++a)  // a tolerance's widths
    if (plan.position_bits[a] != 0) layout.bits[a] = plan.position_bits[a];
  SpgHeader header;
  header.version = static_cast<uint16_t>(plan.version);
  header.flags = static_cast<uint16_t>((normals ? kAttrNormals : 0) | (colors ? kAttrColor : 0) |
                                       (normals && plan.curvature_sign ? kAttrCurvatureSign : 0));
  header.tree_arity = plan.tree.octree ? 8 : 2;
  header.layout = layout;
  header.node_count = static_cast<uint32_t>(nodes);
  header.leaf_count = static_cast<uint32_t>(leaves);
  header.point_count = static_cast<uint32_t>(plan.points);
  header.depth = static_cast<uint16_t>(depth);
  header.view_hint = plan.frame.hint;
  for (int a = 0; a < 3; ++a) {
    header.bbox_bits[a] = f32_bits(bmin[a]);
    header.bbox_bits[3 + a] = f32_bits(bmax[a]);
    std::memcpy(&header.origin_bits[a], &plan.origin[a], 8);
  }
  for (int c = 0; c < 3; ++c) header.class_count[c] = static_cast<uint16_t>(report.classes[c]);
  // Float32 (version 1) or 16-bit codes, sigma_p relative to the stored
  // box's largest side (docs/format.md §2).
  const bool float_tables = header.version == 1;
  double largest = 0;
  for (int a = 0; a < 3; ++a) largest = std::max(largest, double(bmax[a]) - double(bmin[a]));
  if (!(largest > 0)) largest = 1;  // one point: as the client's decoder takes it
  std::vector<uint32_t> sigma_p, sigma_n, sigma_c;
  for (const Vec3& c : cp.centers())
    for (int d = 0; d < 3; ++d) sigma_p.push_back(float_tables ? f32_bits(static_cast<float>(c[d])) : sigma_p_code(c[d], largest));
  for (const Vec3& c : cn.centers())
    for (int d = 0; d < 2; ++d)
      sigma_n.push_back(float_tables ? f32_bits(static_cast<float>(c[d])) : plan.curvature_sign ? q12_signed_code(c[d]) : q12_code(c[d]));
  for (const Vec3& c : cc.centers())
    for (int d = 0; d < 3; ++d) sigma_c.push_back(float_tables ? f32_bits(static_cast<float>(c[d])) : q12_code(c[d]));
  std::vector<uint8_t> bytes(spg_startup_bytes(header.version, header.class_count));
  size_t written = 0;
  const SpgWriteStatus status = spg_write_startup(header, SpgClassTables{sigma_p.data(), sigma_n.data(), sigma_c.data()},
                                                  bytes.data(), bytes.size(), &written);
  if (status != SpgWriteStatus::kOk) return error = std::string("encoder: ") + spg_write_status_text(status), false;
  Output out(sink, error);
  out.put(bytes);

  // §3 topology, LSB first; §4 the leaves' point counts, LEB128.
  if (progress) progress->update(0.95, "writing");
  const bool octree = header.tree_arity == 8;
  uint8_t byte = 0;
  uint64_t leaf_seen = 0, points_seen = 0;
  bytes.clear();
  if (!walk(false, [&](uint64_t at, uint64_t count) {
        for (uint64_t i = 0; i < count; ++i) {
          const uint64_t id = at + i;
          const uint32_t k = child_counts[i];
          if (octree) byte = static_cast<uint8_t>(byte | (k << ((id & 1) * 4)));
          else if (k) byte = static_cast<uint8_t>(byte | (1u << (id & 7)));
          if ((octree ? (id & 1) == 1 : (id & 7) == 7) || id + 1 == nodes) {
            bytes.push_back(byte);
            byte = 0;
          }
        }
        if (bytes.size() >= kBlock && !out.put(bytes)) return false;
        if (bytes.size() >= kBlock) bytes.clear();
        return true;
      }))
    return false;
  out.put(bytes);
  bytes.clear();
  if (!walk(false, [&](uint64_t, uint64_t count) {
        for (uint64_t i = 0; i < count; ++i) {
          if (child_counts[i]) continue;
          ++leaf_seen;
          points_seen += points[i];
          uint8_t leb[5];
          bytes.insert(bytes.end(), leb, leb + store_leb128(leb, points[i]));
        }
        if (bytes.size() >= kBlock && !out.put(bytes)) return false;
        if (bytes.size() >= kBlock) bytes.clear();
        return true;
      }))
    return false;
  out.put(bytes);
  if (leaf_seen != leaves || points_seen != plan.points)
    return error = "the parts' leaves hold " + std::to_string(points_seen) + " points where the plan has " +
                   std::to_string(plan.points) + ": a part is from another plan", false;

  // §5 records, each node's class assigned on the way; §6 CRC-32.
  const AngleBits fp_bits = frame_bits(layout, Field::kFpTheta, false);
  const AngleBits fn_bits = frame_bits(layout, Field::kFnTheta, false);
  const AngleBits fc_bits = frame_bits(layout, Field::kFcTheta, true);
  const size_t record_bytes = static_cast<size_t>(layout.record_bytes());
  const Vec3 origin = plan.origin;
  std::vector<double> err2(3 * kBlock);
  double err_sum[3] = {0, 0, 0};
  if (!walk(true, [&](uint64_t, uint64_t count) {
        bytes.assign(count * record_bytes, 0);
        std::fill(err2.begin(), err2.begin() + static_cast<std::ptrdiff_t>(3 * count), 0.0);
        parallel_for(count, threads, 1024, [&](size_t i) {
          const NodeStats& s = stats[i];
          NodeFields f;
          for (int a = 0; a < 3; ++a) f.v[a] = quantize_cell(s.position.mean[a] - origin[a], bmin[a], bmax[a], layout.bits[a]);
          const FrameCode fp = encode_frame(s.position.frame, fp_bits);
          f[Field::kFpTheta] = fp.theta;
          f[Field::kFpPhi] = fp.phi;
          f[Field::kFpPsi] = fp.psi;
          f[Field::kSigmaP] = cp.assign(s.position.sigma, &err2[3 * i]);
          if (normals) {
            const FrameCode fn = encode_frame(s.normal_frame, fn_bits);
            f[Field::kFnTheta] = fn.theta;
            f[Field::kFnPhi] = fn.phi;
            f[Field::kFnPsi] = fn.psi;
            f[Field::kSigmaN] = cn.assign(sigma_n_tuple(s), &err2[3 * i + 1]);
          }
          if (colors) {
            f[Field::kColorR] = quantize_unit(s.color.mean[0], layout.width(Field::kColorR));
            f[Field::kColorG] = quantize_unit(s.color.mean[1], layout.width(Field::kColorG));
            f[Field::kColorB] = quantize_unit(s.color.mean[2], layout.width(Field::kColorB));
            const FrameCode fc = encode_frame(s.color.frame, fc_bits);
            f[Field::kFcTheta] = fc.theta;
            f[Field::kFcPhi] = fc.phi;
            f[Field::kFcPsi] = fc.psi;
            f[Field::kSigmaC] = cc.assign(s.color.sigma, &err2[3 * i + 2]);
          }
          pack_record(layout, f, bytes.data() + i * record_bytes);
        });
        for (uint64_t i = 0; i < count; ++i)
          for (int c = 0; c < 3; ++c) err_sum[c] += err2[3 * i + c];
        return out.put(bytes);
      }))
    return false;
  const uint32_t crc = out.crc();
  uint8_t tail[4];
  store_u32le(tail, crc);
  if (!out.put(tail, 4)) return false;
  for (int c = 0; c < 3; ++c)
    if (report.classes[c]) report.class_rms_log_error[c] = std::sqrt(err_sum[c] / static_cast<double>(nodes));
  report.bytes = out.bytes();
  report.record_bytes = record_bytes;
  report.bits_per_point = 8.0 * static_cast<double>(report.bytes) / static_cast<double>(report.points);
  report.seconds.write = monotonic_seconds() - stage_start;
  return true;
}

}  // namespace stipple
