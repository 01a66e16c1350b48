// stipple raster — the tile pass's point loop in NEON lanes (ARMv7-A with
// NEON, AArch64), four samples of one node at a time. Included by
// point_kernel.h; the formula and every bound are that header's, and each
// step below is the scalar one in lanes: the int16 samples, de-interleaved
// as they load, times the node's int16 terms in widening multiply-adds
// (exact in int32), saturating narrows where the scalar code clamps to
// int16, and the tables read lane by lane. The bytes are the scalar loop's
// (tests/portable/point_kernel_test.cpp, run on each target under qemu).
#pragma once

#include <arm_neon.h>

#include <cstring>

namespace stipple {
namespace neon {

// Four samples' (first, second) int16 of a paired table, de-interleaved.
inline int16x4x2_t load_pairs(const uint32_t* p) { return vld2_s16(reinterpret_cast<const int16_t*>(p)); }

// a0 g0 + a1 g1 + a2 g2 for four samples.
inline int32x4_t dot3(int16x4_t g0, int16x4_t g1, int16x4_t g2, int16_t a0, int16_t a1, int16_t a2) {
  return vmlal_n_s16(vmlal_n_s16(vmull_n_s16(g0, a0), g1, a1), g2, a2);
}

template <class Entry>
inline uint32x4_t gather(const Entry* table, int32x4_t idx) {
  const uint32_t v[4] = {table[vgetq_lane_s32(idx, 0)], table[vgetq_lane_s32(idx, 1)], table[vgetq_lane_s32(idx, 2)],
                         table[vgetq_lane_s32(idx, 3)]};
  return vld1q_u32(v);
}
inline int32x4_t gather(const CosSincQ14* table, int32x4_t idx) {
  int32_t v[4];
  std::memcpy(&v[0], &table[vgetq_lane_s32(idx, 0)], 4);
  std::memcpy(&v[1], &table[vgetq_lane_s32(idx, 1)], 4);
  std::memcpy(&v[2], &table[vgetq_lane_s32(idx, 2)], 4);
  std::memcpy(&v[3], &table[vgetq_lane_s32(idx, 3)], 4);
  return vld1q_s32(v);
}

inline int32x4_t intensity_index4(int32x4_t l) {
  const int32x4_t i = vshrq_n_s32(vaddq_s32(l, vdupq_n_s32(kIntensityOffsetQ14)), 7);
  return vminq_s32(vmaxq_s32(i, vdupq_n_s32(0)), vdupq_n_s32(kIntensityEntries - 1));
}

// L.n in Q14 (lit_index, before its table index): (cos n0 + sinc ((al t1
// + be t2) >> 14)) >> 12, `cs` holding (cos, sinc) int16 pairs.
inline int32x4_t lit4(int32x4_t cs, int32x4_t al, int32x4_t be, int16_t t1, int16_t t2, int16_t n0) {
  const int32x4_t along = vshrq_n_s32(vmlaq_n_s32(vmulq_n_s32(al, t1), be, t2), 14);
  const int32x4_t cosine = vshrq_n_s32(vshlq_n_s32(cs, 16), 16), sinc = vshrq_n_s32(cs, 16);
  return vshrq_n_s32(vmlaq_s32(vmulq_n_s32(cosine, n0), sinc, along), 12);
}

inline uint32x4_t shade_channel(uint32x4_t c, uint32x4_t intensity, uint32x4_t specular) {
  return vminq_u32(vaddq_u32(vshrq_n_u32(vmulq_u32(c, intensity), 8), specular), vdupq_n_u32(255));
}

inline uint32x4_t rgb565_4(uint32x4_t rgb) {
  return vorrq_u32(vorrq_u32(vandq_u32(vshrq_n_u32(rgb, 8), vdupq_n_u32(0xF800)), vandq_u32(vshrq_n_u32(rgb, 5), vdupq_n_u32(0x07E0))),
                   vandq_u32(vshrq_n_u32(rgb, 3), vdupq_n_u32(0x001F)));
}

template <PointNormals kNormals, bool kColorPoints, bool kSpecular, class Word>
void draw_tile_node(const TileRow& n, const PointTables& t, int size, Word* words, int tile_log2, int px0, int py0) {
  constexpr bool kShadePoints = kNormals != PointNormals::kNode;
  const int tile = 1 << tile_log2;
  const bool inside = n.inside_tile(px0, py0, tile);
  const uint32_t wh = static_cast<uint32_t>(size | size << 4);
  const int32x4_t x0 = vdupq_n_s32(n.x0_q4() - (px0 << 4)), y0 = vdupq_n_s32(n.y0_q4() - (py0 << 4));
  const uint32x4_t depth0 = vdupq_n_u32(n.depth0());
  const int32x4_t dshift = vdupq_n_s32(-static_cast<int32_t>(n.dshift()));
  const uint32_t count = n.count();
  // The node's int16 terms: (first, second) of each pair word.
  const int16_t mx[3] = {n.lo(TileField::kMx01), n.hi(TileField::kMx01), n.lo(TileField::kMx2)};
  const int16_t my[3] = {n.lo(TileField::kMy01), n.hi(TileField::kMy01), n.lo(TileField::kMy2)};
  const int16_t dz[3] = {n.lo(TileField::kDz01), n.hi(TileField::kDz01), n.lo(TileField::kDz2)};
  const int16_t sn[2] = {n.lo(TileField::kSn), n.hi(TileField::kSn)};
  const int16_t lt[2] = {n.lo(TileField::kLt), n.hi(TileField::kLt)}, ht[2] = {n.lo(TileField::kHt), n.hi(TileField::kHt)};
  const int16_t l0 = n.lo(TileField::kL0H0), h0 = n.hi(TileField::kL0H0);
  const int16_t surface[2][3] = {{n.lo(TileField::kS0_01), n.hi(TileField::kS0_01), n.lo(TileField::kS0_2)},
                                 {n.lo(TileField::kS1_01), n.hi(TileField::kS1_01), n.lo(TileField::kS1_2)}};
  int16_t ca[3][3];
  for (int c = 0; c < 3; ++c) {
    ca[0][c] = n.lo(static_cast<TileField>(static_cast<int>(TileField::kCa01R) + c));
    ca[1][c] = n.hi(static_cast<TileField>(static_cast<int>(TileField::kCa01R) + c));
    ca[2][c] = n.lo(static_cast<TileField>(static_cast<int>(TileField::kCa2R) + c));
  }
  const uint32_t base_rgb = n[TileField::kBaseRgb], node_rgb = n[TileField::kNodeRgb];
  uint32x4_t base[3];
  for (int c = 0; c < 3; ++c) base[c] = vdupq_n_u32((base_rgb >> (16 - 8 * c)) & 0xFFu);
  const uint32x4_t node_intensity = vdupq_n_u32(n[TileField::kLighting] & 0xFFFFu);
  const uint32x4_t node_specular = vdupq_n_u32(n[TileField::kLighting] >> 16);
  alignas(16) int32_t xs[4], ys[4];
  alignas(16) Word ws[4];
  for (uint32_t j = 0; j < count; j += 4) {
    const int16x4x2_t g01 = load_pairs(t.g01 + j), g2p = load_pairs(t.g2 + j);
    const int16x4_t g0 = g01.val[0], g1 = g01.val[1], g2 = g2p.val[0];
    const int32x4_t x = vshrq_n_s32(vaddq_s32(vshrq_n_s32(dot3(g0, g1, g2, mx[0], mx[1], mx[2]), 16), x0), 4);
    const int32x4_t y = vshrq_n_s32(vaddq_s32(vshrq_n_s32(dot3(g0, g1, g2, my[0], my[1], my[2]), 16), y0), 4);
    const uint32x4_t depth =
        vaddq_u32(vreinterpretq_u32_s32(vshlq_s32(dot3(g0, g1, g2, dz[0], dz[1], dz[2]), dshift)), depth0);
    uint32x4_t rgb;
    if constexpr (!kColorPoints && !kShadePoints) {
      rgb = vdupq_n_u32(node_rgb);
    } else {
      uint32x4_t ch[3] = {base[0], base[1], base[2]};
      if constexpr (kColorPoints) {
        const int16x4x2_t q01 = load_pairs(t.q01 + j), q2p = load_pairs(t.q2 + j);
        for (int c = 0; c < 3; ++c) {
          const int32x4_t v = vaddq_s32(vreinterpretq_s32_u32(base[c]),
                                        vshrq_n_s32(dot3(q01.val[0], q01.val[1], q2p.val[0], ca[0][c], ca[1][c], ca[2][c]), 19));
          ch[c] = vreinterpretq_u32_s32(vminq_s32(vmaxq_s32(v, vdupq_n_s32(0)), vdupq_n_s32(255)));
        }
      }
      uint32x4_t intensity = node_intensity, specular = node_specular;
      if constexpr (kShadePoints) {
        int32x4_t al, be;
        if constexpr (kNormals == PointNormals::kSurface) {
          al = vshrq_n_s32(dot3(g0, g1, g2, surface[0][0], surface[0][1], surface[0][2]), 12);
          be = vshrq_n_s32(dot3(g0, g1, g2, surface[1][0], surface[1][1], surface[1][2]), 12);
        } else {
          const int16x4x2_t nn = load_pairs(t.n01 + j);
          al = vshrq_n_s32(vmull_n_s16(nn.val[0], sn[0]), 12);
          be = vshrq_n_s32(vmull_n_s16(nn.val[1], sn[1]), 12);
        }
        const int32x4_t lim = vdupq_n_s32(16384), nlim = vdupq_n_s32(-16384);
        al = vminq_s32(vmaxq_s32(al, nlim), lim);
        be = vminq_s32(vmaxq_s32(be, nlim), lim);
        // <= 4096: a cell of the table (kCosSincCells), no clamp.
        const uint32x4_t cell = vshrq_n_u32(vreinterpretq_u32_s32(vmlaq_s32(vmulq_s32(al, al), be, be)), kCosSincShift);
        const int32x4_t cs = gather(t.shading->cos_sinc, vreinterpretq_s32_u32(cell));
        intensity = gather(t.shading->diffuse, intensity_index4(lit4(cs, al, be, lt[0], lt[1], l0)));
        specular = kSpecular ? gather(t.shading->specular, intensity_index4(lit4(cs, al, be, ht[0], ht[1], h0)))
                             : vdupq_n_u32(0);
      }
      rgb = vorrq_u32(vorrq_u32(vshlq_n_u32(shade_channel(ch[0], intensity, specular), 16),
                                vshlq_n_u32(shade_channel(ch[1], intensity, specular), 8)),
                      shade_channel(ch[2], intensity, specular));
    }
    if constexpr (sizeof(Word) == 4) {
      vst1q_u32(reinterpret_cast<uint32_t*>(ws), vorrq_u32(vandq_u32(depth, vdupq_n_u32(0xFFFF0000u)), rgb565_4(rgb)));
    } else {
      vst2q_u32(reinterpret_cast<uint32_t*>(ws), uint32x4x2_t{{rgb, depth}});  // (rgb, depth) pairs: the 64-bit words
    }
    vst1q_s32(xs, x);
    vst1q_s32(ys, y);
    const uint32_t lanes = count - j < 4 ? count - j : 4;
    for (uint32_t k = 0; k < lanes; ++k) ztest_point(words, tile_log2, size, wh, inside, xs[k], ys[k], ws[k]);
  }
}

}  // namespace neon
}  // namespace stipple
