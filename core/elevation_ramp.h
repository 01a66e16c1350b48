// stipple core — the colour ramp of colour by elevation, shared by every
// client (the fixed-point renderer per node, the GL client in its shader),
// so that both draw a height the same colour. Integer only.
#pragma once

#include <cstdint>

namespace stipple {

// Colour by elevation: t = 0 (low) .. 255 (high) along a ramp through five
// colours — blue, cyan, green, yellow, red, the ramp LiDAR viewers use
// (ColorBrewer's RdYlBu reversed, with a green middle) — 0xRRGGBB.
inline constexpr uint32_t kElevationRamp[5] = {0x2C7BB6, 0x00A6CA, 0x7AC943, 0xFDAE2D, 0xD7191C};
constexpr uint32_t elevation_rgb(uint32_t t) {
  const uint32_t i = t >> 6, w = t & 63u;  // four spans of 64 steps
  if (i >= 4) return kElevationRamp[4];
  uint32_t out = 0;
  for (int shift = 16; shift >= 0; shift -= 8) {
    const uint32_t a = (kElevationRamp[i] >> shift) & 0xFFu, b = (kElevationRamp[i + 1] >> shift) & 0xFFu;
    out |= ((a * (64u - w) + b * w + 32u) >> 6) << shift;
  }
  return out;
}

}  // namespace stipple
