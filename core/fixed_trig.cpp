// stipple core — integer sine/cosine, angle tables, Q14 frame decoding and
// binary32-to-fixed conversion. See fixed_trig.h.
#include "core/fixed_trig.h"

#include "core/fixed_range.h"

namespace stipple {
namespace {

constexpr int64_t kQ30 = int64_t{1} << 30;
constexpr int64_t kQuarterPiQ30 = 843314857;  // round(pi/4 * 2^30)

// Q30 product, rounded. Operands stay below 2^31 in magnitude, so the int64
// product cannot overflow.
constexpr int64_t mul30(int64_t a, int64_t b) { return (a * b + (int64_t{1} << 29)) >> 30; }

// sin and cos of x in [0, pi/4] (Q30 radians), Taylor series in Horner form:
// the first omitted terms are below 2e-9 (2 Q30 LSB) on that interval.
void sincos_q30(int64_t x, int64_t& s, int64_t& c) {
  const int64_t x2 = mul30(x, x);
  int64_t t = kQ30 - x2 / 72;
  t = kQ30 - mul30(x2, t) / 42;
  t = kQ30 - mul30(x2, t) / 20;
  t = kQ30 - mul30(x2, t) / 6;
  s = mul30(x, t);
  int64_t u = kQ30 - x2 / 90;
  u = kQ30 - mul30(x2, u) / 56;
  u = kQ30 - mul30(x2, u) / 30;
  u = kQ30 - mul30(x2, u) / 12;
  c = kQ30 - mul30(x2, u) / 2;
}

int16_t q30_to_q14(int64_t v) {
  int64_t r = (v + (int64_t{1} << 15)) >> 16;
  if (r > kQ14One) r = kQ14One;
  if (r < -kQ14One) r = -kQ14One;
  return static_cast<int16_t>(r);
}

int16_t clamp_q14(int32_t v) { return static_cast<int16_t>(v > kQ14One ? kQ14One : v < -kQ14One ? -kQ14One : v); }

}  // namespace

SinCosQ14 sincos_q14(uint32_t binary_angle) {
  const uint32_t quadrant = binary_angle >> 30;
  const uint32_t b = binary_angle & 0x3FFFFFFFu;  // angle within the quadrant, 2^30 = pi/2
  int64_t s, c;
  if (b < (1u << 29)) {
    sincos_q30((static_cast<int64_t>(b) * kQuarterPiQ30 + (int64_t{1} << 28)) >> 29, s, c);
  } else {
    int64_t s2, c2;  // pi/2 - beta, in [0, pi/4]
    sincos_q30((static_cast<int64_t>((1u << 30) - b) * kQuarterPiQ30 + (int64_t{1} << 28)) >> 29, s2, c2);
    s = c2;
    c = s2;
  }
  SinCosQ14 out;
  switch (quadrant) {
    case 0: out = {q30_to_q14(s), q30_to_q14(c)}; break;
    case 1: out = {q30_to_q14(c), q30_to_q14(-s)}; break;
    case 2: out = {q30_to_q14(-s), q30_to_q14(-c)}; break;
    default: out = {q30_to_q14(-c), q30_to_q14(s)}; break;
  }
  return out;
}

uint32_t field_angle(AngleKind kind, uint32_t q, int bits) {
  const uint64_t levels = uint64_t{1} << bits;
  switch (kind) {
    case AngleKind::kThetaSphere:  // q * pi / (2^b - 1): half a turn is 2^31
    case AngleKind::kThetaHemisphere: {
      const uint64_t den = levels - 1;
      const int shift = kind == AngleKind::kThetaSphere ? 31 : 30;
      return static_cast<uint32_t>(((static_cast<uint64_t>(q) << shift) + den / 2) / den);
    }
    case AngleKind::kPhi: return static_cast<uint32_t>(static_cast<uint64_t>(q) << (32 - bits));
    case AngleKind::kPsi: return static_cast<uint32_t>(static_cast<uint64_t>(q) << (31 - bits));
  }
  return 0;
}

bool build_angle_table(AngleKind kind, int bits, SinCosQ14* out, size_t capacity) {
  if (bits < 1 || bits > kMaxAngleBits || capacity < angle_table_entries(bits)) return false;
  for (uint32_t q = 0; q < angle_table_entries(bits); ++q) out[q] = sincos_q14(field_angle(kind, q, bits));
  return true;
}

FrameQ14 decode_frame_q14(const FrameTables& t, uint32_t theta, uint32_t phi, uint32_t psi) {
  // Products are kept exact in int64 and rounded once at the end: sines are
  // Q14 (|v| <= 2^14), so x' and y' below are Q42 (|v| <= 2^44) and the
  // axes Q56 (|v| <= 2^59).
  const int64_t st = t.theta[theta].sin, ct = t.theta[theta].cos;
  const int64_t sp = t.phi[phi].sin, cp = t.phi[phi].cos;
  const int64_t ss = t.psi[psi].sin, cs = t.psi[psi].cos;
  const int64_t omc = kQ14One - ct;  // 1 - cos theta, in [0, 2]
  const int64_t spcp = sp * cp * omc;
  // Rodrigues rotation of x and y by theta about a = (-sin phi, cos phi, 0).
  const int64_t x[3] = {(ct << 28) + sp * sp * omc, -spcp, -(cp * st) << 14};
  const int64_t y[3] = {-spcp, (ct << 28) + cp * cp * omc, -(sp * st) << 14};
  auto round56 = [](int64_t v) { return clamp_q14(narrow<int32_t>((v + (int64_t{1} << 41)) >> 42)); };
  FrameQ14 f;
  for (int k = 0; k < 3; ++k) {
    f.axis[0][k] = round56(cs * x[k] + ss * y[k]);
    f.axis[1][k] = round56(cs * y[k] - ss * x[k]);
  }
  f.axis[2][0] = clamp_q14(narrow<int32_t>((cp * st + (1 << 13)) >> 14));
  f.axis[2][1] = clamp_q14(narrow<int32_t>((sp * st + (1 << 13)) >> 14));
  f.axis[2][2] = static_cast<int16_t>(ct);
  return f;
}

int32_t f32_bits_to_fixed(uint32_t bits, int frac_bits, bool* saturated) {
  constexpr int32_t kMax = 0x7FFFFFFF, kMin = -0x7FFFFFFF;
  const bool negative = (bits >> 31) != 0;
  const int exponent = static_cast<int>((bits >> 23) & 0xFFu);
  const uint32_t mantissa = bits & 0x7FFFFFu;
  if (saturated) *saturated = false;
  if (exponent == 0xFF) {  // infinity or NaN
    if (saturated) *saturated = true;
    if (mantissa != 0) return 0;
    return negative ? kMin : kMax;
  }
  // value = m * 2^e exactly.
  const uint64_t m = exponent == 0 ? mantissa : (mantissa | 0x800000u);
  const int e = (exponent == 0 ? -149 : exponent - 150) + frac_bits;
  uint64_t magnitude;
  if (m == 0) {
    magnitude = 0;
  } else if (e >= 0) {
    if (e > 31 || (m << e) > static_cast<uint64_t>(kMax)) {
      if (saturated) *saturated = true;
      return negative ? kMin : kMax;
    }
    magnitude = m << e;
  } else {
    const int r = -e;
    magnitude = r > 25 ? 0 : (m + (uint64_t{1} << (r - 1))) >> r;  // round half away from zero
  }
  const int32_t v = static_cast<int32_t>(magnitude);
  return negative ? -v : v;
}

}  // namespace stipple
