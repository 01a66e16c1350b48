// stipple raster — the tile pass's point loop in SSE2 lanes (x86-64's
// baseline), four samples of one node at a time. Included by point_kernel.h;
// the formula and every bound are that header's, and each step below is
// the scalar one in lanes: the int16 pairs' multiply-add (pmaddwd) forms
// the dot products exactly in int32, packs saturate exactly where the
// scalar code clamps to int16, and the tables are read lane by lane. The
// bytes are the scalar loop's (tests/portable/point_kernel_test.cpp).
#pragma once

#include <emmintrin.h>

#include <cstring>

namespace stipple {
namespace sse2 {

// An int16 pair (low, high) in every 32-bit lane.
inline __m128i pair_of(int16_t lo, int16_t hi) {
  return _mm_set1_epi32(static_cast<int32_t>(static_cast<uint16_t>(lo) | uint32_t{static_cast<uint16_t>(hi)} << 16));
}
inline __m128i load4(const uint32_t* p) { return _mm_loadu_si128(reinterpret_cast<const __m128i*>(p)); }

// (a0 g0 + a1 g1) + a2 g2 for four samples.
inline __m128i dot3(__m128i g01, __m128i g2, __m128i a01, __m128i a2) {
  return _mm_add_epi32(_mm_madd_epi16(g01, a01), _mm_madd_epi16(g2, a2));
}

// Table entries at the int16 indices in lanes 0..3 of `idx`, as 32-bit lanes.
template <class Entry>
inline __m128i gather(const Entry* table, __m128i idx) {
  return _mm_setr_epi32(table[_mm_extract_epi16(idx, 0)], table[_mm_extract_epi16(idx, 1)],
                        table[_mm_extract_epi16(idx, 2)], table[_mm_extract_epi16(idx, 3)]);
}
// The (cos, sinc) pairs themselves, one a lane.
inline __m128i gather(const CosSincQ14* table, __m128i idx) {
  int32_t v[4];
  std::memcpy(&v[0], &table[_mm_extract_epi16(idx, 0)], 4);
  std::memcpy(&v[1], &table[_mm_extract_epi16(idx, 1)], 4);
  std::memcpy(&v[2], &table[_mm_extract_epi16(idx, 2)], 4);
  std::memcpy(&v[3], &table[_mm_extract_epi16(idx, 3)], 4);
  return _mm_setr_epi32(v[0], v[1], v[2], v[3]);
}

// intensity_index of four Q14 values, as int16 lanes 0..3.
inline __m128i intensity_index4(__m128i l) {
  const __m128i i = _mm_srai_epi32(_mm_add_epi32(l, _mm_set1_epi32(kIntensityOffsetQ14)), 7);
  const __m128i p = _mm_packs_epi32(i, i);
  return _mm_min_epi16(_mm_max_epi16(p, _mm_setzero_si128()), _mm_set1_epi16(kIntensityEntries - 1));
}

// L.n in Q14 (lit_index, before its table index) in lanes: `ab` holds
// (al, be) pairs, `t` the (t1, t2) pair, `n0` the Q12 term in each lane's low half.
inline __m128i lit4(__m128i cs, __m128i ab, __m128i t, __m128i n0) {
  const __m128i along = _mm_srai_epi32(_mm_madd_epi16(ab, t), 14);
  return _mm_srai_epi32(_mm_madd_epi16(cs, _mm_or_si128(n0, _mm_slli_epi32(along, 16))), 12);
}

// A channel (0..255) after shading: min(((c * intensity) >> 8) + specular,
// 255). Every operand is below 2^16 in its lane's low half and zero above,
// so the 16-bit multiply and minimum are the 32-bit ones.
inline __m128i shade_channel(__m128i c, __m128i intensity, __m128i specular) {
  const __m128i v = _mm_add_epi32(_mm_srli_epi32(_mm_mullo_epi16(c, intensity), 8), specular);
  return _mm_min_epi16(v, _mm_set1_epi32(255));
}

// rgb565 in lanes.
inline __m128i rgb565_4(__m128i rgb) {
  return _mm_or_si128(_mm_or_si128(_mm_and_si128(_mm_srli_epi32(rgb, 8), _mm_set1_epi32(0xF800)),
                                   _mm_and_si128(_mm_srli_epi32(rgb, 5), _mm_set1_epi32(0x07E0))),
                      _mm_and_si128(_mm_srli_epi32(rgb, 3), _mm_set1_epi32(0x001F)));
}

template <PointNormals kNormals, bool kColorPoints, bool kSpecular, class Word>
void draw_tile_node(const TileRow& n, const PointTables& t, int size, Word* words, int tile_log2, int px0, int py0) {
  constexpr bool kShadePoints = kNormals != PointNormals::kNode;
  const int tile = 1 << tile_log2;
  const bool inside = n.inside_tile(px0, py0, tile);
  const uint32_t wh = static_cast<uint32_t>(size | size << 4);
  const auto word = [&](TileField f) { return _mm_set1_epi32(static_cast<int32_t>(n[f])); };
  const __m128i mx01 = word(TileField::kMx01), mx2 = word(TileField::kMx2);
  const __m128i my01 = word(TileField::kMy01), my2 = word(TileField::kMy2);
  const __m128i dz01 = word(TileField::kDz01), dz2 = word(TileField::kDz2);
  const __m128i x0 = _mm_set1_epi32(n.x0_q4() - (px0 << 4)), y0 = _mm_set1_epi32(n.y0_q4() - (py0 << 4));
  const __m128i depth0 = _mm_set1_epi32(static_cast<int32_t>(n.depth0())), dshift = _mm_cvtsi32_si128(static_cast<int>(n.dshift()));
  const uint32_t count = n.count();
  const __m128i sn = word(TileField::kSn), lt = word(TileField::kLt), ht = word(TileField::kHt);
  const __m128i l0 = pair_of(n.lo(TileField::kL0H0), 0), h0 = pair_of(n.hi(TileField::kL0H0), 0);
  const __m128i s0_01 = word(TileField::kS0_01), s0_2 = word(TileField::kS0_2);
  const __m128i s1_01 = word(TileField::kS1_01), s1_2 = word(TileField::kS1_2);
  const uint32_t base_rgb = n[TileField::kBaseRgb];
  __m128i base[3], ca01[3], ca2[3];
  for (int c = 0; c < 3; ++c) {
    base[c] = _mm_set1_epi32(static_cast<int32_t>((base_rgb >> (16 - 8 * c)) & 0xFFu));
    ca01[c] = word(static_cast<TileField>(static_cast<int>(TileField::kCa01R) + c));
    ca2[c] = word(static_cast<TileField>(static_cast<int>(TileField::kCa2R) + c));
  }
  const __m128i node_intensity = _mm_set1_epi32(static_cast<int32_t>(n[TileField::kLighting] & 0xFFFFu));
  const __m128i node_specular = _mm_set1_epi32(static_cast<int32_t>(n[TileField::kLighting] >> 16));
  alignas(16) int32_t xs[4], ys[4];
  alignas(16) Word ws[4];
  for (uint32_t j = 0; j < count; j += 4) {
    const __m128i g01 = load4(t.g01 + j), g2 = load4(t.g2 + j);
    const __m128i x = _mm_srai_epi32(_mm_add_epi32(_mm_srai_epi32(dot3(g01, g2, mx01, mx2), 16), x0), 4);
    const __m128i y = _mm_srai_epi32(_mm_add_epi32(_mm_srai_epi32(dot3(g01, g2, my01, my2), 16), y0), 4);
    const __m128i depth = _mm_add_epi32(_mm_sra_epi32(dot3(g01, g2, dz01, dz2), dshift), depth0);
    __m128i rgb;
    if constexpr (!kColorPoints && !kShadePoints) {
      rgb = word(TileField::kNodeRgb);
    } else {
      __m128i ch[3] = {base[0], base[1], base[2]};
      if constexpr (kColorPoints) {
        const __m128i q01 = load4(t.q01 + j), q2 = load4(t.q2 + j);
        for (int c = 0; c < 3; ++c) {
          const __m128i v = _mm_add_epi32(base[c], _mm_srai_epi32(dot3(q01, q2, ca01[c], ca2[c]), 19));
          ch[c] = _mm_min_epi16(_mm_max_epi16(v, _mm_setzero_si128()), _mm_set1_epi32(255));  // |v| < 2^15
        }
      }
      __m128i intensity = node_intensity, specular = node_specular;
      if constexpr (kShadePoints) {
        __m128i p01, p23;  // al and be, as int32, for samples 0, 1 and 2, 3
        if constexpr (kNormals == PointNormals::kSurface) {
          const __m128i al = _mm_srai_epi32(dot3(g01, g2, s0_01, s0_2), 12);
          const __m128i be = _mm_srai_epi32(dot3(g01, g2, s1_01, s1_2), 12);
          p01 = _mm_unpacklo_epi32(al, be);
          p23 = _mm_unpackhi_epi32(al, be);
        } else {
          // (sigma_n n) >> 12 per element: the 16 x 16-bit products whole.
          const __m128i nn = load4(t.n01 + j);
          const __m128i lo = _mm_mullo_epi16(nn, sn), hi = _mm_mulhi_epi16(nn, sn);
          p01 = _mm_srai_epi32(_mm_unpacklo_epi16(lo, hi), 12);
          p23 = _mm_srai_epi32(_mm_unpackhi_epi16(lo, hi), 12);
        }
        // Clamped to +-4 rad and packed back to (al, be) pairs.
        const __m128i ab = _mm_min_epi16(_mm_max_epi16(_mm_packs_epi32(p01, p23), _mm_set1_epi16(-16384)),
                                         _mm_set1_epi16(16384));
        // <= 4096: a cell of the table (kCosSincCells), no clamp.
        const __m128i cell32 = _mm_srli_epi32(_mm_madd_epi16(ab, ab), kCosSincShift);
        const __m128i cell = _mm_packs_epi32(cell32, cell32);
        const __m128i cs = gather(t.shading->cos_sinc, cell);
        intensity = gather(t.shading->diffuse, intensity_index4(lit4(cs, ab, lt, l0)));
        specular = kSpecular ? gather(t.shading->specular, intensity_index4(lit4(cs, ab, ht, h0))) : _mm_setzero_si128();
      }
      rgb = _mm_or_si128(_mm_or_si128(_mm_slli_epi32(shade_channel(ch[0], intensity, specular), 16),
                                      _mm_slli_epi32(shade_channel(ch[1], intensity, specular), 8)),
                         shade_channel(ch[2], intensity, specular));
    }
    if constexpr (sizeof(Word) == 4) {
      _mm_store_si128(reinterpret_cast<__m128i*>(ws),
                      _mm_or_si128(_mm_and_si128(depth, _mm_set1_epi32(static_cast<int32_t>(0xFFFF0000u))), rgb565_4(rgb)));
    } else {
      _mm_store_si128(reinterpret_cast<__m128i*>(ws), _mm_unpacklo_epi32(rgb, depth));
      _mm_store_si128(reinterpret_cast<__m128i*>(ws) + 1, _mm_unpackhi_epi32(rgb, depth));
    }
    _mm_store_si128(reinterpret_cast<__m128i*>(xs), x);
    _mm_store_si128(reinterpret_cast<__m128i*>(ys), y);
    const uint32_t lanes = count - j < 4 ? count - j : 4;
    for (uint32_t k = 0; k < lanes; ++k) ztest_point(words, tile_log2, size, wh, inside, xs[k], ys[k], ws[k]);
  }
}

}  // namespace sse2
}  // namespace stipple
