// stipple raster — close-ups: a node larger on screen than its samples can
// cover, drawn as its 3 sigma ellipse.
//
// A node's points are at most RendererConfig::samples, so a node seen
// closer than its samples' spacing — a leaf of a scan seen from a tenth of
// its point spacing — shows as dots over black. Such a node (its screen
// sigma past kCloseUpSigmaPx, or reaching into the view from a mean
// outside it) is drawn instead as the disc of radius 3 sigma in its
// tangent plane (its two larger axes), opaque, every pixel of it found by
// casting the pixel's ray at that plane: perspective correct, as the GL
// client's discs (docs/viewers.md "Points per node, close-ups"). 3 sigma,
// not 2: a leaf of a regular grid is a rectangle whose corner lies at 2.7
// sigma, and four leaves meeting at a corner left a hole at 2 and 2.5.
//
// The ray through pixel (x, y) has direction d = (x + 1/2 - cx, y + 1/2 -
// cy, f) in camera space (pixels). It meets the plane through the mean c
// with unit normal n at p = s d, s = (n.c) / (n.d); the hit's place in
// the disc, in sigmas along the tangents t1, t2, is
//   u = t1.(p - c) / sigma1 = U / W,  U = E1.d,  E1 = ((n.c) t1 - (t1.c) n) / sigma1
// (v likewise) with W = n.d: U, V and W are affine in the pixel, so a row
// costs three additions a pixel, one reciprocal (the projection's 1024
// entry table) and two multiplies give u and v, and u^2 + v^2 <= 9 is the
// disc. The hit's depth is z = (n.c) f / W, from the same reciprocal.
// (u, v, 0) is a position sample in sigmas (Q12): surface normals turn the
// normal by it exactly as they turn a point's (point_kernel.h), so a disc
// is shaded per pixel as its points would be; its colour is the node's mean
// (the GL client's discs are the same).
//
// Integer throughout, no division per pixel (two per node, four more for
// its bounding box), nothing allocated: the renderer keeps a frame's discs
// in its arena (close_up_capacity) and draws them in the tile pass, after
// the tile's points. docs/fixed_point.md "Close-ups" gives the ranges and
// the measured cost.
#pragma once

#include <cstdint>

#include "core/camera.h"
#include "raster/point_kernel.h"

