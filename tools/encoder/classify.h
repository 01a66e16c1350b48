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
#include <vector>

#include "tools/scan/point_cloud.h"

namespace stipple {

struct Classification {
  std::vector<Vec3> centers;   // linear units (exp of the log-space centroid); unused dims 0
  std::vector<uint16_t> index;  // class of each input tuple
  double rms_log_error = 0;    // RMS of ||log(sigma) - log(center)|| over the inputs
};

// `tuples`: positive values, `dims` (2 or 3) leading components used.
Classification classify_sigmas(const std::vector<Vec3>& tuples, int dims, int max_classes, int max_iterations = 20,
                               int threads = 2);

}  // namespace stipple
