// stipple host — geometric error between an original scan and generated points.
//
// For each point of A, the distance to its nearest point of B (kd-tree, exact).
// PSNR = 20 log10(diagonal of the original's bounding box / RMS distance).
// The paper's figure is one-sided, generated -> original: it cannot see holes.
// The symmetric figure takes the worse (larger RMS) of the two directions.
// Hausdorff = the largest nearest-neighbour distance in either direction.
#pragma once

#include <optional>

#include "tools/scan/kdtree.h"
#include "tools/scan/point_cloud.h"

namespace stipple {

struct DirectedDistance {
  double rms = 0, mean = 0, max = 0;
  double normal_rms_deg = -1, normal_mean_deg = -1;  // -1: not measured
  double color_rms = -1;  // RMS RGB distance (0..1 units) to the nearest point's colour; -1: not measured
};

struct CloudMetrics {
  DirectedDistance generated_to_original, original_to_generated;
  double diagonal = 0;
  double psnr_one_sided = 0, psnr_symmetric = 0;
  double hausdorff = 0;
};

// Distances from every point of `from` to its nearest point of `to`. When both
// clouds have normals, also the angle between each point's normal and its
// nearest neighbour's; when both have colours, the RGB distance likewise.
DirectedDistance directed_distance(const PointCloud& from, const PointCloud& to, int threads = 2);
// The same with a kd-tree already built over `to.positions`.
DirectedDistance directed_distance(const PointCloud& from, const PointCloud& to, const KdTree& to_tree,
                                   int threads = 2);

CloudMetrics compare_clouds(const PointCloud& original, const PointCloud& generated, int threads = 2);
// The same with a kd-tree already built over `original.positions`, for
// comparing many generated clouds against one original.
CloudMetrics compare_clouds(const PointCloud& original, const KdTree& original_tree, const PointCloud& generated,
                            int threads = 2);

double psnr(double diagonal, double rms);

}  // namespace stipple
