// stipple raster — the tile pass's point loop in AVX2 lanes (x86-64 CPUs
// that have it, chosen at run time: raster/point_kernel_avx2.cpp is the one
// file built with -mavx2).
//
// Where the SSE2 and NEON loops take one node at a time, four of its samples
// in the lanes (a node of 3 points leaves a lane idle, and its constants are
// set up for those 3), this one streams the tile's points: lane k holds
// sample j_k of node n_k, the nodes' constants gathered per lane from the
// TileNodes arrays and the samples from the paired tables, so all 8 lanes
// work whatever the nodes' counts. The formula and its bounds are
// point_kernel.h's; the bytes are the scalar loop's
// (tests/portable/point_kernel_test.cpp).
#pragma once

#include <cstddef>
#include <cstdint>

#include "raster/point_kernel.h"

namespace stipple {
namespace avx2 {

#if defined(__x86_64__) || defined(__i386__)
inline constexpr bool kBuilt = true;
// Whether this CPU runs the AVX2 loops.
inline bool supported() {
  return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("popcnt") && __builtin_cpu_supports("bmi") &&
         __builtin_cpu_supports("bmi2");
}
#else
inline constexpr bool kBuilt = false;
inline bool supported() { return false; }
#endif

// Draws the `n` tile nodes listed in `list` into the tile's words (as
// draw_tile_node does for each). `lanes` is scratch of 32 words.
template <PointNormals kNormals, bool kColorPoints, bool kSpecular, class Word>
void draw_tile(const TileNodes& nodes, const uint32_t* list, uint32_t n, const PointTables& t, int size, Word* words,
               int tile_log2, int px0, int py0);

// The tile pass's own loops (PointRaster::draw): a tile's words cleared,
// and a row of them written out as the frame's pixels — RGB888 (3 bytes
// R, G, B) or RGB565 (little-endian) — exactly the bytes of the scalar loops.
void clear_words(uint64_t* words, size_t count, uint64_t word);
void clear_words(uint32_t* words, size_t count, uint32_t word);
void store_row(const uint64_t* row, int pixels, uint8_t* out);
void store_row(const uint32_t* row, int pixels, uint8_t* out);

}  // namespace avx2
}  // namespace stipple
