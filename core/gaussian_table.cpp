// stipple core — fixed-point Gaussian tables. See gaussian_table.h.
#include "core/gaussian_table.h"

#include "core/fixed_trig.h"
#include "core/sobol.h"

namespace stipple {
namespace {

constexpr int64_t kTwoLn2Q30 = 1488522236;    // round(2 ln 2 * 2^30)
constexpr int64_t kSqrtThreeHalvesQ30 = 1315059792;  // round(sqrt(3/2) * 2^30)

uint32_t xorshift32(uint32_t x) {
  x ^= x << 13;
  x ^= x >> 17;
  x ^= x << 5;
  return x;
}

int16_t to_q12(int64_t v_q24) {
  const int64_t r = (v_q24 + (v_q24 >= 0 ? (1 << 11) : -(1 << 11))) / (1 << 12);
  return static_cast<int16_t>(r > kGaussianClip ? kGaussianClip : r < -kGaussianClip ? -kGaussianClip : r);
}

}  // namespace

// tau^2 = -2 ln r0 = 2 ln 2 (33 - log2(2u + 1)).
int64_t box_muller_radius_q24(uint32_t u, bool three_d) {
  const int64_t t = (int64_t{33} << 24) - log2_q24(2 * static_cast<uint64_t>(u) + 1);  // Q24, in [0, 33]
  const int64_t tau2 = (t * kTwoLn2Q30) >> 30;                                          // Q24, <= 22.9 * 2^24
  int64_t tau = static_cast<int64_t>(isqrt64(static_cast<uint64_t>(tau2) << 24));       // Q24, < 2^27
  if (three_d) tau = (tau * kSqrtThreeHalvesQ30) >> 30;
  const int64_t clip = int64_t{7} << 23;  // 3.5
  return tau > clip ? clip : tau;
}

int64_t log2_q24(uint64_t x) {
  if (x == 0) return 0;
  int n = 63;
  while (((x >> n) & 1u) == 0) --n;
  // y = x / 2^n in [1, 2), Q30; then one fraction bit per squaring.
  uint64_t y = n >= 30 ? x >> (n - 30) : x << (30 - n);
  int64_t result = static_cast<int64_t>(n) << 24;
  for (int bit = 23; bit >= 0; --bit) {
    y = (y * y) >> 30;  // Q30 squared stays below 2^62
    if (y >= (uint64_t{2} << 30)) {
      y >>= 1;
      result += int64_t{1} << bit;
    }
  }
  return result;
}

uint64_t isqrt64(uint64_t x) {
  uint64_t root = 0, bit = uint64_t{1} << 62;
  while (bit > x) bit >>= 2;
  while (bit != 0) {
    if (x >= root + bit) {
      x -= root + bit;
      root = (root >> 1) + bit;
    } else {
      root >>= 1;
    }
    bit >>= 2;
  }
  return root;
}

void gaussian_uniforms(GaussianSource source, uint32_t sample, uint32_t out[3], int first_dim) {
  if (source == GaussianSource::kSobol) {
    for (int d = 0; d < 3; ++d) out[d] = sobol_u32(sample + 1, first_dim + d);
    return;
  }
  uint32_t x = 0x9E3779B9u ^ ((sample + static_cast<uint32_t>(first_dim) * 0x20000u) * 0x85EBCA6Bu);
  for (int d = 0; d < 3; ++d) {
    x = xorshift32(x == 0 ? 1u : x);
    x = xorshift32(x);
    out[d] = x;
  }
}

void build_gaussian3_table(GaussianSource source, Gaussian3Q12* out, size_t count, int first_dim) {
  for (size_t j = 0; j < count; ++j) {
    uint32_t u[3];
    gaussian_uniforms(source, static_cast<uint32_t>(j), u, first_dim);
    const int64_t tau = box_muller_radius_q24(u[0], true);
    const SinCosQ14 sc = sincos_q14(u[1]);  // 2 pi r1: u is already a binary angle
    // r2 = 2 r - 1 = (2u + 1) / 2^32 - 1, Q31; ring = sqrt(1 - r2^2), Q31.
    const int64_t r2 = static_cast<int64_t>(2 * static_cast<uint64_t>(u[2]) + 1) - (int64_t{1} << 32);  // Q32
    const uint64_t r2sq = static_cast<uint64_t>((r2 >> 1) * (r2 >> 1)) >> 31;                           // Q31
    const int64_t ring = static_cast<int64_t>(isqrt64(((uint64_t{1} << 31) - r2sq) << 31));             // Q31
    const int64_t radial = (tau * ring) >> 31;                                                          // Q24
    out[j].v[0] = to_q12((radial * sc.cos) >> 14);
    out[j].v[1] = to_q12((radial * sc.sin) >> 14);
    out[j].v[2] = to_q12((tau * (r2 >> 1)) >> 31);
  }
}

void build_gaussian2_table(GaussianSource source, Gaussian2Q12* out, size_t count) {
  for (size_t j = 0; j < count; ++j) {
    uint32_t u[2];
    if (source == GaussianSource::kSobol) {
      u[0] = sobol_u32(static_cast<uint32_t>(j) + 1, 3);
      u[1] = sobol_u32(static_cast<uint32_t>(j) + 1, 4);
    } else {
      uint32_t all[3];
      gaussian_uniforms(source, static_cast<uint32_t>(j) + 0x10000u, all);
      u[0] = all[0];
      u[1] = all[1];
    }
    const int64_t tau = box_muller_radius_q24(u[0], false);
    const SinCosQ14 sc = sincos_q14(u[1]);
    out[j].v[0] = to_q12((tau * sc.cos) >> 14);
    out[j].v[1] = to_q12((tau * sc.sin) >> 14);
  }
}

}  // namespace stipple
