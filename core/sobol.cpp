// stipple core — Sobol sequence (Bratley & Fox construction, Joe–Kuo numbers).
#include "core/sobol.h"

namespace stipple {
namespace {

struct DirectionTable {
  uint32_t v[kSobolDimensions][32];
};

// new-joe-kuo-6.21201, dimensions 2..8 (s, a, m_1..m_s):
//   2 1 0 1 | 3 2 1 1 3 | 4 3 1 1 3 1 | 5 3 2 1 1 1
//   6 4 1 1 1 3 3 | 7 4 4 1 3 5 13 | 8 5 2 1 1 5 5 17
struct Poly {
  uint32_t s, a, m[5];
};
constexpr Poly kJoeKuo[kSobolDimensions - 1] = {
    {1, 0, {1}},          {2, 1, {1, 3}},          {3, 1, {1, 3, 1}},       {3, 2, {1, 1, 1}},
    {4, 1, {1, 1, 3, 3}}, {4, 4, {1, 3, 5, 13}},   {5, 2, {1, 1, 5, 5, 17}},
};

constexpr DirectionTable make_table() {
  DirectionTable t{};
  for (uint32_t i = 0; i < 32; ++i) t.v[0][i] = 1u << (31 - i);
  for (int d = 1; d < kSobolDimensions; ++d) {
    const Poly& p = kJoeKuo[d - 1];
    for (uint32_t i = 0; i < p.s; ++i) t.v[d][i] = p.m[i] << (31 - i);
    for (uint32_t i = p.s; i < 32; ++i) {
      uint32_t v = t.v[d][i - p.s] ^ (t.v[d][i - p.s] >> p.s);
      for (uint32_t k = 1; k < p.s; ++k)
        if ((p.a >> (p.s - 1 - k)) & 1u) v ^= t.v[d][i - k];
      t.v[d][i] = v;
    }
  }
  return t;
}

constexpr DirectionTable kDirections = make_table();

}  // namespace

uint32_t sobol_u32(uint32_t index, int dim) {
  const uint32_t gray = index ^ (index >> 1);
  uint32_t x = 0;
  for (int bit = 0; bit < 32 && (gray >> bit) != 0; ++bit)
    if ((gray >> bit) & 1u) x ^= kDirections.v[dim][bit];
  return x;
}

}  // namespace stipple
