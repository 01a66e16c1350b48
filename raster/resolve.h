// stipple raster — the screen-space resolve: what the point squares leave
// wrong in a finished frame, fixed in one pass over it (docs/results.md,
// "The resolve").
//
// Points drawn as squares of 2 px leave three faults a mesh of the same scan
// does not have: pinholes (uncovered pixels inside the surface, black where
// it is lit), a fringe (the squares reach about a pixel beyond the surface's
// silhouette) and blotches (neighbouring nodes' shading differs in steps).
// Against the scan's own picture the fringe alone is 40-60 % of the squared
// error. The resolve, on the frame's coverage (which pixels a point wrote),
// in three 3 x 3 steps:
//
//   1. fill:  an uncovered pixel with at least 6 of its 8 neighbours covered
//             becomes covered, with their mean colour (a straight silhouette
//             edge gives an outside pixel at most 3, a corner 5: the
//             silhouette never grows);
//   2. trim:  a covered pixel with an uncovered pixel among its 8
//             neighbours (after the fill) is cleared — the fringe; beyond
//             the frame counts as covered, so a surface running off the
//             screen is not trimmed (8 neighbours measured better than 4:
//             docs/results.md) — except a pixel of an isolated speck (at
//             most 3 covered neighbours), so that nodes seen closer than
//             their points cover, and sparse scans, stay dots instead of
//             vanishing;
//   3. blend: every pixel left covered takes the mean of the covered
//             pixels of its 3 x 3 block (after the fill).
//
// Means are of the channels as the frame stores them — 8 bits each in
// RGB888 frames, RGB565's 5, 6 and 5 bits in those — rounded half up.
// Integer only, a row at a time through a ring of rows (the frame is
// rewritten in place), no allocation: `resolve_scratch_bytes` for the rows,
// the coverage bitmap is the caller's (`coverage_bytes`; row-major, one bit a
// pixel, LSB first, rows of coverage_row_bytes). The same bytes on every
// platform: the means are rounded by a reciprocal table, not by division.
#pragma once

#include <cstddef>
#include <cstdint>

#include "raster/point_raster.h"

namespace stipple {

inline size_t coverage_row_bytes(uint16_t width) { return (size_t{width} + 7) / 8; }
inline size_t coverage_bytes(uint16_t width, uint16_t height) { return coverage_row_bytes(width) * height; }
// Seven rows of a pixel's lanes (8 bytes in RGB888 frames, 4 in RGB565):
// three as drawn, three filled, one empty.
inline size_t resolve_scratch_bytes(uint16_t width, PixelFormat format) {
  return 7 * (format == PixelFormat::kRgb565 ? 4 : 8) * size_t{width};
}

// Resolves `frame` (height rows of `stride` bytes in `format`) in place.
// `scratch` is 8-byte aligned and resolve_scratch_bytes(width, format) long.
void resolve_frame(uint8_t* frame, size_t stride, PixelFormat format, uint16_t width, uint16_t height,
                   const uint8_t* coverage, uint32_t clear_rgb, void* scratch);

}  // namespace stipple