namespace stipple {

// A node becomes a disc when its screen covariance's determinant passes
// this sigma's fourth power (the geometric mean of its screen sigmas),
// as the GL client's kDiscSigma.
inline constexpr int kCloseUpSigmaLog2 = 3;
inline constexpr int kCloseUpSigmaPx = 1 << kCloseUpSigmaLog2;
inline constexpr int kCloseUpCut = 3;  // the disc's radius, sigmas
// How a disc is shaded: with surface normals as its points; otherwise
// (sampled or per-node normals) by its mean normal.
constexpr PointNormals close_up_normals(PointNormals n) {
  return n == PointNormals::kSurface ? n : PointNormals::kNode;
}
// Below the discs, a node whose screen sigmas' geometric mean passes 1 px
// — past the cut's size, so a leaf seen close — draws this many times the
// points its table count says (Q8, capped at the samples): the table's 95 %
// of the 2 sigma ellipse leaves holes wider than the resolve's pinholes
// there. Measured against the scans at 640 x 480 (docs/viewers.md): 1.5x
// and 2x past 1 px, 2x past 2 px, and 1.5x to 2 px then 2x; 2x past 1 px
// closed the dragon's close-up best (3.87 % of its pixels missing, 0.83 %:
// the far views' share) and moved no far view of the dragon.
inline constexpr int kCloseUpPointsLog2 = 0;
inline constexpr uint32_t kCloseUpPointsScale_q8 = 512;

// A frame's discs: one for every 512 pixels of the (internal) screen, and
// 32. A disc is at least 8 px sigma, a leaf of a regular grid about 5
// sigma a side: some 50 fill a 240 x 320 screen, 182 are three layers of
// them and more (the handheld's arena: 27.7 KB).
inline uint32_t close_up_capacity(uint32_t width, uint32_t height) { return width * height / 512 + 32; }

// One disc, as the tile pass reads it.
struct CloseUp {
  int16_t box[4];             // pixels covered, inclusive: x lo, x hi, y lo, y hi
  int32_t ax, ay, bx, by, nx, ny;  // U, V, W per pixel along x and y
  int64_t u00, v00, w00;      // U, V, W at pixel (0, 0)
  int8_t ku, kv;              // u = (U r) >> (e + ku) in Q12, r ~ 2^(e+15) / W
  int8_t kz;                  // the depth word = ((zm r) << (kz - e)) - near_word
  int32_t zm;                 // (n.c) f, its top bits (kz says where)
  int64_t near_word;          // near << depth shift
  PackedShade shade;
};

// What the disc's set-up needs of the frame.
struct CloseUpFrame {
  int32_t focal_q4, cx_q4, cy_q4, near;
  int32_t width, height;      // the internal screen, pixels
  int depth_shift;
};

// Sets a disc up from the node's camera-space mean `c` (MU), its axes
// `frame` (Q14 unit vectors, camera space) and sigmas `sigma` (MU). False
// when it is no disc: seen edge on through the eye, degenerate, or wholly
// off screen. The shade is the caller's to fill.
bool set_up_close_up(const CloseUpFrame& f, const int32_t c[3], const int16_t frame[3][3], const int32_t sigma[3],
                     CloseUp* out);

// Whether a node whose mean is outside the view (NodeProjection::in_view)
// may still reach into it: its 3 sigma ball (the largest sigma) meets the
// space beyond the near plane and inside the ~165 degree cone.
inline bool close_up_reaches(const Camera& camera, const int32_t c[3], int32_t largest_sigma) {
  const int64_t r = int64_t{kCloseUpCut} * largest_sigma, z = int64_t{c[2]} + r;
  const auto abs = [](int64_t v) { return v < 0 ? -v : v; };
  return z > camera.near_mu && abs(c[0]) - r <= 8 * z && abs(c[1]) - r <= 8 * z;
}

// Calls fn(at, u, v, depth) for each pixel of a tile (the tile's first
// pixel px0, py0; pw x ph of its pixels on screen; 2^tile_log2 a row) whose
// ray meets the plane of `s` within kCut (Q12 sigmas) of its mean, beyond
// the near plane: `at` the pixel's place in the tile, u, v the hit's place
// in sigmas (Q12), depth its depth word.
template <int32_t kCut, class Fn>
[[gnu::always_inline]] inline void for_each_close_up_pixel(const CloseUp& s, const uint16_t* reciprocal, int px0, int py0,
                                                           int pw, int ph, int tile_log2, const Fn& fn) {
  const int x0 = s.box[0] > px0 ? s.box[0] : px0, x1 = s.box[1] < px0 + pw - 1 ? s.box[1] : px0 + pw - 1;
  const int y0 = s.box[2] > py0 ? s.box[2] : py0, y1 = s.box[3] < py0 + ph - 1 ? s.box[3] : py0 + ph - 1;
  if (x0 > x1 || y0 > y1) return;
  constexpr int64_t kRow = int64_t{1} << 30;  // U, V, W stay int32 along a row
  constexpr int32_t kCut2 = kCut * kCut;
  for (int y = y0; y <= y1; ++y) {
    const int64_t u_first = s.u00 + int64_t{s.ay} * y + int64_t{s.ax} * x0, v_first = s.v00 + int64_t{s.by} * y + int64_t{s.bx} * x0;
    const int64_t w_first = s.w00 + int64_t{s.ny} * y + int64_t{s.nx} * x0;
    const int64_t n = x1 - x0;
    const auto beyond = [&](int64_t first, int32_t step) {
      const int64_t last = first + step * n;
      return first >= kRow || first <= -kRow || last >= kRow || last <= -kRow;
    };
    if (beyond(u_first, s.ax) || beyond(v_first, s.bx) || beyond(w_first, s.nx)) continue;  // a hostile camera's centre
    int32_t U = static_cast<int32_t>(u_first), V = static_cast<int32_t>(v_first), W = static_cast<int32_t>(w_first);
    const int row = ((y - py0) << tile_log2) - px0;
    for (int x = x0; x <= x1; ++x, U += s.ax, V += s.bx, W += s.nx) {
      if (W <= 0) continue;  // the ray leaves the plane behind
      const int e = 32 - __builtin_clz(static_cast<uint32_t>(W));
      const uint32_t m = e >= 11 ? static_cast<uint32_t>(W) >> (e - 11) : static_cast<uint32_t>(W) << (11 - e);
      const int64_t r = reciprocal[m - 1024];
      const auto scaled = [&](int32_t value, int k) {  // (value r) >> (e + k), saturated past 2^20
        const int64_t p = int64_t{value} * r;
        const int sh = e + k;
        if (sh >= 0) return sh > 62 ? (p < 0 ? -1 : 0) : p >> sh;
        if (sh < -20 || p >= (int64_t{1} << 40) || p <= -(int64_t{1} << 40)) return p == 0 ? int64_t{0} : p < 0 ? -(int64_t{1} << 20) : int64_t{1} << 20;
        return p * (int64_t{1} << -sh);
      };
      const int64_t u = scaled(U, s.ku), v = scaled(V, s.kv);
      if (u > kCut || u < -kCut || v > kCut || v < -kCut) continue;
      const int32_t uu = static_cast<int32_t>(u), vv = static_cast<int32_t>(v);
      if (uu * uu + vv * vv > kCut2) continue;
      // The depth word: ((n.c) f / W) << shift, less the near plane's.
      const int64_t p = int64_t{s.zm} * r;  // below 2^47
      const int sh = s.kz - e;
      int64_t d;
      if (sh >= 0) d = sh >= 16 || p >= (int64_t{1} << (62 - sh)) ? INT64_MAX : p << sh;
      else d = sh <= -63 ? 0 : p >> -sh;
      if (d != INT64_MAX) d -= s.near_word;
      if (d < 0) continue;  // nearer than the near plane
      fn(row + x, uu, vv, d > 0xFFFFFFFE ? 0xFFFFFFFEu : static_cast<uint32_t>(d));
    }
  }
}

// Draws disc `s` into a tile's words (the tile's first pixel px0, py0; pw x
// ph of its pixels on screen; 2^tile_log2 words a row).
template <PointNormals kNormals, bool kSpecular, class Word>
void draw_close_up(const CloseUp& s, const PointTables& t, const uint16_t* reciprocal, int px0, int py0, int pw,
                   int ph, int tile_log2, Word* words) {
  for_each_close_up_pixel<(kCloseUpCut << 12)>(s, reciprocal, px0, py0, pw, ph, tile_log2,
                          [&](int at, int32_t uu, int32_t vv, uint32_t depth) __attribute__((always_inline)) {
                            uint32_t color;
                            if constexpr (kNormals == PointNormals::kSurface)
                              color = point_color<kNormals, false, kSpecular, sizeof(Word) == 4>(s.shade, t, 0, int16_pair(uu, vv), 0);
                            else
                              color = sizeof(Word) == 4 ? uint32_t{rgb565(s.shade.node_rgb)} : s.shade.node_rgb;
                            const Word w = pack_word<Word>(depth, color);
                            if (w < words[at]) words[at] = w;
                          });
}

}  // namespace stipple
