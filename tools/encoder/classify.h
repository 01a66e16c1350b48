// stipple host — sigma classification (TOG05 §5): k-means of sigma tuples in
// log space, so a class's error is relative (what the eye sees), and a node
// stores only its class index.
//
// Scales to millions of tuples: k-means++ seeding on a deterministic sample
// of at most 4k tuples, then Lloyd iterations on a deterministic sample of at
// most max(16k, 16384) tuples (every tuple below that), then one assignment
// of every tuple; nearest-centre queries go through a kd-tree of the centres
// (O(log k) each, never k).
// If there are at most k distinct tuples, each becomes its own class exactly.
// Deterministic: a fixed-seed generator, ties to the lower index.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "tools/scan/kdtree.h"
#include "tools/scan/point_cloud.h"

namespace stipple {

struct Classification {
  std::vector<Vec3> centers;   // linear units (exp of the log-space centroid); unused dims 0
  std::vector<uint16_t> index;  // class of each input tuple
  double rms_log_error = 0;    // RMS of ||log(sigma) - log(center)|| over the inputs
};

// Classes fitted to `sample` (what classify_sigmas does before its
// assignment), then any tuple assigned to its nearest class, one at a time:
// the out-of-core encoder fits them to a sample of the nodes and assigns
// every node while it writes the file. `assign` is thread-safe.
class SigmaClasses {
 public:
  SigmaClasses(const std::vector<Vec3>& sample, int dims, int max_classes, int max_iterations = 20, int threads = 2);
  SigmaClasses(const SigmaClasses&) = delete;
  SigmaClasses& operator=(const SigmaClasses&) = delete;
  const std::vector<Vec3>& centers() const { return centers_; }  // linear units; unused dims 0
  // The nearest class (ties to the lower index) and, when asked, the
  // squared log-space distance to it.
  uint16_t assign(const Vec3& tuple, double* log_error2 = nullptr) const;

 private:
  Vec3 log_of(const Vec3& tuple) const;
  int dims_;
  std::vector<Vec3> log_centers_, centers_;
  std::unique_ptr<KdTree> tree_;  // of log_centers_
};

// Classes of tuples whose components may be negative (sigma_n with the
// curvature's sign): each sign pattern gets classes of its own, fitted in log
// space to the magnitudes, so no class crosses a sign. The patterns share
// max_classes by their counts in the sample (one at least each while the
// budget lasts; a pattern left without classes, or absent from the sample,
// takes the nearest pattern's, its sign lost). Positive tuples alone give
// SigmaClasses' classes exactly.
class SignedSigmaClasses {
 public:
  SignedSigmaClasses(const std::vector<Vec3>& sample, int dims, int max_classes, int max_iterations = 20, int threads = 2);
  const std::vector<Vec3>& centers() const { return centers_; }  // signed, linear units
  uint16_t assign(const Vec3& tuple, double* log_error2 = nullptr) const;

 private:
  static constexpr int kPatterns = 8;
  int pattern(const Vec3& tuple) const;
  int dims_;
  std::unique_ptr<SigmaClasses> parts_[kPatterns];
  uint16_t first_[kPatterns] = {};
  std::vector<Vec3> centers_;
};

// `tuples`: positive values, `dims` (2 or 3) leading components used.
Classification classify_sigmas(const std::vector<Vec3>& tuples, int dims, int max_classes, int max_iterations = 20,
                               int threads = 2);

}  // namespace stipple
