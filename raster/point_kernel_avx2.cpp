// stipple raster — the tile pass's point loop in AVX2 lanes. See
// point_kernel_avx2.h; built with -mavx2 and called only where
// avx2::supported(). Each step is the scalar formula's (point_kernel.h) in
// lanes: the int16 pairs' multiply-add forms the dot products exactly, the
// tables are gathered, and every clamp is the scalar one.
#include "raster/point_kernel_avx2.h"

#if defined(__x86_64__) || defined(__i386__)

#include <immintrin.h>

#include <cstring>

namespace stipple {
namespace avx2 {
namespace {

inline __m256i gather(const uint32_t* base, __m256i index) {
  return _mm256_i32gather_epi32(reinterpret_cast<const int*>(base), index, 4);
}
inline __m256i lo16(__m256i pairs) { return _mm256_srai_epi32(_mm256_slli_epi32(pairs, 16), 16); }
inline __m256i hi16(__m256i pairs) { return _mm256_srai_epi32(pairs, 16); }

// (a0 g0 + a1 g1) + a2 g2 for eight samples.
inline __m256i dot3(__m256i g01, __m256i g2, __m256i a01, __m256i a2) {
  return _mm256_add_epi32(_mm256_madd_epi16(g01, a01), _mm256_madd_epi16(g2, a2));
}

inline __m256i intensity_index8(__m256i l) {
  const __m256i i = _mm256_srai_epi32(_mm256_add_epi32(l, _mm256_set1_epi32(kIntensityOffsetQ14)), 7);
  return _mm256_min_epi32(_mm256_max_epi32(i, _mm256_setzero_si256()), _mm256_set1_epi32(kIntensityEntries - 1));
}

// The diffuse table's entries for L.n in Q14, `l`, computed (diffuse_q8):
// with i = intensity_index(l), clamp(i - kIntensityZero, 0, 128) =
// clamp((l + 64) >> 7, 0, 128) — 16,384 is 128 << 7. Seven operations
// instead of a gather, which on the 1 px frame is the tile pass's costliest
// instruction.
inline __m256i diffuse8(__m256i l, __m256i ambient, __m256i lit_scale) {
  const __m256i lit = _mm256_min_epi32(
      _mm256_max_epi32(_mm256_srai_epi32(_mm256_add_epi32(l, _mm256_set1_epi32(64)), 7), _mm256_setzero_si256()),
      _mm256_set1_epi32(128));
  return _mm256_add_epi32(ambient, _mm256_srai_epi32(_mm256_add_epi32(_mm256_mullo_epi32(lit_scale, lit), _mm256_set1_epi32(64)), 7));
}

// L.n in Q14 (lit_index, before its table index) in lanes: `ab` holds
// (al, be) pairs, `t` (t1, t2) pairs, `n0` the Q12 term in each lane's low half.
inline __m256i lit8(__m256i cs, __m256i ab, __m256i t, __m256i n0) {
  const __m256i along = _mm256_srai_epi32(_mm256_madd_epi16(ab, t), 14);
  return _mm256_srai_epi32(_mm256_madd_epi16(cs, _mm256_or_si256(n0, _mm256_slli_epi32(along, 16))), 12);
}

inline __m256i shade_channel(__m256i c, __m256i intensity, __m256i specular) {
  const __m256i v = _mm256_add_epi32(_mm256_srli_epi32(_mm256_mullo_epi32(c, intensity), 8), specular);
  return _mm256_min_epi32(v, _mm256_set1_epi32(255));
}

inline __m256i rgb565_8(__m256i rgb) {
  return _mm256_or_si256(_mm256_or_si256(_mm256_and_si256(_mm256_srli_epi32(rgb, 8), _mm256_set1_epi32(0xF800)),
                                         _mm256_and_si256(_mm256_srli_epi32(rgb, 5), _mm256_set1_epi32(0x07E0))),
                         _mm256_and_si256(_mm256_srli_epi32(rgb, 3), _mm256_set1_epi32(0x001F)));
}

// Each lane's first pixel's word: (y << tile_log2) + x.
inline __m256i add_offsets(__m256i x, __m256i y, int tile_log2) {
  return _mm256_add_epi32(_mm256_sll_epi32(y, _mm_cvtsi32_si128(tile_log2)), x);
}

// A point's square of kSize x kSize inside the tile: ztest_square unrolled,
// and without a branch — each pixel is written back with the lesser of its
// word and the point's (a compare and a conditional move). Which wins is close to
// a coin toss where a node's points overlap, and the branch it replaces
// mispredicted often enough to cost a third of the frame's time with 1 px
// points (docs/fixed_point.md, "Wall clock").
template <int kSize, class Word>
[[gnu::always_inline]] inline void ztest_fixed(Word* at, int tile_log2, Word w) {
  const int tile = 1 << tile_log2;
#pragma GCC unroll 3
  for (int y = 0; y < kSize; ++y, at += tile)
#pragma GCC unroll 3
    for (int x = 0; x < kSize; ++x) {
      const Word v = at[x];
      at[x] = w < v ? w : v;
    }
}

// Eight points: lane k is sample lane_j[k] of the node whose row starts
// at word lane_row[k] (an int32: the raster's pool, which holds the rows,
// is at most 2 GiB) — or, for kRun, samples lane_j[0] .. + 7 of the node
// at lane_row[0], whose constants are then broadcast and whose samples are
// loaded, not gathered; the first `active` lanes are drawn, as squares of
// kSize px.
template <PointNormals kNormals, bool kColorPoints, bool kSpecular, int kSize, bool kRun, class Word>
[[gnu::always_inline]] inline void draw_lanes(const TileNodes& nodes, const int32_t* lane_row, const int32_t* lane_j,
                                              uint32_t active, const PointTables& t, Word* words, int tile_log2, int px0,
                                              int py0) {
  constexpr bool kShadePoints = kNormals != PointNormals::kNode;
  const __m256i rows = _mm256_load_si256(reinterpret_cast<const __m256i*>(lane_row));
  const __m256i jj = _mm256_load_si256(reinterpret_cast<const __m256i*>(lane_j));
  const auto field = [&](TileField f) {
    if constexpr (kRun) return _mm256_set1_epi32(static_cast<int32_t>(nodes.words()[lane_row[0] + static_cast<int>(f)]));
    else return gather(nodes.words() + static_cast<int>(f), rows);
  };
  const auto sample = [&](const uint32_t* table) {
    if constexpr (kRun) return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(table + lane_j[0]));
    else return gather(table, jj);
  };
  const __m256i g01 = sample(t.g01), g2 = sample(t.g2);
  const __m256i x = _mm256_srai_epi32(
      _mm256_add_epi32(_mm256_srai_epi32(dot3(g01, g2, field(TileField::kMx01), field(TileField::kMx2)), 16),
                       _mm256_sub_epi32(field(TileField::kX0), _mm256_set1_epi32(px0 << 4))),
      4);
  const __m256i y = _mm256_srai_epi32(
      _mm256_add_epi32(_mm256_srai_epi32(dot3(g01, g2, field(TileField::kMy01), field(TileField::kMy2)), 16),
                       _mm256_sub_epi32(field(TileField::kY0), _mm256_set1_epi32(py0 << 4))),
      4);
  const __m256i dshift = _mm256_srli_epi32(field(TileField::kCountShift), 16);
  const __m256i depth = _mm256_add_epi32(
      _mm256_srav_epi32(dot3(g01, g2, field(TileField::kDz01), field(TileField::kDz2)), dshift), field(TileField::kDepth0));
  __m256i rgb;
  if constexpr (!kColorPoints && !kShadePoints) {
    rgb = field(TileField::kNodeRgb);
  } else {
    const __m256i base = t.uniform_base ? _mm256_set1_epi32(static_cast<int32_t>(t.base_rgb)) : field(TileField::kBaseRgb);
    const __m256i mask8 = _mm256_set1_epi32(0xFF);
    __m256i ch[3] = {_mm256_and_si256(_mm256_srli_epi32(base, 16), mask8), _mm256_and_si256(_mm256_srli_epi32(base, 8), mask8),
                     _mm256_and_si256(base, mask8)};
    if constexpr (kColorPoints) {
      const __m256i q01 = sample(t.q01), q2 = sample(t.q2);
      #pragma GCC unroll 3
      for (int c = 0; c < 3; ++c) {
        const __m256i a01 = field(static_cast<TileField>(static_cast<int>(TileField::kCa01R) + c));
        const __m256i a2 = field(static_cast<TileField>(static_cast<int>(TileField::kCa2R) + c));
        const __m256i v = _mm256_add_epi32(ch[c], _mm256_srai_epi32(dot3(q01, q2, a01, a2), 19));
        ch[c] = _mm256_min_epi32(_mm256_max_epi32(v, _mm256_setzero_si256()), _mm256_set1_epi32(255));
      }
    }
    __m256i intensity, specular;
    if constexpr (kShadePoints) {
      __m256i al, be;
      if constexpr (kNormals == PointNormals::kSurface) {
        al = _mm256_srai_epi32(dot3(g01, g2, field(TileField::kS0_01), field(TileField::kS0_2)), 12);
        be = _mm256_srai_epi32(dot3(g01, g2, field(TileField::kS1_01), field(TileField::kS1_2)), 12);
      } else {
        // (sigma_n n) >> 12 per element.
        const __m256i nn = sample(t.n01), sn = field(TileField::kSn);
        al = _mm256_srai_epi32(_mm256_mullo_epi32(lo16(nn), lo16(sn)), 12);
        be = _mm256_srai_epi32(_mm256_mullo_epi32(hi16(nn), hi16(sn)), 12);
      }
      // Clamped to +-4 rad, as (al, be) pairs.
      const __m256i lim = _mm256_set1_epi32(16384), nlim = _mm256_set1_epi32(-16384);
      al = _mm256_min_epi32(_mm256_max_epi32(al, nlim), lim);
      be = _mm256_min_epi32(_mm256_max_epi32(be, nlim), lim);
      const __m256i ab = _mm256_or_si256(_mm256_and_si256(al, _mm256_set1_epi32(0xFFFF)), _mm256_slli_epi32(be, 16));
      // <= 4096: a cell of the table (kCosSincCells), no clamp.
      const __m256i cell = _mm256_srli_epi32(_mm256_madd_epi16(ab, ab), kCosSincShift);
      const __m256i cs = _mm256_i32gather_epi32(reinterpret_cast<const int*>(t.shading->cos_sinc), cell, 4);
      const __m256i l0h0 = field(TileField::kL0H0);
      const __m256i l0 = _mm256_and_si256(l0h0, _mm256_set1_epi32(0xFFFF)), h0 = _mm256_srli_epi32(l0h0, 16);
      const __m256i ambient = _mm256_set1_epi32(t.shading->ambient_q8);
      intensity = diffuse8(lit8(cs, ab, field(TileField::kLt), l0), ambient, _mm256_sub_epi32(_mm256_set1_epi32(256), ambient));
      specular = kSpecular ? gather(t.shading->specular, intensity_index8(lit8(cs, ab, field(TileField::kHt), h0)))
                           : _mm256_setzero_si256();
    } else {
      const __m256i li = field(TileField::kLighting);
      intensity = _mm256_and_si256(li, _mm256_set1_epi32(0xFFFF));
      specular = _mm256_srli_epi32(li, 16);
    }
    // The grey shortcut's frames (no model colour, a grey base): every
    // point's three channels are equal, so one is shaded.
    if (!kColorPoints && t.grey_shade != nullptr) {
      rgb = _mm256_mullo_epi32(shade_channel(ch[2], intensity, specular), _mm256_set1_epi32(0x010101));
    } else {
      rgb = _mm256_or_si256(_mm256_or_si256(_mm256_slli_epi32(shade_channel(ch[0], intensity, specular), 16),
                                            _mm256_slli_epi32(shade_channel(ch[1], intensity, specular), 8)),
                            shade_channel(ch[2], intensity, specular));
    }
  }
  alignas(32) int32_t xs[8], ys[8];
  alignas(32) Word ws[8];
  if constexpr (sizeof(Word) == 4) {
    _mm256_store_si256(reinterpret_cast<__m256i*>(ws),
                       _mm256_or_si256(_mm256_and_si256(depth, _mm256_set1_epi32(static_cast<int32_t>(0xFFFF0000u))), rgb565_8(rgb)));
  } else {
    const __m256i lo = _mm256_unpacklo_epi32(rgb, depth), hi = _mm256_unpackhi_epi32(rgb, depth);
    _mm256_store_si256(reinterpret_cast<__m256i*>(ws), _mm256_permute2x128_si256(lo, hi, 0x20));
    _mm256_store_si256(reinterpret_cast<__m256i*>(ws) + 1, _mm256_permute2x128_si256(lo, hi, 0x31));
  }
  _mm256_store_si256(reinterpret_cast<__m256i*>(xs), x);
  _mm256_store_si256(reinterpret_cast<__m256i*>(ys), y);
  alignas(32) int32_t offs[8];
  _mm256_store_si256(reinterpret_cast<__m256i*>(offs), add_offsets(x, y, tile_log2));
  // Which lanes' squares lie wholly inside the tile (drawn unclipped),
  // which wholly outside it (a node across tiles: drawn in the other).
  const int tile = 1 << tile_log2;
  const __m256i lim = _mm256_set1_epi32(tile - kSize + 1), neg = _mm256_set1_epi32(-1);
  const __m256i in = _mm256_and_si256(
      _mm256_and_si256(_mm256_cmpgt_epi32(x, neg), _mm256_cmpgt_epi32(lim, x)),
      _mm256_and_si256(_mm256_cmpgt_epi32(y, neg), _mm256_cmpgt_epi32(lim, y)));
  const __m256i lo = _mm256_set1_epi32(-kSize + 1), hi = _mm256_set1_epi32(tile);
  const __m256i touches = _mm256_and_si256(
      _mm256_and_si256(_mm256_cmpgt_epi32(x, _mm256_sub_epi32(lo, _mm256_set1_epi32(1))), _mm256_cmpgt_epi32(hi, x)),
      _mm256_and_si256(_mm256_cmpgt_epi32(y, _mm256_sub_epi32(lo, _mm256_set1_epi32(1))), _mm256_cmpgt_epi32(hi, y)));
  const uint32_t inside = static_cast<uint32_t>(_mm256_movemask_ps(_mm256_castsi256_ps(in)));
  const uint32_t touching = static_cast<uint32_t>(_mm256_movemask_ps(_mm256_castsi256_ps(touches)));
  const uint32_t wh = static_cast<uint32_t>(kSize | kSize << 4);
  const uint32_t lanes = (1u << active) - 1u;
  if ((inside & lanes) == 0xFFu) {  // nearly always: eight squares, no lanes to pick
#pragma GCC unroll 8
    for (int k = 0; k < 8; ++k) ztest_fixed<kSize>(words + offs[k], tile_log2, ws[k]);
    return;
  }
  for (uint32_t m = inside & lanes; m != 0; m &= m - 1) {
    const int k = __builtin_ctz(m);
    ztest_fixed<kSize>(words + offs[k], tile_log2, ws[k]);
  }
  for (uint32_t m = touching & ~inside & lanes; m != 0; m &= m - 1) {
    const int k = __builtin_ctz(m);
    ztest_point(words, tile_log2, kSize, wh, false, xs[k], ys[k], ws[k]);
  }
}

}  // namespace

// All of a node's samples, 8 at a time in lanes of their own — fewer than
// 8 in one run with the rest of its lanes idle. The last run of a node of
// 8 or more ends at its last sample, so it may draw again some of the run
// before it: a point drawn twice leaves the same words, the z-test keeping
// the lesser (depth, colour) word.
template <PointNormals kNormals, bool kColorPoints, bool kSpecular, int kSize, class Word>
[[gnu::noinline]] void draw_runs(const TileNodes& nodes, uint32_t node, uint32_t count, const PointTables& t,
                                 Word* words, int tile_log2, int px0, int py0) {
  alignas(32) int32_t run_row[8] = {static_cast<int32_t>(node * kTileStride)}, run_j[8] = {};
  if (count < 8) {
    draw_lanes<kNormals, kColorPoints, kSpecular, kSize, true>(nodes, run_row, run_j, count, t, words, tile_log2, px0, py0);
    return;
  }
  for (uint32_t j = 0; j < count; j += 8) {
    run_j[0] = static_cast<int32_t>(j + 8 <= count ? j : count - 8);
    draw_lanes<kNormals, kColorPoints, kSpecular, kSize, true>(nodes, run_row, run_j, 8, t, words, tile_log2, px0, py0);
  }
}

// The fewest samples a node draws in runs of its own rather than filed
// with other nodes' (whose fields are gathered lane by lane). Runs with
// idle lanes cost instructions and save gathers; measured on the dragon
// at 640x480 (one core, median of 7; callgrind), a threshold of 4 rather
// than 8 takes 1 px points from 4.89 to 4.61 ms a frame for 29.05 ->
// 30.80 M instructions, and 2 px points from 3.66 to 3.57 ms for 18.30 ->
// 18.67 M — past the 18.6 M that issue 15 holds the 2 px frame to, so
// only 1 px points, four times as many a node, take the lower threshold.
template <int kSize>
inline constexpr uint32_t kRunMin = kSize == 1 ? 4 : 8;

template <PointNormals kNormals, bool kColorPoints, bool kSpecular, int kSize, class Word>
void draw_tile_sized(const TileNodes& nodes, const uint32_t* list, uint32_t n, const PointTables& t, Word* words,
                     int tile_log2, int px0, int py0) {
  // The lanes are filed 8 at a time from each node's run of samples; the
  // buffers hold 16 so that a run's store may overrun the 8 in use.
  alignas(32) int32_t lane_row[16] = {}, lane_j[16] = {};
  const __m256i iota = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  uint32_t k = 0;
  for (uint32_t i = 0; i < n; ++i) {
    const uint32_t node = list[i];
    const int32_t row = static_cast<int32_t>(node * kTileStride);
    const uint32_t count = nodes.row(node)[static_cast<int>(TileField::kCountShift)] & 0xFFFFu;
    if (count >= kRunMin<kSize>) {
      draw_runs<kNormals, kColorPoints, kSpecular, kSize>(nodes, node, count, t, words, tile_log2, px0, py0);
      continue;
    }
    // A smaller node is filed with other nodes'.
    if (count <= 8 - k) {  // the node's run fits the lanes left (most small nodes)
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(lane_row + k), _mm256_set1_epi32(row));
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(lane_j + k), iota);
      k += count;
      if (k == 8) {
        draw_lanes<kNormals, kColorPoints, kSpecular, kSize, false>(nodes, lane_row, lane_j, 8, t, words, tile_log2, px0, py0);
        k = 0;
      }
      continue;
    }
    for (uint32_t j = 0; j < count;) {
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(lane_row + k), _mm256_set1_epi32(row));
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(lane_j + k),
                          _mm256_add_epi32(_mm256_set1_epi32(static_cast<int32_t>(j)), iota));
      const uint32_t take = count - j < 8 - k ? count - j : 8 - k;
      k += take;
      j += take;
      if (k == 8) {
        draw_lanes<kNormals, kColorPoints, kSpecular, kSize, false>(nodes, lane_row, lane_j, 8, t, words, tile_log2, px0, py0);
        k = 0;
      }
    }
  }
  if (k > 0) draw_lanes<kNormals, kColorPoints, kSpecular, kSize, false>(nodes, lane_row, lane_j, k, t, words, tile_log2, px0, py0);
}

