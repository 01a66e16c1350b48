// stipple host — hierarchy construction (TOG05 §4). See hierarchy.h.
#include "tools/encoder/hierarchy.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <thread>

#include "tools/encoder/parallel.h"

namespace stipple {
namespace {

// Whitening transform of a cluster: m(q) = ||W (q - mean)||.
struct Metric {
  Vec3 mean;
  Mat3 w = Mat3::Identity();
};

Metric mahalanobis_metric(const Gaussian3& g, double min_sigma) {
  Metric m;
  m.mean = g.mean;
  for (int k = 0; k < 3; ++k) m.w.row(k) = g.frame.col(k).transpose() / std::max(g.sigma[k], min_sigma);
  return m;
}

// A node's points and their indices reordered together, stably, by label: the
// ones labelled b go to fill[b], fill[b] + 1, ... (the counts' prefix sums).
// `nrm` may be null (a scan without normals).
struct Scratch {
  std::vector<uint32_t> ids;
  std::vector<Vec3> points, normals;
  void scatter(Vec3* p, Vec3* nrm, uint32_t* id, size_t n, const std::vector<uint8_t>& labels, uint32_t* fill) {
    ids.assign(id, id + n);
    points.assign(p, p + n);
    if (nrm) normals.assign(nrm, nrm + n);
    for (size_t i = 0; i < n; ++i) {
      const uint32_t to = fill[labels[i]]++;
      id[to] = ids[i];
      p[to] = points[i];
      if (nrm) nrm[to] = normals[i];
    }
  }
};

struct SplitResult {
  uint32_t mid = 0;  // order[begin, mid) left, [mid, end) right
  bool ok = false;
  bool fallback = false, unbalanced = false;
  int iterations = 0;
};

// A node's sums are taken over fixed chunks of kChunk points and added in
// chunk order, whether one thread or several compute them: the same bits for
// any thread count, and a large node (the top levels) on every core.
constexpr size_t kChunk = 1 << 16;

size_t chunk_count(size_t n) { return (n + kChunk - 1) / kChunk; }

// fn(lo, hi, chunk) for each chunk of [0, n) on `threads` threads.
template <class Fn>
void for_chunks(size_t n, int threads, const Fn& fn) {
  const size_t chunks = chunk_count(n);
  if (threads <= 1 || chunks <= 1) {
    for (size_t c = 0; c < chunks; ++c) fn(c * kChunk, std::min(n, (c + 1) * kChunk), c);
    return;
  }
  parallel_for(chunks, threads, 1, [&](size_t c) { fn(c * kChunk, std::min(n, (c + 1) * kChunk), c); });
}

// PCA of p[0..n) (pca3's two passes, chunked).
Gaussian3 node_pca(const Vec3* p, size_t n, int threads) {
  if (n == 0) return Gaussian3{};
  const Vec3 origin = p[0];
  if (n <= kChunk) return pca3(p, n);  // one chunk: the plain loops
  std::vector<Vec3> sums(chunk_count(n), Vec3::Zero());
  for_chunks(n, threads, [&](size_t lo, size_t hi, size_t c) {
    for (size_t i = lo; i < hi; ++i) sums[c] += p[i] - origin;
  });
  Vec3 sum = Vec3::Zero();
  for (const Vec3& v : sums) sum += v;
  const Vec3 mean = origin + sum / static_cast<double>(n);
  std::vector<Mat3> m2s(sums.size(), Mat3::Zero());
  for_chunks(n, threads, [&](size_t lo, size_t hi, size_t c) {
    for (size_t i = lo; i < hi; ++i) {
      const Vec3 d = p[i] - mean;
      m2s[c].noalias() += d * d.transpose();
    }
  });
  Mat3 m2 = Mat3::Zero();
  for (const Mat3& m : m2s) m2 += m;
  return gaussian_from_covariance(mean, m2 / static_cast<double>(n));
}

// normal_spread of nrm[0..n) (its turn against p[0..n) about `mean`),
// chunked like node_pca.
NormalSpread node_normal_spread(const Vec3* nrm, const Vec3* p, const Vec3& mean, size_t n, const Vec3& fallback_z,
                                int threads) {
  if (n <= kChunk) return normal_spread(nrm, n, fallback_z, p, mean);  // one chunk: the plain loops
  std::vector<Vec3> sums(chunk_count(n), Vec3::Zero());
  for_chunks(n, threads, [&](size_t lo, size_t hi, size_t c) {
    for (size_t i = lo; i < hi; ++i) sums[c] += nrm[i];
  });
  Vec3 sum = Vec3::Zero();
  for (const Vec3& v : sums) sum += v;
  const LogMapFrame frame = log_map_frame(sum, n, fallback_z);
  std::vector<LogMapSums> parts(sums.size());
  for_chunks(n, threads,
             [&](size_t lo, size_t hi, size_t c) { accumulate_log_map(frame, nrm + lo, hi - lo, parts[c], p + lo, mean); });
  LogMapSums all;
  for (const LogMapSums& part : parts) all.add(part);
  return finish_log_map(frame, all);
}

// 2-means on the node's points p[0..n). Fills `labels` (0/1). Returns the
// left-cluster size.
size_t two_means(const Vec3* p, size_t n, const Gaussian3& parent, bool mahalanobis, const TreeOptions& o,
                 int threads, std::vector<uint8_t>& labels, int& iterations) {
  const double min_sigma = std::max(1e-3 * parent.sigma[0], o.stats.sigma_floor);
  const Vec3 step = o.init_step * parent.sigma[0] * parent.frame.col(0);
  Metric c[2];
  c[0] = mahalanobis ? mahalanobis_metric(parent, min_sigma) : Metric{};
  c[1] = c[0];
  c[0].mean = parent.mean + step;
  c[1].mean = parent.mean - step;
  labels.assign(n, 0);
  double previous = std::numeric_limits<double>::infinity();
  size_t left = 0;
  struct Partial {
    double distortion = 0;
    size_t left = 0;
    Vec3 sum[2] = {Vec3::Zero(), Vec3::Zero()};
    Mat3 cov[2] = {Mat3::Zero(), Mat3::Zero()};
  };
  thread_local std::vector<Partial> reused;  // most nodes are one chunk
  std::vector<Partial>& parts = reused;       // this thread's, which the chunks' threads share
  for (int it = 0; it < o.max_iterations; ++it) {
    ++iterations;
    parts.assign(chunk_count(n), Partial{});
    for_chunks(n, threads, [&](size_t lo, size_t hi, size_t chunk) {
      Partial& part = parts[chunk];
      for (size_t i = lo; i < hi; ++i) {
        const Vec3& q = p[i];
        const double d0 = (c[0].w * (q - c[0].mean)).squaredNorm();
        const double d1 = (c[1].w * (q - c[1].mean)).squaredNorm();
        const uint8_t label = d1 < d0 ? 1 : 0;
        labels[i] = label;
        part.distortion += std::sqrt(label ? d1 : d0);
        part.left += label == 0;
        part.sum[label] += q - parent.mean;
      }
    });
    double distortion = 0;
    left = 0;
    Vec3 sum[2] = {Vec3::Zero(), Vec3::Zero()};
    for (const Partial& part : parts) {
      distortion += part.distortion;
      left += part.left;
      sum[0] += part.sum[0];
      sum[1] += part.sum[1];
    }
    if (left == 0 || left == n) return left;
    const bool converged = std::abs(previous - distortion) <= o.tolerance * std::max(previous, 1e-300);
    previous = distortion;
    if (converged) break;
    const size_t count[2] = {left, n - left};
    Vec3 mean[2];
    for (int k = 0; k < 2; ++k) mean[k] = parent.mean + sum[k] / static_cast<double>(count[k]);
    if (!mahalanobis) {
      c[0].mean = mean[0];
      c[1].mean = mean[1];
      continue;
    }
    for_chunks(n, threads, [&](size_t lo, size_t hi, size_t chunk) {
      Mat3* cov = parts[chunk].cov;
      for (size_t i = lo; i < hi; ++i) {
        const Vec3 d = p[i] - mean[labels[i]];
        cov[labels[i]].noalias() += d * d.transpose();
      }
    });
    for (int k = 0; k < 2; ++k) {
      Mat3 cov = Mat3::Zero();
      for (const Partial& part : parts) cov += part.cov[k];
      c[k] = mahalanobis_metric(gaussian_from_covariance(mean[k], cov / static_cast<double>(count[k])), min_sigma);
    }
  }
  return left;
}

// Splits the node whose points are p[0..n) (ids[0..n) their indices), and
// partitions both, stably, left then right.
SplitResult split_binary(Vec3* p, Vec3* nrm, uint32_t* ids, size_t n, const Gaussian3& g, const TreeOptions& o, int threads,
                         std::vector<uint8_t>& labels, Scratch& scratch) {
  SplitResult r;
  size_t left = two_means(p, n, g, true, o, threads, labels, r.iterations);
  auto in_band = [&](size_t l) {
    const double f = static_cast<double>(std::min(l, n - l)) / static_cast<double>(n);
    return f >= o.balance;
  };
  if (!in_band(left)) {
    r.fallback = true;
    left = two_means(p, n, g, false, o, threads, labels, r.iterations);
    r.unbalanced = !in_band(left);
  }
  if (left == 0 || left == n) return r;
  uint32_t fill[2] = {0, static_cast<uint32_t>(left)};
  scratch.scatter(p, nrm, ids, n, labels, fill);
  r.mid = static_cast<uint32_t>(left);
  r.ok = true;
  return r;
}

struct Cube {
  Vec3 center;
  double half;
};

}  // namespace

uint32_t Tree::leaf_count() const {
  uint32_t leaves = 0;
  for (const TreeNode& node : nodes) leaves += node.leaf();
  return leaves;
}

namespace {

// build_tree on `positions` and `normals` (the scan's, moved or copied in;
// empty normals: none), which it reorders; `cloud` gives the colours.
Tree build(std::vector<Vec3> positions, std::vector<Vec3> normals, const PointCloud& cloud, const TreeOptions& o,
           const std::function<void(double)>& progress) {
  Tree tree;
  tree.octree = o.octree;
  const size_t n = positions.size();
  tree.order.resize(n);
  for (size_t i = 0; i < n; ++i) tree.order[i] = static_cast<uint32_t>(i);
  // Room for the nodes up front: a vector that doubles copies itself, and at
  // 10^8 points the old and the new copy of ~350-byte nodes were 12 GB at
  // once. Leaves of the default 16 hold ~10.6 points, so there are ~0.19 n
  // nodes; pages reserved and never written cost address space, not memory.
  tree.nodes.reserve(n / 4 + 16);
  tree.nodes.push_back(TreeNode{0, static_cast<uint32_t>(n), 0, 0, 0, {}});
  std::vector<Cube> cubes;  // octree only, parallel to nodes
  if (o.octree) {
    const Box3 box = bounding_box(positions);
    cubes.push_back({(box.min + box.max) / 2, (box.max - box.min).maxCoeff() / 2 * (1 + 1e-9) + o.stats.sigma_floor});
  }
  // `positions` and `normals` are partitioned with `order`: a node's points
  // are contiguous, so its PCA and 2-means read memory in sequence.
  double processed = 0;  // points handled by finished levels
  const double expected_work = static_cast<double>(n) *
      (std::log2(std::max(2.0, static_cast<double>(n) / std::max<uint32_t>(o.leaf_size, 2))) + 2);

  size_t level_begin = 0;
  std::vector<size_t> level_starts;
  while (level_begin < tree.nodes.size()) {
    level_starts.push_back(level_begin);
    const size_t level_end = tree.nodes.size();
    const size_t level_size = level_end - level_begin;
    // Children found for each node of this level: ranges of `order`, in order.
    std::vector<std::vector<std::pair<uint32_t, uint32_t>>> children(level_size);
    std::vector<std::vector<Cube>> child_cubes(o.octree ? level_size : 0);
    std::vector<SplitResult> results(level_size);
    // One node: its PCA, then its split; `threads` work inside it.
    const auto split_node = [&](size_t k, int threads, std::vector<uint8_t>& labels, Scratch& scratch) {
      {
        TreeNode& node = tree.nodes[level_begin + k];
        uint32_t* ids = tree.order.data() + node.begin;
        Vec3* p = positions.data() + node.begin;
        Vec3* nrm = normals.empty() ? nullptr : normals.data() + node.begin;
        const size_t count = node.count();
        // The statistics but colours (those come from the leaves up).
        const Gaussian3 position = node_pca(p, count, threads);
        NormalSpread spread;
        if (nrm) spread = node_normal_spread(nrm, p, position.mean, count, position.frame.col(2), threads);
        node.stats = finish_stats(count, position, nrm ? &spread : nullptr, o.stats);
        if (count < o.leaf_size || node.stats.position.sigma[0] <= o.stats.sigma_floor ||
            node.stats.position.sigma[0] <= o.leaf_sigma || node.depth >= o.max_depth)
          return;
        if (!o.octree) {
          results[k] = split_binary(p, nrm, ids, count, node.stats.position, o, threads, labels, scratch);
          if (results[k].ok)
            children[k] = {{node.begin, node.begin + results[k].mid}, {node.begin + results[k].mid, node.end}};
          return;
        }
        const Cube cube = cubes[level_begin + k];
        uint32_t bucket_size[8] = {};
        labels.resize(count);
        for (size_t i = 0; i < count; ++i) {
          const Vec3& q = p[i];
          const uint8_t oct = static_cast<uint8_t>((q.x() >= cube.center.x()) | ((q.y() >= cube.center.y()) << 1) |
                                                   ((q.z() >= cube.center.z()) << 2));
          labels[i] = oct;
          ++bucket_size[oct];
        }
        uint32_t start[8], at = 0;
        for (int b = 0; b < 8; ++b) {
          start[b] = at;
          at += bucket_size[b];
        }
        uint32_t fill[8];
        std::copy(start, start + 8, fill);
        scratch.scatter(p, nrm, ids, count, labels, fill);
        for (int b = 0; b < 8; ++b) {
          if (bucket_size[b] == 0) continue;
          children[k].push_back({node.begin + start[b], node.begin + start[b] + bucket_size[b]});
          const double h = cube.half / 2;
          const Vec3 c = cube.center + Vec3((b & 1) ? h : -h, (b & 2) ? h : -h, (b & 4) ? h : -h);
          child_cubes[k].push_back({c, h});
        }
      }
    };
    // Wide nodes (the top levels) one at a time on every thread, then the
    // rest a node per thread; the bits are the same either way (kChunk).
    std::vector<uint8_t> labels;
    Scratch scratch;
    std::vector<size_t> narrow;
    for (size_t k = 0; k < level_size; ++k) {
      if (tree.nodes[level_begin + k].count() >= o.wide_node) split_node(k, o.threads, labels, scratch);
      else narrow.push_back(k);
    }
    scratch = Scratch{};  // a wide node's copies (up to the whole scan) go now
    std::atomic<size_t> next{0};
    auto worker = [&]() {
      std::vector<uint8_t> own_labels;
      Scratch own_scratch;
      for (size_t at; (at = next.fetch_add(1)) < narrow.size();) split_node(narrow[at], 1, own_labels, own_scratch);
    };
    std::vector<std::thread> pool;
    for (int t = 1; t < std::max(1, o.threads) && static_cast<size_t>(t) < narrow.size(); ++t) pool.emplace_back(worker);
    worker();
    for (std::thread& t : pool) t.join();

    for (size_t k = 0; k < level_size; ++k) {
      const SplitResult& r = results[k];
      tree.report.two_means_iterations += static_cast<uint64_t>(r.iterations);
      tree.report.euclidean_fallbacks += r.fallback;
      tree.report.unbalanced += r.unbalanced && r.ok;
      tree.report.failed_splits += (r.fallback || r.iterations > 0) && !r.ok;
      const size_t id = level_begin + k;
      processed += tree.nodes[id].count();
      if (children[k].empty()) continue;
      ++tree.report.splits;
      tree.nodes[id].first_child = static_cast<uint32_t>(tree.nodes.size());
      tree.nodes[id].child_count = static_cast<uint8_t>(children[k].size());
      const uint16_t depth = static_cast<uint16_t>(tree.nodes[id].depth + 1);
      tree.depth = std::max<int>(tree.depth, depth);
      for (size_t c = 0; c < children[k].size(); ++c) {
        tree.nodes.push_back(TreeNode{children[k][c].first, children[k][c].second, 0, 0, depth, {}});
        if (o.octree) cubes.push_back(child_cubes[k][c]);
      }
    }
    level_begin = level_end;
    if (progress) progress(std::min(0.99, processed / std::max(expected_work, 1.0)));
  }

  // Colours from the leaves up, one level at a time: a leaf's moments from
  // its points, a parent's its children's added in order.
  if (!o.stats.colors || !cloud.has_colors()) return tree;
  std::vector<Moments> below, current;
  size_t below_begin = tree.nodes.size();
  for (size_t level = level_starts.size(); level-- > 0;) {
    const size_t begin = level_starts[level];
    const size_t end = level + 1 < level_starts.size() ? level_starts[level + 1] : tree.nodes.size();
    current.assign(end - begin, Moments{});
    parallel_for(end - begin, o.threads, 64, [&](size_t k) {
      TreeNode& node = tree.nodes[begin + k];
      Moments& m = current[k];
      if (node.leaf()) m = color_moments(cloud, tree.order.data() + node.begin, node.count(), o.stats);
      for (uint32_t c = 0; c < node.child_count; ++c) m.add(below[node.first_child + c - below_begin]);
      set_color_stats(node.stats, m, o.stats);
    });
    below.swap(current);
    below_begin = begin;
  }
  return tree;
}

}  // namespace

Tree build_tree(const PointCloud& cloud, const TreeOptions& o, const std::function<void(double)>& progress) {
  return build(cloud.positions, o.stats.normals ? cloud.normals : std::vector<Vec3>{}, cloud, o, progress);
}

Tree build_tree_consuming(PointCloud& cloud, const TreeOptions& o, const std::function<void(double)>& progress) {
  std::vector<Vec3> normals;
  if (o.stats.normals) normals = std::move(cloud.normals);
  cloud.normals = {};
  return build(std::move(cloud.positions), std::move(normals), cloud, o, progress);
}

void PartitionRatioAccumulator::add_family(double parent_sigma1, const double* counts, const double* sigma1,
                                           size_t children) {
  if (children == 0) return;
  const auto [cmin, cmax] = std::minmax_element(counts, counts + children);
  const auto [smin, smax] = std::minmax_element(sigma1, sigma1 + children);
  apr_sum += *cmax / *cmin;
  ++families;
  if (*smin >= 1e-6 * parent_sigma1) {
    capr_sum += *smax / *smin;
    ++capr_families;
  }
}

void PartitionRatioAccumulator::add(const PartitionRatioAccumulator& o) {
  apr_sum += o.apr_sum;
  capr_sum += o.capr_sum;
  families += o.families;
  capr_families += o.capr_families;
}

PartitionRatios PartitionRatioAccumulator::result() const {
  PartitionRatios r;
  r.families = families;
  r.capr_excluded = families - capr_families;
  if (families) r.apr = apr_sum / static_cast<double>(families);
  if (capr_families) r.capr = capr_sum / static_cast<double>(capr_families);
  return r;
}

PartitionRatios partition_ratios(const Tree& tree) { return partition_ratio_sums(tree).result(); }

PartitionRatioAccumulator partition_ratio_sums(const Tree& tree) {
  PartitionRatioAccumulator acc;
  double counts[8], sigma1[8];
  for (const TreeNode& node : tree.nodes) {
    for (uint32_t c = 0; c < node.child_count; ++c) {
      counts[c] = tree.nodes[node.first_child + c].count();
      sigma1[c] = tree.nodes[node.first_child + c].stats.position.sigma[0];
    }
    acc.add_family(node.stats.position.sigma[0], counts, sigma1, node.child_count);
  }
  return acc;
}

}  // namespace stipple
