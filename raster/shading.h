// stipple raster — Lambert and specular shading through tables.
//
// A sampled normal n is the exponential map of a 2-D Gaussian offset
// (alpha, beta) = (sigma_n1 g0, sigma_n2 g1) about the node's mean normal n0
// in its tangent frame (t1, t2) (docs/sampling.md):
//   n = cos(theta) n0 + sinc(theta) (alpha t1 + beta t2),  theta^2 = alpha^2 + beta^2,
// so for any fixed direction L
//   L.n = cos(theta) (L.n0) + sinc(theta) (g0 sigma_n1 L.t1 + g1 sigma_n2 L.t2).
// The three dot products are per node; per point the client needs theta^2,
// one lookup of (cos, sinc) — both smooth functions of theta^2 — and three
// products. The intensity tables then map L.n (Q14) to a Q8 factor:
//   diffuse(l)  = ambient + (1 - ambient) max(0, l)        (Lambert)
//   specular(h) = 255 strength max(0, h)^shininess          (Blinn, h = H.n; 8-bit levels added)
// Light and half vector are given in camera space; the client rotates them
// into the model each frame. All tables are built at init with integer code.
#pragma once

#include <cstddef>
#include <cstdint>

namespace stipple {

struct Lighting {
  int16_t light_q14[3] = {-4096, -6144, -14336};  // towards the light, camera space (x right, y down, z forward)
  uint16_t ambient_q8 = 64;                       // 0.25
  uint16_t specular_q8 = 64;                      // 0 turns specular off
  uint8_t shininess = 16;                         // 1 .. 64
};

inline constexpr int kCosSincEntries = 2048;  // theta^2 in [0, 16), steps of 2^-7
inline constexpr int kCosSincShift = 17;      // theta^2 in Q24 -> index
inline constexpr int kIntensityEntries = 257; // l in [-1, 1], steps of 2^-7

struct CosSincQ14 {
  int16_t cos, sinc;
};

struct ShadingTables {
  CosSincQ14 cos_sinc[kCosSincEntries];
  uint16_t diffuse[kIntensityEntries];   // Q8
  uint16_t specular[kIntensityEntries];  // 8-bit levels added to each channel
  int32_t light_q14[3];                  // normalized, camera space
  int32_t half_q14[3];                   // normalized (light + view), camera space
};

// Fills the tables. Returns false for a zero light vector or a shininess outside 1..64.
[[nodiscard]] bool build_shading_tables(const Lighting& lighting, ShadingTables* out);

// Table index of l in Q14 ([-16384, 16384]).
inline int intensity_index(int32_t l_q14) {
  const int32_t i = (l_q14 + 16384 + 64) >> 7;
  return i < 0 ? 0 : i > kIntensityEntries - 1 ? kIntensityEntries - 1 : i;
}

}  // namespace stipple
