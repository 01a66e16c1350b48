// stipple host — log-space k-means of sigma tuples. See classify.h.
#include "tools/encoder/classify.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <random>

#include "tools/encoder/parallel.h"
#include "tools/scan/kdtree.h"

namespace stipple {
namespace {

// Lloyd's sample: this many tuples a class, and at least this many.
constexpr size_t kLloydPerClass = 16, kLloydAtLeast = 16384;

// A uniform double in [0, 1) from a 64-bit generator, identical everywhere.
double uniform(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

void assign_all(const std::vector<Vec3>& points, const std::vector<Vec3>& centers, std::vector<uint16_t>& index,
                int threads) {
  const KdTree tree(centers);
  parallel_for(points.size(), threads, 1024,
               [&](size_t i) { index[i] = static_cast<uint16_t>(tree.nearest(points[i], uint32_t{index[i]})); });
}

}  // namespace

SigmaClasses::SigmaClasses(const std::vector<Vec3>& sample, int dims, int max_classes, int max_iterations, int threads)
    : dims_(dims) {
  const size_t n = sample.size();
  if (n == 0) return;
  std::vector<Vec3> logs(n, Vec3::Zero());
  for (size_t i = 0; i < n; ++i) logs[i] = log_of(sample[i]);

  // Few distinct tuples: classes are exact.
  std::vector<Vec3> distinct = logs;
  auto less = [](const Vec3& a, const Vec3& b) {
    return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3);
  };
  std::sort(distinct.begin(), distinct.end(), less);
  distinct.erase(std::unique(distinct.begin(), distinct.end()), distinct.end());
  const size_t k = std::min(distinct.size(), static_cast<size_t>(std::max(1, max_classes)));
  std::vector<Vec3>& centers = log_centers_;
  if (distinct.size() <= k) {
    centers = distinct;
  } else {
    // k-means++ seeding on a deterministic sample.
    std::mt19937_64 rng(0x5354504701ull);
    const size_t sample_size = std::min(distinct.size(), 4 * k);
    std::vector<Vec3> seeds;
    seeds.reserve(sample_size);
    for (size_t i = 0; i < sample_size; ++i) seeds.push_back(distinct[i * distinct.size() / sample_size]);
    std::vector<double> d2(sample_size, std::numeric_limits<double>::infinity());
    centers.push_back(seeds[static_cast<size_t>(uniform(rng) * static_cast<double>(sample_size))]);
    while (centers.size() < k) {
      double total = 0;
      for (size_t i = 0; i < sample_size; ++i) {
        d2[i] = std::min(d2[i], (seeds[i] - centers.back()).squaredNorm());
        total += d2[i];
      }
      if (total <= 0) break;
      double target = uniform(rng) * total;
      size_t pick = sample_size - 1;
      for (size_t i = 0; i < sample_size; ++i) {
        target -= d2[i];
        if (target < 0) {
          pick = i;
          break;
        }
      }
      centers.push_back(seeds[pick]);
    }
    // Lloyd iterations on a deterministic sample of the tuples (all of them
    // up to kLloydPerClass a class): the centres need a few dozen members
    // each to settle, and more only cost time (docs/encoder.md "Classes").
    const size_t lloyd_size = std::min(n, std::max(kLloydPerClass * k, kLloydAtLeast));
    std::vector<Vec3> lloyd;
    if (lloyd_size < n) {
      lloyd.reserve(lloyd_size);
      for (size_t i = 0; i < lloyd_size; ++i) lloyd.push_back(logs[i * n / lloyd_size]);
    }
    const std::vector<Vec3>& members = lloyd_size < n ? lloyd : logs;
    std::vector<uint16_t> index(members.size(), 0), before;
    std::vector<Vec3> sums;
    std::vector<uint32_t> counts;
    for (int it = 0; it < max_iterations; ++it) {
      before = index;
      assign_all(members, centers, index, threads);
      if (it > 0 && index == before) break;
      sums.assign(centers.size(), Vec3::Zero());
      counts.assign(centers.size(), 0);
      for (size_t i = 0; i < members.size(); ++i) {
        sums[index[i]] += members[i];
        ++counts[index[i]];
      }
      for (size_t c = 0; c < centers.size(); ++c)
        if (counts[c]) centers[c] = sums[c] / static_cast<double>(counts[c]);  // an empty class keeps its centre
    }
  }
  // Numbered by size (σ1 ascending, then σ2, σ3, in log space; `distinct`
  // is in that order already): a view's classes then go in pieces whose
  // neighbours differ little (docs/protocol.md "Coded batches"), and the
  // numbering no longer depends on the seeding's order.
  if (distinct.size() > k) std::sort(centers.begin(), centers.end(), less);
  centers_.resize(centers.size());
  for (size_t c = 0; c < centers.size(); ++c) {
    centers_[c] = Vec3::Zero();
    for (int d = 0; d < dims; ++d) centers_[c][d] = std::exp(centers[c][d]);
  }
  tree_ = std::make_unique<KdTree>(log_centers_);
}

Vec3 SigmaClasses::log_of(const Vec3& tuple) const {
  Vec3 l = Vec3::Zero();
  for (int d = 0; d < dims_; ++d) l[d] = std::log(tuple[d]);
  return l;
}

uint16_t SigmaClasses::assign(const Vec3& tuple, double* log_error2) const {
  if (!tree_) return 0;  // fitted to nothing
  const Vec3 l = log_of(tuple);
  const uint32_t c = tree_->nearest(l, uint32_t{0});
  if (log_error2) *log_error2 = (l - log_centers_[c]).squaredNorm();
  return static_cast<uint16_t>(c);
}

SignedSigmaClasses::SignedSigmaClasses(const std::vector<Vec3>& sample, int dims, int max_classes, int max_iterations,
                                       int threads)
    : dims_(dims) {
  std::vector<Vec3> by[kPatterns];
  for (const Vec3& t : sample) by[pattern(t)].push_back(t.cwiseAbs());
  // Each pattern's share of the budget: its count's, at least one class.
  const size_t n = sample.size();
  const int budget = std::max(1, max_classes);
  int k[kPatterns] = {}, total = 0;
  double share[kPatterns] = {};
  for (int p = 0; p < kPatterns; ++p) {
    if (by[p].empty()) continue;
    share[p] = static_cast<double>(budget) * static_cast<double>(by[p].size()) / static_cast<double>(n);
    k[p] = std::max(1, static_cast<int>(share[p]));
    total += k[p];
  }
  while (n > 0 && total < budget) {  // the rest to the largest remainders (ties: the lower pattern)
    int most = -1;
    for (int p = 0; p < kPatterns; ++p)
      if (!by[p].empty() && (most < 0 || share[p] - k[p] > share[most] - k[most])) most = p;
    ++k[most];
    ++total;
  }
  while (total > budget) {  // the largest share gives one back (ties: the lower pattern)
    int largest = 0;
    for (int p = 1; p < kPatterns; ++p)
      if (k[p] > k[largest]) largest = p;
    --k[largest];
    --total;
  }
  for (int p = 0; p < kPatterns; ++p) {
    if (k[p] == 0) continue;
    parts_[p] = std::make_unique<SigmaClasses>(by[p], dims, k[p], max_iterations, threads);
    first_[p] = static_cast<uint16_t>(centers_.size());
    for (Vec3 c : parts_[p]->centers()) {
      for (int d = 0; d < dims; ++d)
        if (p & (1 << d)) c[d] = -c[d];
      centers_.push_back(c);
    }
  }
}

int SignedSigmaClasses::pattern(const Vec3& tuple) const {
  int p = 0;
  for (int d = 0; d < dims_; ++d)
    if (tuple[d] < 0) p |= 1 << d;
  return p;
}

uint16_t SignedSigmaClasses::assign(const Vec3& tuple, double* log_error2) const {
  // Its own pattern's classes, or the pattern with classes whose signs differ
  // from its in the fewest components (ties: the lower pattern).
  const int own = pattern(tuple);
  int best = -1;
  for (int p = 0; p < kPatterns; ++p) {
    if (!parts_[p]) continue;
    if (best < 0 || __builtin_popcount(static_cast<unsigned>(p ^ own)) < __builtin_popcount(static_cast<unsigned>(best ^ own)))
      best = p;
  }
  if (best < 0) return 0;  // fitted to nothing
  return static_cast<uint16_t>(first_[best] + parts_[best]->assign(tuple.cwiseAbs(), log_error2));
}

Classification classify_sigmas(const std::vector<Vec3>& tuples, int dims, int max_classes, int max_iterations,
                               int threads) {
  Classification out;
  const size_t n = tuples.size();
  out.index.assign(n, 0);
  if (n == 0) return out;
  const SigmaClasses classes(tuples, dims, max_classes, max_iterations, threads);
  std::vector<double> err2(n);
  parallel_for(n, threads, 1024, [&](size_t i) { out.index[i] = classes.assign(tuples[i], &err2[i]); });
  double err = 0;
  for (size_t i = 0; i < n; ++i) err += err2[i];
  out.rms_log_error = std::sqrt(err / static_cast<double>(n));
  out.centers = classes.centers();
  return out;
}

}  // namespace stipple