template <PointNormals kNormals, bool kColorPoints, bool kSpecular, class Word>
void draw_tile(const TileNodes& nodes, const uint32_t* list, uint32_t n, const PointTables& t, int size, Word* words,
               int tile_log2, int px0, int py0) {
  switch (size) {
    case 1: return draw_tile_sized<kNormals, kColorPoints, kSpecular, 1>(nodes, list, n, t, words, tile_log2, px0, py0);
    case 2: return draw_tile_sized<kNormals, kColorPoints, kSpecular, 2>(nodes, list, n, t, words, tile_log2, px0, py0);
    default: return draw_tile_sized<kNormals, kColorPoints, kSpecular, 3>(nodes, list, n, t, words, tile_log2, px0, py0);
  }
}

void clear_words(uint64_t* words, size_t count, uint64_t word) {
  const __m256i w = _mm256_set1_epi64x(static_cast<long long>(word));
  size_t i = 0;
  for (; i + 4 <= count; i += 4) _mm256_storeu_si256(reinterpret_cast<__m256i*>(words + i), w);
  for (; i < count; ++i) words[i] = word;
}

void clear_words(uint32_t* words, size_t count, uint32_t word) {
  const __m256i w = _mm256_set1_epi32(static_cast<int32_t>(word));
  size_t i = 0;
  for (; i + 8 <= count; i += 8) _mm256_storeu_si256(reinterpret_cast<__m256i*>(words + i), w);
  for (; i < count; ++i) words[i] = word;
}

