// stipple host — a static 3-D kd-tree for exact nearest-neighbour queries.
//
// Built once over a point array (which must outlive the tree) in
// O(n log n); queries are exact and read-only, so several threads may query
// one tree at once. Among candidates the search meets, ties are broken by the
// smaller point index; a subtree is searched only when it could hold a
// strictly closer point, so among many equidistant points (duplicates) the
// query costs O(k + log n), not a visit of every tie. Which of several
// equidistant points are returned is a function of the points alone: not of
// the thread count or the order of queries.
#pragma once

#include <cstdint>
#include <vector>

#include "tools/scan/point_cloud.h"

namespace stipple {

inline constexpr size_t kMaxK = 64;

class KdTree {
 public:
  // `threads` build disjoint subtrees at once; the tree is the same for any
  // count.
  explicit KdTree(const std::vector<Vec3>& points, int threads = 1);

  // Index of the nearest point to `q` and its squared distance.
  uint32_t nearest(const Vec3& q, double* dist2 = nullptr) const;
  // The same, starting from point `hint` as the best so far (a query's
  // previous answer, in k-means): subtrees that cannot beat it are skipped
  // from the start. Among equidistant points the answer may then be the hint,
  // so it is a function of the points and the hint.
  uint32_t nearest(const Vec3& q, uint32_t hint) const;

  // The `k` nearest points to `q` (k at most kMaxK), closest first (fewer if
  // the tree is smaller). `visited`, when given, receives the number of
  // points the query compared: its cost.
  void knearest(const Vec3& q, size_t k, std::vector<uint32_t>& out, size_t* visited = nullptr) const;

  size_t size() const { return order_.size(); }
  // The points' indices in the tree's order: neighbours in space are mostly
  // neighbours here, so queries made in this order share cache lines.
  const std::vector<uint32_t>& spatial_order() const { return order_; }

 private:
  struct Best;
  void build(uint32_t lo, uint32_t hi, int threads);
  void search(uint32_t lo, uint32_t hi, const Vec3& q, Best& best) const;

  const std::vector<Vec3>& points_;
  std::vector<uint32_t> order_;  // implicit tree: node = middle of a range
  std::vector<uint8_t> axis_;    // split axis of the node at each middle position
};

}  // namespace stipple
