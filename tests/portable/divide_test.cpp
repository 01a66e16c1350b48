// Floored division without a divide instruction (core/divide.h) gives the
// hardware's quotient for every input class: the projection's range, the
// edges of the fast path, and the far ends of int64.
#include <gtest/gtest.h>

#include <cstdint>
#include <limits>
#include <random>

#include "core/divide.h"

namespace stipple {
namespace {

int64_t floor_div_reference(int64_t n, int64_t d) {
  const int64_t q = n / d, r = n % d;
  return r != 0 && ((r < 0) != (d < 0)) ? q - 1 : q;
}

TEST(Divide, FloorRoundsTowardMinusInfinity) {
  for (auto f : {&floor_div, &floor_div_soft}) {
    EXPECT_EQ(f(7, 2), 3);
    EXPECT_EQ(f(-7, 2), -4);
    EXPECT_EQ(f(-8, 2), -4);
    EXPECT_EQ(f(0, 5), 0);
    EXPECT_EQ(f(-1, 1000000007), -1);
  }
  RecordProperty("floor_div", STIPPLE_HW_DIVIDE ? "hardware" : "soft");  // the build's choice
}

TEST(Divide, SoftEqualsHardwareAtTheEdges) {
  const int64_t kMax = std::numeric_limits<int64_t>::max(), kMin = std::numeric_limits<int64_t>::min();
  std::vector<int64_t> divisors = {1, 2, 3, 5, 7, 255, 256, 257, 1000000007, kMax};
  for (int k = 1; k < 63; ++k)
    for (int64_t delta : {-1, 0, 1}) divisors.push_back((int64_t{1} << k) + delta);
  int checked = 0;
  for (const int64_t d : divisors) {
    if (d <= 0) continue;
    std::vector<int64_t> numerators = {0, 1, -1, kMax, kMin, kMin + 1, d, -d, d - 1, 1 - d};
    if (d < kMax) numerators.insert(numerators.end(), {d + 1, -d - 1});
    for (int k = 0; k < 63; ++k) {  // quotients at every power of two, with remainders 0, 1 and d - 1
      const int64_t q = int64_t{1} << k;
      if (q > kMax / d) break;
      for (int64_t r : {int64_t{0}, int64_t{1}, d - 1}) {
        if (q * d > kMax - r) continue;
        numerators.push_back(q * d + r);
        numerators.push_back(-(q * d + r));
        numerators.push_back((q - 1) * d + r);
      }
    }
    for (const int64_t n : numerators) {
      ASSERT_EQ(floor_div_soft(n, d), floor_div_reference(n, d)) << n << " / " << d;
      ++checked;
    }
  }
  RecordProperty("cases", checked);
}

TEST(Divide, SoftEqualsHardwareForRandomInputs) {
  std::mt19937_64 rng(17);
  for (int i = 0; i < 400000; ++i) {
    // Log-uniform magnitudes: every bit length of numerator and divisor.
    const int64_t d = static_cast<int64_t>((rng() >> (rng() % 64)) | 1) & std::numeric_limits<int64_t>::max();
    const int64_t n = static_cast<int64_t>(rng()) >> (rng() % 64);
    if (d == 0) continue;
    ASSERT_EQ(floor_div_soft(n, d), floor_div_reference(n, d)) << n << " / " << d;
  }
  // The exact projection's divisions: f X_p / Z_p with Z_p in [2^12, 2^32)
  // and |X_p| <= 8 Z_p, f up to 2^20 (Q4).
  for (int i = 0; i < 400000; ++i) {
    const int64_t z = int64_t{4096} + static_cast<int64_t>(rng() >> (rng() % 32 + 32));
    const int64_t f = static_cast<int64_t>(rng() >> 44);
    const int64_t x = static_cast<int64_t>(rng() % static_cast<uint64_t>(16 * z + 1)) - 8 * z;
    ASSERT_EQ(floor_div_soft(f * x, z), floor_div_reference(f * x, z)) << f * x << " / " << z;
  }
}

}  // namespace
}  // namespace stipple