// RGB888: 8 words' colours (0x00RRGGBB in each word's low half) gathered
// into one register, each 128-bit half shuffled to R, G, B bytes (12 of
// 16), stored as 12 + 12 bytes (the first half's 4 spare bytes are
// overwritten by the second half's).
void store_row(const uint64_t* row, int pixels, uint8_t* out) {
  const __m256i low = _mm256_setr_epi32(0, 2, 4, 6, 0, 2, 4, 6);
  const __m256i bytes = _mm256_setr_epi8(2, 1, 0, 6, 5, 4, 10, 9, 8, 14, 13, 12, -1, -1, -1, -1,  //
                                         2, 1, 0, 6, 5, 4, 10, 9, 8, 14, 13, 12, -1, -1, -1, -1);
  int x = 0;
  for (; x + 8 <= pixels; x += 8, out += 24) {
    const __m256i a = _mm256_permutevar8x32_epi32(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(row + x)), low);
    const __m256i b = _mm256_permutevar8x32_epi32(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(row + x + 4)), low);
    const __m256i rgb = _mm256_shuffle_epi8(_mm256_blend_epi32(a, b, 0xF0), bytes);
    const __m128i hi = _mm256_extracti128_si256(rgb, 1);
    _mm_storeu_si128(reinterpret_cast<__m128i*>(out), _mm256_castsi256_si128(rgb));
    _mm_storel_epi64(reinterpret_cast<__m128i*>(out + 12), hi);
    const int32_t last = _mm_extract_epi32(hi, 2);
    std::memcpy(out + 20, &last, 4);
  }
  for (; x < pixels; ++x, out += 3) {
    out[0] = static_cast<uint8_t>(row[x] >> 16);
    out[1] = static_cast<uint8_t>(row[x] >> 8);
    out[2] = static_cast<uint8_t>(row[x]);
  }
}

