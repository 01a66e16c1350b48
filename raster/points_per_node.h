// stipple raster — how many points a node gets (TOG05 Table 1).
//
// A node's projection is summarized by its screen covariance
// S = M M^T (M: the 2 x 3 affine projection of its sigma-scaled axes, in
// 1/16 px), in 1/256 px^2: a = S_xx, b = S_xy, c = S_yy. Two integer
// indices, both cheap (bit length and one more bit):
//   size    t = H(a + c)                       half-octaves of sigma1^2 + sigma2^2
//   aspect  d = 2 H(a + c) - H(4 (a c - b^2))  half-octaves of the elongation
// where H(x) = 2 floor(log2 x) + (the bit below the top one). The table gives,
// for each (t, d), point size and sample source, the smallest number of
// points whose squares cover 95 % of the pixels inside the node's 2-sigma
// ellipse — the area a node stands for — measured by `stipple ppn-table` with
// this rasterizer and the client's Gaussian tables (docs/points_per_node.md).
// The table is generated into ppn_table.inc; a test re-measures it.
#pragma once

#include <cstddef>
#include <cstdint>

#include "core/gaussian_table.h"

namespace stipple {

inline constexpr int kPpnSizes = 41;    // t = 0 .. 40 (t >= 40: sigma beyond ~16 px)
inline constexpr int kPpnAspects = 24;  // d = 0 .. 23
inline constexpr int kPpnPointSizes = 3;
inline constexpr uint32_t kPpnMaxCount = 1024;  // the measurement's ceiling

struct PpnIndex {
  uint8_t size = 0, aspect = 0;
};

using PpnTable = uint16_t[kPpnSizes][kPpnAspects];

// H(x): 2 floor(log2 x) + the second-highest bit; 0 for x <= 1.
int half_octave(uint64_t x);

// Index of a screen covariance (1/256 px^2; a, c >= 0, a c >= b^2).
PpnIndex ppn_index(int64_t a, int64_t b, int64_t c);

// The measured table for a source and point size (1..3; clamped).
const PpnTable& ppn_table(GaussianSource source, int point_size);

// Points for a node: the table's count scaled by quality (Q8, 256 = as
// measured), rounded, clamped to [1, max_count].
inline uint32_t points_per_node(const PpnTable& table, PpnIndex i, uint32_t quality_q8, uint32_t max_count) {
  const uint32_t n = (table[i.size][i.aspect] * quality_q8 + 128) >> 8;
  return n < 1 ? 1 : n > max_count ? max_count : n;
}

}  // namespace stipple
