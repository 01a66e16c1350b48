// stipple host — the node hierarchy (TOG05 §4, "Hierarchical PCA"; SGP03's
// octree as the baseline of TOG05 Table II).
//
// Top-down, level by level, so nodes come out in breadth-first order with
// siblings adjacent — the order of the `.spg` file. A node splits unless it
// holds fewer than `leaf_size` points, its sigma1 is at the variance floor or
// at most `leaf_sigma` (the variance stop), or it sits at `max_depth`.
//
// Binary split by 2-means: centres mean +- `init_step` * sigma1 * f1; assign
// each point to the nearer centre by Mahalanobis distance ||S T (q - mu)||
// (each cluster's own PCA; axes below 1e-3 sigma1 of the parent are clamped
// so a flat cluster's metric stays finite), update means and covariances,
// stop when the distortion (sum of distances) changes by less than
// `tolerance` relative, or after `max_iterations`. A split whose smaller side
// holds less than `balance` of the points is redone with Euclidean distance;
// that result is kept even if still unbalanced. A split that leaves one side
// empty makes the node a leaf.
//
// Octree: the node's cube is cut into its 8 octants; empty octants are dropped.
//
// Deterministic: the same input and options give the same tree for any
// thread count (nodes of a level are independent; children are appended in
// node order).
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "tools/encoder/node_stats.h"

namespace stipple {

struct TreeOptions {
  uint32_t leaf_size = 16;  // nodes with fewer points are leaves
  double leaf_sigma = 0;    // and those whose sigma1 is at most this (TOG05's variance stop; 0: none)
  double balance = 0.3;     // balance band [balance, 1 - balance]
  bool octree = false;
  int max_iterations = 30;
  double tolerance = 1e-7;
  double init_step = 0.8;   // initial centres at +- init_step * sigma1 along f1
  int max_depth = 512;
  int threads = 2;
  // Nodes of at least this many points are split one at a time with every
  // thread inside them (the top levels); smaller ones a node per thread.
  // Sums run over fixed chunks of 65,536 points either way, so neither this
  // nor `threads` changes a bit of the tree.
  uint32_t wide_node = 8 << 16;
  StatsOptions stats;
};

struct TreeNode {
  uint32_t begin = 0, end = 0;  // range of Tree::order
  uint32_t first_child = 0;     // 0 for a leaf (the root is never a child)
  uint8_t child_count = 0;
  uint16_t depth = 0;
  NodeStats stats;
  uint32_t count() const { return end - begin; }
  bool leaf() const { return child_count == 0; }
};

struct TreeReport {
  uint64_t splits = 0;             // internal nodes
  uint64_t euclidean_fallbacks = 0;  // Mahalanobis split out of the band, redone
  uint64_t unbalanced = 0;         // still out of the band after the fallback
  uint64_t failed_splits = 0;      // one side empty: became a leaf
  uint64_t two_means_iterations = 0;
  void add(const TreeReport& o) {
    splits += o.splits;
    euclidean_fallbacks += o.euclidean_fallbacks;
    unbalanced += o.unbalanced;
    failed_splits += o.failed_splits;
    two_means_iterations += o.two_means_iterations;
  }
};

struct Tree {
  std::vector<uint32_t> order;  // point indices; each node owns order[begin, end)
  std::vector<TreeNode> nodes;  // breadth-first, siblings adjacent, root first
  int depth = 0;
  bool octree = false;
  TreeReport report;
  uint32_t leaf_count() const;
};

// `progress(fraction)` is called from the building thread between levels;
// the fraction estimates the work done: points processed so far over
// n x (expected depth + 1), with the expected depth log2(n / leaf_size) + 1.
Tree build_tree(const PointCloud& cloud, const TreeOptions& options,
                const std::function<void(double)>& progress = {});
// The same tree, taking the scan's positions and normals instead of copying
// them: `cloud` is left with none (its colours stay). 48 bytes a point less
// at the encoder's peak.
Tree build_tree_consuming(PointCloud& cloud, const TreeOptions& options,
                          const std::function<void(double)>& progress = {});

// Table II statistics. APR: the average over internal nodes of the largest /
// smallest child point count. cAPR: the same for sigma1, over the families
// whose children all have a sigma1 of at least 1e-6 of their parent's — a
// single-point child sits at the variance floor and would make the ratio
// ~1e9; such families are counted in `capr_excluded` instead.
struct PartitionRatios {
  double apr = 0, capr = 0;
  uint64_t families = 0, capr_excluded = 0;
};

// Sums over families, so a tree built in parts adds up its parts' (the
// fields are plain for the part files that carry them).
struct PartitionRatioAccumulator {
  // One internal node: its sigma1 and its children's point counts and sigma1s.
  void add_family(double parent_sigma1, const double* counts, const double* sigma1, size_t children);
  void add(const PartitionRatioAccumulator& other);
  PartitionRatios result() const;

  double apr_sum = 0, capr_sum = 0;
  uint64_t families = 0, capr_families = 0;
};

PartitionRatioAccumulator partition_ratio_sums(const Tree& tree);
PartitionRatios partition_ratios(const Tree& tree);

}  // namespace stipple
