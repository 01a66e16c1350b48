// Fixed-point trigonometry and binary32 conversion against double-precision
// oracles (libm; the Q14 frame decode is checked against the reference
// decoder in tests/node_decoder_test.cpp).
#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>
#include <random>

#include "core/fixed_trig.h"

namespace stipple {
namespace {

constexpr double kPi = std::numbers::pi;

TEST(FixedTrig, SinCosWithinOneLsbOfLibmEverywhere) {
  int worst = 0;
  for (uint64_t a = 0; a < (uint64_t{1} << 32); a += (uint64_t{1} << 16) + 7) {  // 65,535 angles, all octants
    const double rad = static_cast<double>(a) * 2 * kPi / 4294967296.0;
    const SinCosQ14 v = sincos_q14(static_cast<uint32_t>(a));
    const int ds = std::abs(v.sin - static_cast<int>(std::lround(std::sin(rad) * kQ14One)));
    const int dc = std::abs(v.cos - static_cast<int>(std::lround(std::cos(rad) * kQ14One)));
    worst = std::max({worst, ds, dc});
    ASSERT_LE(ds, 1) << "angle " << a;
    ASSERT_LE(dc, 1) << "angle " << a;
  }
  RecordProperty("worst_lsb", worst);
  // Exact at the axes.
  const uint32_t quarter = 1u << 30;
  EXPECT_EQ(sincos_q14(0).cos, kQ14One);
  EXPECT_EQ(sincos_q14(0).sin, 0);
  EXPECT_EQ(sincos_q14(quarter).sin, kQ14One);
  EXPECT_EQ(sincos_q14(quarter).cos, 0);
  EXPECT_EQ(sincos_q14(2 * quarter).cos, -kQ14One);
  EXPECT_EQ(sincos_q14(3 * quarter).sin, -kQ14One);
  EXPECT_EQ(sincos_q14(0xFFFFFFFFu).cos, kQ14One);  // the wrap
}

TEST(FixedTrig, FieldAnglesMatchTheFormat) {
  for (int bits : {1, 3, 4, 6, 8, 10, 12, 16}) {
    const uint32_t levels = 1u << bits;
    for (uint32_t q = 0; q < levels; q += 1 + levels / 512) {
      const double turns[4] = {q / (2.0 * (levels - 1)), q / (4.0 * (levels - 1)), static_cast<double>(q) / levels,
                               q / (2.0 * levels)};
      const AngleKind kinds[4] = {AngleKind::kThetaSphere, AngleKind::kThetaHemisphere, AngleKind::kPhi,
                                  AngleKind::kPsi};
      for (int k = 0; k < 4; ++k) {
        const double expect = turns[k] * 4294967296.0;
        ASSERT_LE(std::abs(static_cast<double>(field_angle(kinds[k], q, bits)) - std::fmod(expect, 4294967296.0)), 0.5)
            << "kind " << k << " bits " << bits << " q " << q;
      }
    }
  }
  EXPECT_EQ(field_angle(AngleKind::kThetaSphere, 255, 8), 1u << 31);  // theta = pi exactly
  EXPECT_EQ(field_angle(AngleKind::kThetaHemisphere, 15, 4), 1u << 30);
}

TEST(FixedTrig, AngleTablesCheckTheirBounds) {
  SinCosQ14 table[256];
  EXPECT_TRUE(build_angle_table(AngleKind::kPhi, 8, table, 256));
  EXPECT_FALSE(build_angle_table(AngleKind::kPhi, 8, table, 255));  // too small
  EXPECT_FALSE(build_angle_table(AngleKind::kPhi, 0, table, 256));
  EXPECT_FALSE(build_angle_table(AngleKind::kPhi, kMaxAngleBits + 1, table, 256));
  EXPECT_EQ(table[64].sin, kQ14One);  // phi = pi/2
}

// The set-up's Q14 scaling in 32-bit products is mul_q14's int64 formula,
// at the ends of its range and between.
TEST(FixedTrig, MulQ14Int32IsMulQ14) {
  const int32_t as[] = {-16384, -16383, -8193, -1, 0, 1, 8191, 16383, 16384};
  const int32_t bs[] = {-(1 << 30) + 1, -(1 << 29) - (1 << 24), -16385, -16384, -16383, -8192, -1, 0, 1, 8191, 8192,
                        16383, 16384, 16385, 1 << 25, (1 << 29) + (1 << 24), (1 << 30) - 1};
  for (int32_t a : as)
    for (int32_t b : bs) EXPECT_EQ(mul_q14_int32(a, b), mul_q14(a, b)) << a << " x " << b;
  std::mt19937 rng(14);
  std::uniform_int_distribution<int32_t> a_of(-16384, 16384), b_of(-(1 << 30) + 1, (1 << 30) - 1);
  for (int i = 0; i < 200000; ++i) {
    const int32_t a = a_of(rng), b = b_of(rng) >> (i % 20);
    ASSERT_EQ(mul_q14_int32(a, b), mul_q14(a, b)) << a << " x " << b;
  }
}

uint32_t bits_of(float f) {
  uint32_t b;
  std::memcpy(&b, &f, 4);
  return b;
}

TEST(FixedConversion, Binary32ToFixedAgainstADoubleOracle) {
  const float values[] = {0.0f, -0.0f, 1.0f, -1.0f, 0.5f, 1.5f, -2.5f, 3.0e-5f, 1e-15f, 0.15f, 1234.5678f,
                          32767.99f, 32768.0f, -32768.0f, 65535.0f, 1e10f, -1e10f, FLT_MAX, -FLT_MAX,
                          std::numeric_limits<float>::denorm_min(), FLT_MIN, 0x1.0p-17f, 0x1.8p-17f, -0x1.8p-17f};
  for (int frac : {0, 8, 14, 16, 24, 30}) {
    for (float v : values) {
      bool sat = true;
      const int32_t got = f32_bits_to_fixed(bits_of(v), frac, &sat);
      const double scaled = static_cast<double>(v) * std::ldexp(1.0, frac);
      const double rounded = scaled < 0 ? -std::floor(-scaled + 0.5) : std::floor(scaled + 0.5);
      if (rounded > 2147483647.0 || rounded < -2147483647.0) {
        EXPECT_TRUE(sat) << v << " frac " << frac;
        EXPECT_EQ(got, v > 0 ? INT32_MAX : -INT32_MAX) << v << " frac " << frac;
      } else {
        EXPECT_FALSE(sat) << v << " frac " << frac;
        EXPECT_EQ(got, static_cast<int32_t>(rounded)) << v << " frac " << frac;
      }
    }
  }
  bool sat = false;
  EXPECT_EQ(f32_bits_to_fixed(0x7FC00000u, 16, &sat), 0);  // NaN
  EXPECT_TRUE(sat);
  EXPECT_EQ(f32_bits_to_fixed(bits_of(-INFINITY), 16, &sat), -INT32_MAX);
  EXPECT_TRUE(sat);
  EXPECT_EQ(f32_bits_to_fixed(bits_of(0x1.0p-17f), 16, nullptr), 1);  // exactly half an LSB: away from zero
  EXPECT_EQ(f32_bits_to_fixed(bits_of(-0x1.0p-17f), 16, nullptr), -1);
}

}  // namespace
}  // namespace stipple
