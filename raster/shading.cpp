// stipple raster — shading tables. See shading.h.
#include "raster/shading.h"

#include "core/fixed_trig.h"
#include "core/gaussian_table.h"

namespace stipple {
namespace {

// v / |v| in Q14, v in Q14 (not zero).
bool normalize_q14(const int16_t in[3], int32_t out[3]) {
  const uint64_t sq = static_cast<uint64_t>(int64_t{in[0]} * in[0] + int64_t{in[1]} * in[1] + int64_t{in[2]} * in[2]);
  const uint64_t len = isqrt64(sq << 28);  // |v| in Q28
  if (len == 0) return false;
  for (int k = 0; k < 3; ++k) out[k] = static_cast<int32_t>((int64_t{in[k]} << 28) / static_cast<int64_t>(len));
  return true;
}

}  // namespace

bool build_shading_tables(const Lighting& lighting, ShadingTables* out) {
  if (lighting.shininess < 1 || lighting.shininess > 64) return false;
  if (!normalize_q14(lighting.light_q14, out->light_q14)) return false;
  // Half vector between the light and the direction to the eye, (0, 0, -1).
  int16_t h[3];
  for (int k = 0; k < 3; ++k) h[k] = static_cast<int16_t>((out->light_q14[k] + (k == 2 ? -16384 : 0)) / 2);
  if (!normalize_q14(h, out->half_q14)) {  // light exactly behind the model
    out->half_q14[0] = out->half_q14[1] = 0;
    out->half_q14[2] = -16384;
  }

  // cos and sinc at the middle of each theta^2 cell (Q24 cell = 2^17).
  constexpr int64_t kTwoPiQ24 = 105414357;  // 2 pi * 2^24, rounded
  for (int i = 0; i < kCosSincEntries; ++i) {
    const uint64_t theta_sq_q48 = (static_cast<uint64_t>(2 * i + 1) << (kCosSincShift - 1)) << 24;
    const int64_t theta_q24 = static_cast<int64_t>(isqrt64(theta_sq_q48));
    // Binary angle theta / 2 pi * 2^32.
    const uint32_t angle = static_cast<uint32_t>((static_cast<uint64_t>(theta_q24) << 32) / kTwoPiQ24);
    const SinCosQ14 sc = sincos_q14(angle);
    out->cos_sinc[i].cos = static_cast<int16_t>(sc.cos);
    out->cos_sinc[i].sinc = static_cast<int16_t>((int64_t{sc.sin} << 24) / theta_q24);
  }
  for (int i = kCosSincEntries; i < kCosSincCells; ++i) out->cos_sinc[i] = out->cos_sinc[kCosSincEntries - 1];

  // Reciprocal square roots: round(2^19 / sqrt(m)) = round(sqrt(2^38 / m)),
  // the square root of the rounded-down quotient, corrected to the nearest.
  for (int i = 0; i < kRsqrtEntries; ++i) {
    const uint64_t q = (uint64_t{1} << 38) / static_cast<uint64_t>(256 + i);
    uint64_t r = isqrt64(q);
    if ((r + 1) * (r + 1) - q < q - r * r) ++r;
    out->rsqrt[i] = static_cast<uint16_t>(r);
  }

  // Intensities: l = (i - kIntensityZero) / 128, taken within [-1, 1].
  const int32_t ambient = lighting.ambient_q8 > 256 ? 256 : lighting.ambient_q8;
  out->ambient_q8 = ambient;
  for (int i = 0; i < kIntensityEntries; ++i) {
    const int32_t l_q7 = i - kIntensityZero;  // Q7
    const int32_t lit = l_q7 < 0 ? 0 : l_q7 > 128 ? 128 : l_q7;
    out->diffuse[i] = static_cast<uint16_t>(diffuse_q8(ambient, lit));
    int64_t p = int64_t{1} << 30;  // Q30 power of max(0, l)
    for (int s = 0; s < lighting.shininess; ++s) p = (p * lit) >> 7;
    out->specular[i] = static_cast<uint32_t>((int64_t{lighting.specular_q8} * 255 * p + (int64_t{1} << 37)) >> 38);
  }
  for (int i = kIntensityEntries; i < kSpecularWords; ++i) out->specular[i] = 0;  // unread: the layout's room
  return true;
}

}  // namespace stipple
