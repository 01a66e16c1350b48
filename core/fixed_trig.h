// stipple core — fixed-point trigonometry and frame decoding for node
// records (TOG05 §5, "Decoding"), integer only.
//
// Formats
//   Q14     int16 / int32 value v means v / 2^14; unit vectors and sines lie in
//           [-16384, 16384]. One LSB is 6.1e-5.
//   binary angle  uint32 a means a / 2^32 of a turn (wraps for free).
//
// Angles of a record field map to binary angles exactly as the reference
// decoder maps them to radians (docs/format.md §5): theta = q range/(2^b - 1)
// (range pi, or pi/2 for hemispheric colour frames), phi = q 2pi/2^b,
// psi = q pi/2^b; the conversion rounds to the nearest binary angle.
//
// `sincos_q14` evaluates sine and cosine with a degree-9/10 Taylor series in
// Q30 on [0, pi/4] and octant symmetry: |error| <= 1 LSB of Q14 (tested
// against libm over all 2^16 angles of a 16-bit grid). Tables are therefore
// exact functions of the format, generated at init, identical on every build.
#pragma once

#include <cstddef>
#include <cstdint>

#include "core/fixed_range.h"

namespace stipple {

inline constexpr int32_t kQ14One = 1 << 14;

// a * b with a in Q14, rounded half up: b's format scaled by a.
inline int32_t mul_q14(int32_t a_q14, int32_t b) {
  return narrow<int32_t>((static_cast<int64_t>(a_q14) * b + (1 << 13)) >> 14);
}
// The same for |a| <= 2^14 and |b| < 2^30 in 32-bit products: with b = h
// 2^14 + l (h = b >> 14, 0 <= l < 2^14), a b + 2^13 = a h 2^14 + (a l +
// 2^13), and the floor of a division by 2^14 takes a h out whole. |a h| <=
// 2^30 and |a l + 2^13| < 2^28.1: int32 throughout — two multiplies on
// ARMv5, not an SMULL, its carries and a 64-bit shift (the client's
// per-node set-up; tests/portable/fixed_test.cpp holds the two equal).
inline int32_t mul_q14_int32(int32_t a_q14, int32_t b) {
  return a_q14 * (b >> 14) + ((a_q14 * (b & 0x3FFF) + (1 << 13)) >> 14);
}
// mul_q14 for those ranges, the cheaper way on the target: 64-bit targets
// multiply 64 bits in one instruction (the split costs x86-64's scalar
// set-up ~54 instructions a node more), 32-bit ones take mul_q14_int32.
inline int32_t mul_q14_fast(int32_t a_q14, int32_t b) {
#if UINTPTR_MAX > 0xFFFFFFFFu
  return mul_q14(a_q14, b);
#else
  return mul_q14_int32(a_q14, b);
#endif
}
inline constexpr int kMaxAngleBits = 16;  // the widest field the format allows; tables are 2^bits entries

// 4-aligned: a copy is one word (on ARMv5, without unaligned loads, GCC
// copied a 2-aligned one by calling memcpy — twice a node in the set-up).
struct alignas(4) SinCosQ14 {
  int16_t sin = 0, cos = 0;
};

SinCosQ14 sincos_q14(uint32_t binary_angle);

enum class AngleKind : uint8_t { kThetaSphere, kThetaHemisphere, kPhi, kPsi };

// Binary angle of quantized value `q` of a `bits`-wide field (1 <= bits <= 16).
uint32_t field_angle(AngleKind kind, uint32_t q, int bits);

// Sine/cosine of every value of one angle field: 2^bits entries.
constexpr size_t angle_table_entries(int bits) { return size_t{1} << bits; }
// Fills `out[0 .. 2^bits)`; `bits` in 1..kMaxAngleBits (returns false otherwise).
[[nodiscard]] bool build_angle_table(AngleKind kind, int bits, SinCosQ14* out, size_t capacity);

// The three sin/cos tables of one frame field (theta, phi, psi).
struct FrameTables {
  const SinCosQ14* theta = nullptr;
  const SinCosQ14* phi = nullptr;
  const SinCosQ14* psi = nullptr;
};

// A decoded frame: axis[k] is f_(k+1) as (x, y, z) in Q14.
struct FrameQ14 {
  int16_t axis[3][3] = {};
};

// f3 = (cos phi sin theta, sin phi sin theta, cos theta); x', y' = x, y rotated
// by theta about (-sin phi, cos phi, 0); f1 = cos psi x' + sin psi y',
// f2 = cos psi y' - sin psi x'. Indices must be below their tables' sizes.
FrameQ14 decode_frame_q14(const FrameTables& tables, uint32_t theta, uint32_t phi, uint32_t psi);

// IEEE-754 binary32 (raw bits) to a signed fixed-point value with `frac_bits`
// fraction bits (0..30), rounded to nearest (ties away from zero), saturated
// to [INT32_MIN + 1, INT32_MAX]. NaN gives 0 and sets *saturated; so does
// infinity (saturated to the signed bound). `saturated` may be null.
int32_t f32_bits_to_fixed(uint32_t bits, int frac_bits, bool* saturated);

}  // namespace stipple
