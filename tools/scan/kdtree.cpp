// stipple host — static kd-tree (median split on the widest axis, buckets of 8).
#include "tools/scan/kdtree.h"

#include <algorithm>
#include <limits>
#include <numeric>
#include <thread>

namespace stipple {
namespace {
constexpr uint32_t kBucket = 8;
constexpr uint32_t kParallelRange = 1 << 16;  // smaller halves are not worth a thread
}

// A bounded list of the best candidates found so far, sorted by (distance, index).
// Fixed storage: queries allocate nothing.
struct KdTree::Best {
  size_t k;
  size_t count = 0;
  size_t visited = 0;  // points offered: the query's cost
  std::pair<double, uint32_t> items[kMaxK] = {};
  double worst() const { return count < k ? std::numeric_limits<double>::infinity() : items[count - 1].first; }
  void offer(double d2, uint32_t index) {
    ++visited;
    const std::pair<double, uint32_t> item{d2, index};
    if (count == k) {
      if (!(item < items[count - 1])) return;
      --count;
    }
    size_t i = count++;
    for (; i > 0 && item < items[i - 1]; --i) items[i] = items[i - 1];
    items[i] = item;
  }
};

KdTree::KdTree(const std::vector<Vec3>& points, int threads)
    : points_(points), order_(points.size()), axis_(points.size(), 0) {
  std::iota(order_.begin(), order_.end(), 0u);
  build(0, static_cast<uint32_t>(points.size()), std::max(1, threads));
}

// Splits [lo, hi) at its median along its widest axis, then its halves: the
// two halves are disjoint ranges, so with threads to spare one half goes to
// a thread of its own. Each range's split depends on its contents alone, so
// the tree is the same for any thread count.
void KdTree::build(uint32_t lo0, uint32_t hi0, int threads) {
  struct Range {
    uint32_t lo, hi;
  };
  std::vector<Range> stack{{lo0, hi0}};
  std::vector<std::thread> helpers;
  while (!stack.empty()) {
    const Range r = stack.back();
    stack.pop_back();
    if (r.hi - r.lo <= kBucket) continue;
    Vec3 lo = points_[order_[r.lo]], hi = lo;
    for (uint32_t i = r.lo; i < r.hi; ++i) {
      lo = lo.cwiseMin(points_[order_[i]]);
      hi = hi.cwiseMax(points_[order_[i]]);
    }
    int axis;
    (hi - lo).maxCoeff(&axis);
    const uint32_t mid = r.lo + (r.hi - r.lo) / 2;
    std::nth_element(order_.begin() + r.lo, order_.begin() + mid, order_.begin() + r.hi,
                     [&](uint32_t a, uint32_t b) {
                       const double pa = points_[a][axis], pb = points_[b][axis];
                       return pa < pb || (pa == pb && a < b);
                     });
    axis_[mid] = static_cast<uint8_t>(axis);
    if (threads > 1 && mid - r.lo >= kParallelRange) {
      const int given = threads / 2;
      threads -= given;
      helpers.emplace_back([this, r, mid, given] { build(r.lo, mid, given); });
    } else {
      stack.push_back({r.lo, mid});
    }
    stack.push_back({mid + 1, r.hi});
  }
  for (std::thread& t : helpers) t.join();
}

void KdTree::search(uint32_t lo, uint32_t hi, const Vec3& q, Best& best) const {
  if (hi - lo <= kBucket) {
    for (uint32_t i = lo; i < hi; ++i) best.offer((points_[order_[i]] - q).squaredNorm(), order_[i]);
    return;
  }
  const uint32_t mid = lo + (hi - lo) / 2;
  const uint32_t index = order_[mid];
  const int axis = axis_[mid];
  const double delta = q[axis] - points_[index][axis];
  best.offer((points_[index] - q).squaredNorm(), index);
  // The far side is searched only if it could hold a strictly closer point.
  // With "<=" a tie at the splitting plane sent the search into both halves,
  // so k-NN among many coincident points visited whole subtrees (quadratic).
  if (delta < 0) {
    search(lo, mid, q, best);
    if (delta * delta < best.worst()) search(mid + 1, hi, q, best);
  } else {
    search(mid + 1, hi, q, best);
    if (delta * delta < best.worst()) search(lo, mid, q, best);
  }
}

uint32_t KdTree::nearest(const Vec3& q, double* dist2) const {
  Best best{1, 0, 0, {}};
  search(0, static_cast<uint32_t>(order_.size()), q, best);
  if (dist2) *dist2 = best.count == 0 ? 0.0 : best.items[0].first;
  return best.count == 0 ? 0u : best.items[0].second;
}

uint32_t KdTree::nearest(const Vec3& q, uint32_t hint) const {
  Best best{1, 0, 0, {}};
  if (hint < points_.size()) best.offer((points_[hint] - q).squaredNorm(), hint);
  search(0, static_cast<uint32_t>(order_.size()), q, best);
  return best.count == 0 ? 0u : best.items[0].second;
}

void KdTree::knearest(const Vec3& q, size_t k, std::vector<uint32_t>& out, size_t* visited) const {
  Best best{std::min(k, kMaxK), 0, 0, {}};
  search(0, static_cast<uint32_t>(order_.size()), q, best);
  if (visited) *visited = best.visited;
  out.clear();
  for (size_t i = 0; i < best.count; ++i) out.push_back(best.items[i].second);
}

}  // namespace stipple
