// stipple raster — EWA splatting in the fixed-point client (TOG05 §8.4's
// quality mode; `--splat ewa`), as the GL client does it (docs/viewers.md
// "EWA splatting"): each drawn node is also an elliptical Gaussian splat of
// its two main axes, in the three passes of Botsch, Hornung, Zwicker and
// Kobbelt (PBG 2005) —
//   visibility:    each splat's core (kEwaCore sigma) pushed back by one
//                  radius writes the nearest depth a pixel's splats reach;
//   accumulation:  every splat within kEwaCut sigma and no deeper adds
//                  w = exp(-r^2 / 2) times the pixel's shaded colour (its
//                  normal turned by the pixel's place in the splat, as
//                  surface normals turn a point's), and w;
//   normalization: the colour is the sums' ratio.
// A splat is the close-up disc's ray cast (close_up.h): perspective
// correct, the object-space EWA of Ren, Pfister and Zwicker (2002), each
// radius widened to at least a pixel's footprint (sqrt(sigma^2 + p^2), p a
// pixel at the node's depth) — their approximation of EWA's screen-space
// low-pass filter. Which pixels are covered comes from the points, drawn
// first as in the default mode (the splats' own outline at a weight or a
// radius put 2-4 % of the pixels outside the silhouette in the GL client):
// the splats give the colour wherever their weight reaches.
//
// Per tile, after its points and discs, over every splat whose box meets
// it; the sums in a scratch of 20 bytes a pixel of a tile (80 KB for 64 x
// 64 tiles: more than the handheld's arena has to spare, docs/fixed_point.md
// "EWA"). Integer throughout: the weights a table made at compile time, one
// division a channel per covered pixel.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "raster/close_up.h"
#include "raster/point_raster.h"

