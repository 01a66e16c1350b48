// stipple host — measuring the points-per-node table (TOG05 Table 1) with
// the client's own rasterizer and Gaussian tables.
//
// For a node whose projection has screen sigmas (s1, s2) px, n points are
// the first n entries of the 3-D Gaussian table seen face-on,
// (s1 g0, s2 g1) rotated and shifted, drawn as point_size squares by
// PointRaster. Coverage is the fraction of the pixels whose centres lie in
// the node's 2-sigma ellipse — the disc a uniform patch with that sigma
// fills — that receive a point, averaged over `trials` placements (rotation
// and sub-pixel offset; deterministic). The count for (s1, s2) is the
// smallest n whose coverage reaches the target, found by doubling and then
// bisection, capped at kPpnMaxCount. A table entry (t, d) is the largest count
// over a grid of (s1, s2) pairs that fall into that index (8 steps per octave
// of s1, 4 per octave of s2 / s1), so the table errs on the side of coverage;
// entries no pair reaches take their smaller neighbour's count.
// docs/points_per_node.md explains the choices and lists the measured table.
#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include "core/gaussian_table.h"
#include "raster/points_per_node.h"

namespace stipple {

struct PpnMeasureOptions {
  GaussianSource source = GaussianSource::kSobol;
  int point_size = 1;
  double coverage = 0.95;
  int trials = 8;
  uint32_t max_count = kPpnMaxCount;
};

// Mean coverage of the 2-sigma ellipse by the first n points.
double ppn_coverage(double sigma1, double sigma2, uint32_t n, const PpnMeasureOptions& options);

// Smallest n reaching the coverage target (max_count if none does).
uint32_t ppn_points_needed(double sigma1, double sigma2, const PpnMeasureOptions& options);

// The whole table; `progress` (may be empty) gets a fraction in [0, 1].
void measure_ppn_table(const PpnMeasureOptions& options, PpnTable& out,
                       const std::function<void(double)>& progress = {});

// C++ initializer text of the full [source][point size][t][d] table, as
// raster/ppn_table.inc holds it.
std::string ppn_table_source(const PpnTable tables[2][kPpnPointSizes], const PpnMeasureOptions& options);

}  // namespace stipple
