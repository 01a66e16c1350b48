// stipple core — tables of Gaussian sample vectors in fixed point (TOG05 §6).
//
// Entry j holds the unit-variance 3-D (or 2-D) sample that the reference
// sampler (tools/reference/sampler.cpp, docs/sampling.md) draws for sample j of a
// node: Sobol point j + 1 (dimensions 0-2; 3-4 for the 2-D normal table)
// through the paper's Box–Muller variant,
//   tau = sqrt(-2 ln r0) * sqrt(3/2) (3-D; unscaled for 2-D), clipped at 3.5;
//   3-D: tau (sqrt(1 - r2^2) cos 2 pi r1, sqrt(1 - r2^2) sin 2 pi r1, r2),
//   2-D: tau (cos 2 pi r1, sin 2 pi r1),
// with r = (u + 1/2) / 2^32 for each 32-bit Sobol coordinate u.
//
// Values are Q12 (int16, 4096 = one sigma; |v| <= 3.5 * 4096 = 14336).
// Generation is integer only — a bit-by-bit log2, an integer square root and
// `sincos_q14` — so the table is the same on every build; it agrees with the
// reference sampler's doubles to within 2 Q12 LSB (tested).
// `GaussianSource::kPseudo` uses a xorshift32 generator instead of Sobol, for
// comparisons; it is not what clients draw with.
#pragma once

#include <cstddef>
#include <cstdint>

namespace stipple {

inline constexpr int32_t kGaussianOne = 1 << 12;        // Q12
inline constexpr int32_t kGaussianClip = 14336;         // 3.5 in Q12

enum class GaussianSource : uint8_t { kSobol, kPseudo };

struct Gaussian3Q12 {
  int16_t v[3];
};
struct Gaussian2Q12 {
  int16_t v[2];
};

// Fills out[0 .. count) with samples 0 .. count-1. No allocation.
// 3-D tables read Sobol dimensions first_dim .. first_dim + 2: 0 for
// positions, kColorSobolDim for colours (the reference sampler's choice).
inline constexpr int kColorSobolDim = 5;
void build_gaussian3_table(GaussianSource source, Gaussian3Q12* out, size_t count, int first_dim = 0);
void build_gaussian2_table(GaussianSource source, Gaussian2Q12* out, size_t count);

// The 32-bit uniform inputs (r0, r1, r2 as 0.32 fractions) of sample j.
void gaussian_uniforms(GaussianSource source, uint32_t sample, uint32_t out[3], int first_dim = 0);

// The Box–Muller radius tau, Q24, of the 0.32 fraction u of
// r0 = (u + 1/2) / 2^32: sqrt(-2 ln r0), times sqrt(3/2) for the 3-D tables,
// clipped at 3.5. Bounded at both ends: u = 0 (r0 = 2^-33, the smallest; the
// unclipped radius would be 6.8) gives exactly 3.5, u = 2^32 - 1 (r0 -> 1)
// under 1.5 Q12 LSB (the square root of one Q24 unit), never a negative or
// a wrapped value.
int64_t box_muller_radius_q24(uint32_t u, bool three_d);

// log2(x) for x >= 1, in Q24. Integer only.
int64_t log2_q24(uint64_t x);
// floor(sqrt(x)).
uint64_t isqrt64(uint64_t x);

}  // namespace stipple
