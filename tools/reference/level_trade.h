// stipple host — the size/accuracy trade of a model's tree levels (TOG05
// Fig. 19a): per level's cut, the bits per original point a client receives
// and the PSNR of points regenerated from it against the scan. Shared by
// `stipple levels` (one model) and `stipple rd` (encoder settings).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "tools/reference/spg_model.h"
#include "tools/scan/kdtree.h"
#include "tools/scan/point_cloud.h"

namespace stipple {

struct LevelPoint {
  int level = 0;
  size_t nodes = 0;
  double bits_per_point = 0;  // the cut's records plus the startup (header and class tables)
  double coded_bits_per_point = 0;  // the same with the records entropy-coded (coded_cut_bytes); 0: not measured
  double psnr_one_sided = 0, psnr_symmetric = 0, hausdorff = 0;
};

// Measures `levels` (each level's cut: the nodes at that depth and the
// leaves above it). False with a message when a cut would generate more
// points than this host's memory allows. `progress(i)` before level i.
// With `file` (the model's bytes, as decoded), each cut's coded bits too.
bool measure_levels(const DecodedModel& model, const PointCloud& original, const KdTree& original_tree,
                    const std::vector<int>& levels, std::vector<LevelPoint>& out, std::string& error,
                    const std::function<void(size_t)>& progress = {}, const std::vector<uint8_t>* file = nullptr);

}  // namespace stipple
