// stipple host — hierarchy construction (TOG05 §4). See hierarchy.h.
#include "tools/encoder/hierarchy.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <thread>

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

struct SplitResult {
  uint32_t mid = 0;  // order[begin, mid) left, [mid, end) right
  bool ok = false;
  bool fallback = false, unbalanced = false;
  int iterations = 0;
};

// 2-means on ids[0..n). Fills `labels` (0/1). Returns the left-cluster size.
size_t two_means(const Vec3* p, const uint32_t* ids, size_t n, const Gaussian3& parent, bool mahalanobis,
                 const TreeOptions& o, std::vector<uint8_t>& labels, int& iterations) {
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
  for (int it = 0; it < o.max_iterations; ++it) {
    ++iterations;
    double distortion = 0;
    left = 0;
    Vec3 sum[2] = {Vec3::Zero(), Vec3::Zero()};
    for (size_t i = 0; i < n; ++i) {
      const Vec3& q = p[ids[i]];
      const double d0 = (c[0].w * (q - c[0].mean)).squaredNorm();
      const double d1 = (c[1].w * (q - c[1].mean)).squaredNorm();
      const uint8_t label = d1 < d0 ? 1 : 0;
      labels[i] = label;
      distortion += std::sqrt(label ? d1 : d0);
      left += label == 0;
      sum[label] += q - parent.mean;
    }
    if (left == 0 || left == n) return left;
    const bool converged = std::abs(previous - distortion) <= o.tolerance * std::max(previous, 1e-300);
    previous = distortion;
    if (converged) break;
    const size_t count[2] = {left, n - left};
    for (int k = 0; k < 2; ++k) {
      const Vec3 mean = parent.mean + sum[k] / static_cast<double>(count[k]);
      if (!mahalanobis) {
        c[k].mean = mean;
        continue;
      }
      Mat3 cov = Mat3::Zero();
      for (size_t i = 0; i < n; ++i) {
        if (labels[i] != k) continue;
        const Vec3 d = p[ids[i]] - mean;
        cov.noalias() += d * d.transpose();
      }
      cov /= static_cast<double>(count[k]);
      const Eigen::SelfAdjointEigenSolver<Mat3> eig(cov);
      Gaussian3 g;
      g.mean = mean;
      for (int a = 0; a < 3; ++a) {
        g.sigma[a] = std::sqrt(std::max(0.0, eig.eigenvalues()[2 - a]));
        g.frame.col(a) = eig.eigenvectors().col(2 - a);
      }
      c[k] = mahalanobis_metric(g, min_sigma);
    }
  }
  return left;
}