// RGB565: the low halves of 16 words, packed to 16-bit pixels in order.
void store_row(const uint32_t* row, int pixels, uint8_t* out) {
  const __m256i mask = _mm256_set1_epi32(0xFFFF);
  int x = 0;
  for (; x + 16 <= pixels; x += 16, out += 32) {
    const __m256i a = _mm256_and_si256(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(row + x)), mask);
    const __m256i b = _mm256_and_si256(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(row + x + 8)), mask);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(out), _mm256_permute4x64_epi64(_mm256_packus_epi32(a, b), 0xD8));
  }
  for (; x < pixels; ++x, out += 2) {
    out[0] = static_cast<uint8_t>(row[x]);
    out[1] = static_cast<uint8_t>(row[x] >> 8);
  }
}

#define STIPPLE_DRAW_TILE(N, C, S, W)                                                                                 \
  template void draw_tile<PointNormals::N, C, S, W>(const TileNodes&, const uint32_t*, uint32_t, const PointTables&, int, \
                                                    W*, int, int, int);
#define STIPPLE_DRAW_TILE_N(N)              \
  STIPPLE_DRAW_TILE(N, false, false, uint32_t) \
  STIPPLE_DRAW_TILE(N, false, true, uint32_t)  \
  STIPPLE_DRAW_TILE(N, true, false, uint32_t)  \
  STIPPLE_DRAW_TILE(N, true, true, uint32_t)   \
  STIPPLE_DRAW_TILE(N, false, false, uint64_t) \
  STIPPLE_DRAW_TILE(N, false, true, uint64_t)  \
  STIPPLE_DRAW_TILE(N, true, false, uint64_t)  \
  STIPPLE_DRAW_TILE(N, true, true, uint64_t)
STIPPLE_DRAW_TILE_N(kNode)
STIPPLE_DRAW_TILE_N(kSampled)
STIPPLE_DRAW_TILE_N(kSurface)
#undef STIPPLE_DRAW_TILE_N
#undef STIPPLE_DRAW_TILE

}  // namespace avx2
}  // namespace stipple

#endif