namespace stipple {

inline constexpr int kEwaCut = 3;                       // sigmas: the accumulation's radius
inline constexpr int32_t kEwaCore_q12 = 3 << 11;        // 1.5 sigma: the visibility pass's
inline constexpr int kEwaWeightShift = 17;              // r^2 (Q24) >> 17: 1/128 sigma^2 a step
inline constexpr int kEwaWeights = ((kEwaCut * kEwaCut) << (24 - kEwaWeightShift)) + 1;
inline constexpr uint32_t kEwaWeightOne = 1u << 12;     // w at the centre
// Beyond this weight a pixel's sums stop growing (a hostile file's
// thousands of coincident splats): the colour sums stay below 2^32.
inline constexpr uint32_t kEwaWeightMost = 1u << 23;

// w_i = exp(-r^2 / 2) at r^2 = i / 128: exp(-1/256)^i, in integers (Q30,
// rounded; the series of exp(-1/256) to 1e-18), Q12 — the same table on
// every target, made at compile time.
constexpr std::array<uint16_t, kEwaWeights> ewa_weight_table() {
  static_assert(kEwaWeightShift == 17, "the step exp(-1/256) is r^2 = 1/128 sigma^2");
  constexpr int64_t kOne = int64_t{1} << 30;
  int64_t step = kOne, term = kOne;
  for (int k = 1; k < 6; ++k) {
    term = -term / (256 * k);
    step += term;
  }
  std::array<uint16_t, kEwaWeights> w{};
  int64_t p = kOne;
  for (int i = 0; i < kEwaWeights; ++i) {
    w[i] = static_cast<uint16_t>((p * kEwaWeightOne + kOne / 2) >> 30);
    p = (p * step + kOne / 2) >> 30;
  }
  return w;
}
inline constexpr std::array<uint16_t, kEwaWeights> kEwaWeight = ewa_weight_table();

// A splat: its disc (close_up.h, the sigmas widened) and how far the
// visibility pass pushes it back, in depth words.
struct Splat {
  CloseUp disc;
  uint32_t push;
};

// Bytes of a tile's sums: the visibility depth, the weight and three
// channels, 4 bytes each a pixel.
constexpr size_t ewa_tile_bytes(int tile_log2) { return size_t{20} << (2 * tile_log2); }

// Sets splat `out` up for a node (as set_up_close_up: its camera-space
// mean `c`, axes `frame`, sigmas `sigma`), each tangent sigma widened by a
// pixel's footprint at its depth; false when it is none (edge on through
// the eye, behind the near plane, off screen). The shade is the caller's.
bool set_up_splat(const CloseUpFrame& f, const int32_t c[3], const int16_t frame[3][3], const int32_t sigma[3],
                  Splat* out);

// The three passes over one tile's words (after its points; `words` in
// pack_word's format, 2^tile_log2 a row, pw x ph of them on screen from
// px0, py0), with `sums` (ewa_tile_bytes) to work in.
template <PointNormals kNormals, bool kSpecular, class Word>
void draw_splats(const Splat* splats, uint32_t count, const PointTables& t, const uint16_t* reciprocal, int px0, int py0,
                 int pw, int ph, int tile_log2, Word* words, uint32_t* sums) {
  const size_t pixels = size_t{1} << (2 * tile_log2);
  uint32_t* visible = sums;
  uint32_t* weight = sums + pixels;
  uint32_t* channel = sums + 2 * pixels;  // 3 a pixel
  for (int y = 0; y < ph; ++y)
    for (int x = 0; x < pw; ++x) {
      const size_t at = (size_t{static_cast<uint32_t>(y)} << tile_log2) + static_cast<uint32_t>(x);
      visible[at] = 0xFFFFFFFFu;
      weight[at] = channel[3 * at] = channel[3 * at + 1] = channel[3 * at + 2] = 0;
    }
  for (uint32_t i = 0; i < count; ++i) {
    const Splat& s = splats[i];
    for_each_close_up_pixel<kEwaCore_q12>(s.disc, reciprocal, px0, py0, pw, ph, tile_log2,
                                          [&](int at, int32_t, int32_t, uint32_t depth) __attribute__((always_inline)) {
                                            const uint32_t back = depth > 0xFFFFFFFEu - s.push ? 0xFFFFFFFEu : depth + s.push;
                                            if (back < visible[at]) visible[at] = back;
                                          });
  }
  for (uint32_t i = 0; i < count; ++i) {
    const Splat& s = splats[i];
    for_each_close_up_pixel<(kEwaCut << 12)>(
        s.disc, reciprocal, px0, py0, pw, ph, tile_log2,
        [&](int at, int32_t uu, int32_t vv, uint32_t depth) __attribute__((always_inline)) {
          if (depth > visible[at] || weight[at] >= kEwaWeightMost) return;
          const uint32_t w = kEwaWeight[static_cast<uint32_t>(uu * uu + vv * vv) >> kEwaWeightShift];
          uint32_t color;
          if constexpr (kNormals == PointNormals::kSurface)
            color = point_color<kNormals, false, kSpecular, false>(s.disc.shade, t, 0, int16_pair(uu, vv), 0);
          else
            color = s.disc.shade.node_rgb;
          weight[at] += w;
          channel[3 * at] += w * (color >> 16 & 0xFFu);
          channel[3 * at + 1] += w * (color >> 8 & 0xFFu);
          channel[3 * at + 2] += w * (color & 0xFFu);
        });
  }
  for (int y = 0; y < ph; ++y) {
    Word* row = words + (y << tile_log2);
    for (int x = 0; x < pw; ++x) {
      const size_t at = (size_t{static_cast<uint32_t>(y)} << tile_log2) + static_cast<uint32_t>(x);
      const uint32_t w = weight[at];
      if (w == 0 || !word_covered(row[x])) continue;  // no splat here, or no point covers it
      const uint32_t half = w / 2;
      const uint32_t rgb = ((channel[3 * at] + half) / w) << 16 | ((channel[3 * at + 1] + half) / w) << 8 |
                           ((channel[3 * at + 2] + half) / w);
      row[x] = recolour_word(row[x], sizeof(Word) == 4 ? uint32_t{rgb565(rgb)} : rgb);
    }
  }
}

}  // namespace stipple
