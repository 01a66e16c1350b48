// stipple raster — the point formula's paired sample tables. See point_kernel.h.
#include "raster/point_kernel.h"

#include "core/arena.h"

namespace stipple {
namespace {

inline uint32_t pair(int16_t lo, int16_t hi) { return static_cast<uint16_t>(lo) | uint32_t{static_cast<uint16_t>(hi)} << 16; }

}  // namespace

size_t point_lane_bytes(uint32_t samples) { return 5 * align8(4 * (size_t{samples} + kLaneSlack)); }

void build_point_lanes(const Gaussian3Q12* position, const Gaussian2Q12* normal, const Gaussian3Q12* color,
                       uint32_t samples, void* storage, PointTables* out) {
  const size_t n = samples + kLaneSlack, stride = align8(4 * n) / 4;
  uint32_t* at = static_cast<uint32_t*>(storage);
  uint32_t *g01 = at, *g2 = at + stride, *n01 = at + 2 * stride, *q01 = at + 3 * stride, *q2 = at + 4 * stride;
  for (size_t j = 0; j < n; ++j) {
    const bool in = j < samples;
    g01[j] = in ? pair(position[j].v[0], position[j].v[1]) : 0;
    g2[j] = in ? pair(position[j].v[2], 0) : 0;
    n01[j] = in && normal ? pair(normal[j].v[0], normal[j].v[1]) : 0;
    q01[j] = in && color ? pair(color[j].v[0], color[j].v[1]) : 0;
    q2[j] = in && color ? pair(color[j].v[2], 0) : 0;
  }
  out->g01 = g01;
  out->g2 = g2;
  out->n01 = n01;
  out->q01 = q01;
  out->q2 = q2;
}

bool build_grey_shades(const ShadingTables& shading, uint32_t rgb, uint32_t* diffuse, uint32_t* shades,
                       uint32_t* shades565) {
  const uint32_t v = rgb & 0xFFu;
  if (((rgb >> 16) & 0xFFu) != v || ((rgb >> 8) & 0xFFu) != v) return false;
  for (int i = 0; i < kIntensityEntries; ++i)
    if (shading.specular[i] > 255) return false;
  for (int i = 0; i < kIntensityEntries; ++i) diffuse[i] = (v * shading.diffuse[i]) >> 8;
  for (uint32_t s = 0; s < kGreyShades; ++s) {
    shades[s] = (s > 255 ? 255u : s) * 0x010101u;
    shades565[s] = rgb565(shades[s]);
  }
  return true;
}

}  // namespace stipple