SplitResult split_binary(const Vec3* p, uint32_t* ids, size_t n, const Gaussian3& g, const TreeOptions& o,
                         std::vector<uint8_t>& labels, std::vector<uint32_t>& scratch) {
  SplitResult r;
  size_t left = two_means(p, ids, n, g, true, o, labels, r.iterations);
  auto in_band = [&](size_t l) {
    const double f = static_cast<double>(std::min(l, n - l)) / static_cast<double>(n);
    return f >= o.balance;
  };
  if (!in_band(left)) {
    r.fallback = true;
    left = two_means(p, ids, n, g, false, o, labels, r.iterations);
    r.unbalanced = !in_band(left);
  }
  if (left == 0 || left == n) return r;
  // Stable partition by label.
  scratch.assign(ids, ids + n);
  size_t a = 0, b = left;
  for (size_t i = 0; i < n; ++i) ids[labels[i] ? b++ : a++] = scratch[i];
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

Tree build_tree(const PointCloud& cloud, const TreeOptions& o, const std::function<void(double)>& progress) {
  Tree tree;
  tree.octree = o.octree;
  const size_t n = cloud.size();
  tree.order.resize(n);
  for (size_t i = 0; i < n; ++i) tree.order[i] = static_cast<uint32_t>(i);
  tree.nodes.push_back(TreeNode{0, static_cast<uint32_t>(n), 0, 0, 0, {}});
  std::vector<Cube> cubes;  // octree only, parallel to nodes
  if (o.octree) {
    const Box3 box = bounding_box(cloud.positions);
    cubes.push_back({(box.min + box.max) / 2, (box.max - box.min).maxCoeff() / 2 * (1 + 1e-9) + o.stats.sigma_floor});
  }
  const Vec3* p = cloud.positions.data();
  double processed = 0;  // points handled by finished levels
  const double expected_work = static_cast<double>(n) *
      (std::log2(std::max(2.0, static_cast<double>(n) / std::max<uint32_t>(o.leaf_size, 2))) + 2);

  size_t level_begin = 0;
  while (level_begin < tree.nodes.size()) {
    const size_t level_end = tree.nodes.size();
    const size_t level_size = level_end - level_begin;
    // Children found for each node of this level: ranges of `order`, in order.
    std::vector<std::vector<std::pair<uint32_t, uint32_t>>> children(level_size);
    std::vector<std::vector<Cube>> child_cubes(o.octree ? level_size : 0);
    std::vector<SplitResult> results(level_size);
    std::atomic<size_t> next{0};
    auto worker = [&]() {
      std::vector<uint8_t> labels;
      std::vector<uint32_t> scratch;
      for (size_t k; (k = next.fetch_add(1)) < level_size;) {
        TreeNode& node = tree.nodes[level_begin + k];
        uint32_t* ids = tree.order.data() + node.begin;
        const size_t count = node.count();
        node.stats = node_stats(cloud, ids, count, o.stats);
        if (count < o.leaf_size || node.stats.position.sigma[0] <= o.stats.sigma_floor || node.depth >= o.max_depth)
          continue;
        if (!o.octree) {
          results[k] = split_binary(p, ids, count, node.stats.position, o, labels, scratch);
          if (results[k].ok)
            children[k] = {{node.begin, node.begin + results[k].mid}, {node.begin + results[k].mid, node.end}};
          continue;
        }
        const Cube cube = cubes[level_begin + k];
        uint32_t bucket_size[8] = {};
        labels.resize(count);
        for (size_t i = 0; i < count; ++i) {
          const Vec3& q = p[ids[i]];
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
        scratch.assign(ids, ids + count);
        uint32_t fill[8];
        std::copy(start, start + 8, fill);
        for (size_t i = 0; i < count; ++i) ids[fill[labels[i]]++] = scratch[i];
        for (int b = 0; b < 8; ++b) {
          if (bucket_size[b] == 0) continue;
          children[k].push_back({node.begin + start[b], node.begin + start[b] + bucket_size[b]});
          const double h = cube.half / 2;
          const Vec3 c = cube.center + Vec3((b & 1) ? h : -h, (b & 2) ? h : -h, (b & 4) ? h : -h);
          child_cubes[k].push_back({c, h});
        }
      }
    };
    std::vector<std::thread> pool;
    for (int t = 1; t < std::max(1, o.threads) && static_cast<size_t>(t) < level_size; ++t) pool.emplace_back(worker);
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
  return tree;
}

void PartitionRatioAccumulator::add_family(double parent_sigma1, const double* counts, const double* sigma1,
                                           size_t children) {
  if (children == 0) return;
  const auto [cmin, cmax] = std::minmax_element(counts, counts + children);
  const auto [smin, smax] = std::minmax_element(sigma1, sigma1 + children);
  apr_sum_ += *cmax / *cmin;
  ++families_;
  if (*smin >= 1e-6 * parent_sigma1) {
    capr_sum_ += *smax / *smin;
    ++capr_families_;
  }
}

PartitionRatios PartitionRatioAccumulator::result() const {
  PartitionRatios r;
  r.families = families_;
  r.capr_excluded = families_ - capr_families_;
  if (families_) r.apr = apr_sum_ / static_cast<double>(families_);
  if (capr_families_) r.capr = capr_sum_ / static_cast<double>(capr_families_);
  return r;
}

PartitionRatios partition_ratios(const Tree& tree) {
  PartitionRatioAccumulator acc;
  double counts[8], sigma1[8];
  for (const TreeNode& node : tree.nodes) {
    for (uint32_t c = 0; c < node.child_count; ++c) {
      counts[c] = tree.nodes[node.first_child + c].count();
      sigma1[c] = tree.nodes[node.first_child + c].stats.position.sigma[0];
    }
    acc.add_family(node.stats.position.sigma[0], counts, sigma1, node.child_count);
  }
  return acc.result();
}

}  // namespace stipple
