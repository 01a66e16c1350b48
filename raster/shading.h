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

#include "core/fixed_range.h"

namespace stipple {

struct Lighting {
  int16_t light_q14[3] = {-4096, -6144, -14336};  // towards the light, camera space (x right, y down, z forward)
  uint16_t ambient_q8 = 64;                       // 0.25
  uint16_t specular_q8 = 64;                      // 0 turns specular off
  uint8_t shininess = 16;                         // 1 .. 64
};

inline constexpr int kCosSincEntries = 2048;  // theta^2 in [0, 16), steps of 2^-7
inline constexpr int kCosSincShift = 17;      // theta^2 in Q24 -> index
// The cells an angle pair reaches: each angle within 4 rad (Q12: |.| <=
// 2^14, clamp_angle_q12's bound), so theta^2 <= 2^29 in Q24, cell <= 4096.
// Cells past kCosSincEntries repeat its last entry — the table ends at
// theta^2 = 16 — so the scalar loops index it without a clamp.
inline constexpr int kCosSincCells = ((2 << 28) >> kCosSincShift) + 1;
// The intensity tables: l in steps of 2^-7, entry kIntensityZero at l = 0.
// [-1, 1] takes 257 entries; kIntensityPad more on either side repeat
// the ends (l <= -1 and l >= 1 shade alike), so the scalar point loops
// index them without a clamp: a sampled normal's L.n stays within 1.26
// (lit_entry_q26), inside the padded [-1.37, 1.37].
inline constexpr int kIntensityPad = 48;
inline constexpr int kIntensityEntries = 257 + 2 * kIntensityPad;
inline constexpr int kIntensityZero = kIntensityPad + 128;  // the entry of l = 0

// 4-aligned: the scalar loops on 32-bit ARM load an entry as one word.
struct alignas(4) CosSincQ14 {
  int16_t cos, sinc;
};

// Reciprocal square roots of m = 256 .. 1023: round(2^19 / sqrt(m)), for
// normalizing a vector without a square root or a division per use
// (rsqrt_shift).
inline constexpr int kRsqrtEntries = 768;

// The scalar point loops on 32-bit ARM read `specular` and `cos_sinc` a
// point each from one base register: the first as 32-bit words at offset 0
// (one LDR with a scaled index, where a uint16 entry farther in took four
// instructions), the second kSpecularWords words on, an ARM immediate (one
// ADD to the index; 353 took two).
inline constexpr int kSpecularWords = 384;
static_assert(kSpecularWords >= kIntensityEntries);
struct ShadingTables {
  uint32_t specular[kSpecularWords];  // 8-bit levels added to each channel; kIntensityEntries used
  CosSincQ14 cos_sinc[kCosSincCells];    // [kCosSincEntries, kCosSincCells): the last entry again
  uint16_t rsqrt[kRsqrtEntries];
  uint16_t diffuse[kIntensityEntries];   // Q8: diffuse_q8(ambient_q8, entry)
  int32_t light_q14[3];                  // normalized, camera space
  int32_t half_q14[3];                   // normalized (light + view), camera space
  int32_t ambient_q8;                    // Lighting's, at most 256
};

// The diffuse table's entry i, l = (i - kIntensityZero) / 128, for an
// ambient term `ambient_q8` (at most 256): ambient + (1 - ambient)
// clamp(l, 0, 1) in Q8, from lit_q7 = clamp(i - kIntensityZero, 0, 128).
// The AVX2 lanes compute it rather than gather it
// (raster/point_kernel_avx2.cpp).
constexpr int32_t diffuse_q8(int32_t ambient_q8, int32_t lit_q7) {
  return ambient_q8 + (((256 - ambient_q8) * lit_q7 + 64) >> 7);
}

// Fills the tables. Returns false for a zero light vector or a shininess outside 1..64.
[[nodiscard]] bool build_shading_tables(const Lighting& lighting, ShadingTables* out);

// v * 2^14 / sqrt(s2) for s2 >= 1, from the table: s2 = m 4^k with m in
// [256, 1024), so 1 / sqrt(s2) = rsqrt[m - 256] 2^-19 2^-k; returns the
// multiplier and the right shift that apply it (v * mul >> shift), within
// 1/512 of the exact quotient. Integer only, no division.
struct RsqrtScale {
  uint32_t mul;
  int shift;
};
inline RsqrtScale rsqrt_scale(const ShadingTables& t, uint64_t s2) {
  const int e = 63 - __builtin_clzll(s2);  // floor log2, s2 >= 1
  const int k = (e - 8) >= 0 ? (e - 8) / 2 : -((9 - e) / 2);  // s2 / 4^k in [256, 1024)
  const uint64_t m = k >= 0 ? s2 >> (2 * k) : s2 << (-2 * k);
  return RsqrtScale{t.rsqrt[m - 256], 5 + k};  // 2^14 / 2^19 / 2^k
}

// Table index of l in Q14: (l + kIntensityOffsetQ14) >> 7, clamped — l
// rounded to the nearest 2^-7, the pad entries below it.
inline constexpr int32_t kIntensityOffsetQ14 = (kIntensityZero << 7) + 64;
inline int intensity_entry(int32_t i) { return i < 0 ? 0 : i > kIntensityEntries - 1 ? kIntensityEntries - 1 : i; }
inline int intensity_index(int32_t l_q14) { return intensity_entry((l_q14 + kIntensityOffsetQ14) >> 7); }
// The unclamped index of l in Q26, whose Q14 value is l_q26 >> 12: floors
// of power-of-two divisions compose, so (l_q26 + kIntensityOffsetQ14 2^12)
// >> 19 is intensity_index(l_q26 >> 12) exactly, one shift instead of two —
// for |l| < 1 + (kIntensityPad + 1/2) / 128 (|l_q26| < kIntensityOffsetQ26),
// where the pads make the clamp needless: a sampled normal's L.n and H.n,
// which stay within 1.26 (the cos/sinc table's (cos, sinc theta) has norm at
// most 1.2532 for any two angles within 4 rad, tested cell by cell in
// Shading.IntensityPadCoversSampledNormals; docs/fixed_point.md, "Shading").
// lit_entry takes the sum with its offset (a multiply-accumulate chain may
// start at it), lit_entry_q26 l itself.
inline constexpr int32_t kIntensityOffsetQ26 = kIntensityOffsetQ14 << 12;
inline int lit_entry(int32_t biased_q26) {
  const int32_t i = biased_q26 >> 19;
#if STIPPLE_CHECK_RANGES
  if (i < 0 || i >= kIntensityEntries) __builtin_trap();
#endif
  return i;
}
inline int lit_entry_q26(int32_t l_q26) { return lit_entry(l_q26 + kIntensityOffsetQ26); }

}  // namespace stipple
