// stipple core — floored integer division, with or without a divide
// instruction.
//
// ARMv5TE (and most ARMv7-A cores) have no divide instruction: `n / d` on
// 64-bit values becomes a call to libgcc's __aeabi_ldivmod, a bit-serial
// loop of a few hundred cycles. `floor_div_soft` gives the same floored
// quotient from multiplications: a 256-entry reciprocal seed (relative
// error 2^-9), two Newton steps (2^-30), the quotient from a split 64-bit
// product, and a correction by the remainder that makes it exact. Its fast
// path needs 0 < d < 2^32 and a quotient below 2^30 — the projection's
// divisions (raster/projection.h) always are — and anything else takes an
// exact shift-and-subtract loop, so every input gets the exact result.
//
// `floor_div` is the one the per-point path calls: the divide instruction
// (or the compiler's helper) when the build says the target has one —
// STIPPLE_HW_DIVIDE=1, CMake option STIPPLE_HW_DIVIDE — and
// floor_div_soft otherwise. Both give identical results (tests/portable/
// divide_test.cpp), so images do not depend on the option.
#pragma once

#include <cstdint>

namespace stipple {

namespace divide_detail {

// Seed i ~ 2^62 / ((256 + i + 1/2) 2^23) = 2^40 / (513 + 2i), rounded: in (2^30, 2^31).
struct ReciprocalSeeds {
  uint32_t v[256];
  constexpr ReciprocalSeeds() : v() {
    for (uint64_t i = 0; i < 256; ++i) v[i] = static_cast<uint32_t>(((uint64_t{1} << 40) + (513 + 2 * i) / 2) / (513 + 2 * i));
  }
};
inline constexpr ReciprocalSeeds kSeeds{};

// a / d and a % d by shift and subtract, for any d > 0.
inline uint64_t long_divide(uint64_t a, uint64_t d, uint64_t* rem) {
  uint64_t q = 0, r = 0;
  for (int bit = 63; bit >= 0; --bit) {
    r = (r << 1) | ((a >> bit) & 1);
    if (r >= d) {
      r -= d;
      q |= uint64_t{1} << bit;
    }
  }
  *rem = r;
  return q;
}

}  // namespace divide_detail

// floor(n / d) for d > 0, without a division instruction or helper.
inline int64_t floor_div_soft(int64_t n, int64_t d) {
  const uint64_t a = n < 0 ? 0 - static_cast<uint64_t>(n) : static_cast<uint64_t>(n);
  const uint64_t ud = static_cast<uint64_t>(d);
  uint64_t q, r;
  const int e = 63 - __builtin_clzll(ud);  // 2^e <= d < 2^(e+1)
  if (e < 32 && (a >> e) < (uint64_t{1} << 30)) {  // quotient below 2^30
    const uint32_t dn = static_cast<uint32_t>(ud << (31 - e));  // in [2^31, 2^32)
    uint64_t x = divide_detail::kSeeds.v[(dn >> 23) & 255];     // ~ 2^62 / dn
    for (int step = 0; step < 2; ++step) {                       // x += x (2^62 - dn x) / 2^62
      const int64_t err = static_cast<int64_t>((uint64_t{1} << 62) - dn * x);  // |err| <= 2^53: (err >> 22) x < 2^62
      x = static_cast<uint64_t>(static_cast<int64_t>(x) + (((err >> 22) * static_cast<int64_t>(x)) >> 40));
    }
    // q ~ a x / 2^(31 + e) from the halves of a (a < 2^(e + 30) < 2^62).
    const uint64_t t = (a >> 32) * x + (((a & 0xFFFFFFFFu) * x) >> 32);  // a x / 2^32
    const int shift = e - 1;                                               // 31 + e - 32
    int64_t qs = static_cast<int64_t>(shift >= 0 ? t >> shift : t << 1);
    int64_t rs = static_cast<int64_t>(a) - qs * static_cast<int64_t>(ud);
    while (rs < 0) {  // at most a few steps each way
      --qs;
      rs += static_cast<int64_t>(ud);
    }
    while (rs >= static_cast<int64_t>(ud)) {
      ++qs;
      rs -= static_cast<int64_t>(ud);
    }
    q = static_cast<uint64_t>(qs);
    r = static_cast<uint64_t>(rs);
  } else {
    q = divide_detail::long_divide(a, ud, &r);
  }
  if (n >= 0) return static_cast<int64_t>(q);
  return static_cast<int64_t>(r != 0 ? ~q : 0 - q);  // -q, or -q - 1 (modular: INT64_MIN / 1 too)
}

// floor(n / d) for d > 0.
inline int64_t floor_div(int64_t n, int64_t d) {
#if STIPPLE_HW_DIVIDE
  const int64_t q = n / d;
  return q * d > n ? q - 1 : q;
#else
  return floor_div_soft(n, d);
#endif
}

}  // namespace stipple
