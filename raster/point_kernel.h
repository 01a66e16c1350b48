// stipple raster — the point formula: what sample j of a node becomes.
//
// Per node and frame the renderer forms a few constants (`PointShade`, and
// the position terms below); per point, with g the position sample, n the
// normal sample and q the colour sample of the Gaussian tables (Q12):
//
//   x = x0 + (mx . g) >> 16,  y = y0 + (my . g) >> 16             Q4 pixels
//   depth = depth0 + (dz . g) >> dshift                           the tile word's depth
//   al = clamp((sn1 n_1) >> 12, +-4 rad), be = likewise            Q12 radians
//   (cos, sinc) = table[(al^2 + be^2) >> 17]                      theta^2 cell
//   l = (cos l0 + sinc ((al lt1 + be lt2) >> 14)) >> 12          L.n, Q14
//   h = the same with H                                           H.n, Q14
//   rgb = shade(base + (ca . q) >> 19, diffuse[l], specular[h])
//
// (the exponential map of docs/sampling.md: L.n = cos(theta) L.n0 +
// sinc(theta) (al L.t1 + be L.t2), raster/shading.h). Every value is an
// int32 whose bound is stated where it is formed and proved in
// docs/fixed_point.md, "The point formula"; for nodes that stay inside two
// tiles a side, whose slopes and depth terms fit 16 bits, the position terms
// are int32 as well, and such a node is drawn by `draw_tile_node`: inside the
// tile pass, straight into the hot tile's words, 4 points at a time in SSE2
// or NEON lanes where the target has them, scalar elsewhere — the same
// bytes on every target. Larger nodes take the renderer's per-point path
// through the bins, with the same formula in int64 where a term needs it.
#pragma once

#include <cstddef>
#include <cstdint>

#if defined(__ARM_FEATURE_DSP)
#include <arm_acle.h>  // SMLAxy (pair_dot)
#endif

#include "core/fixed_range.h"
#include "core/gaussian_table.h"
#include "raster/point_raster.h"
#include "raster/shading.h"

namespace stipple {

// Which normal each point is shaded by.
enum class PointNormals : uint8_t { kNode, kSampled, kSurface };

// A node's per-point shading and colour constants.
struct PointShade {
  int16_t sn[2] = {};       // sigma_n1, sigma_n2: Q12 radians, <= 4 rad
  int16_t lt[2] = {};       // L.t1, L.t2: Q14
  int16_t ht[2] = {};       // H.t1, H.t2: Q14
  int16_t l0 = 0, h0 = 0;   // L.n0, H.n0: Q12
  // kSurface: the normal's angles per position sample component — sigma_n
  // times the normal's turn along each axis — in Q12 radians per sigma
  // (|.| <= 16416): al = (surface[0] . g) >> 12.
  int16_t surface[2][3] = {};
  int16_t ca[3][3] = {};    // colour axes: 8-bit levels per sigma, Q7 (|.| <= 32767, saturated)
  uint32_t base_rgb = 0;    // the node's colour, 0xRRGGBB
  uint32_t node_rgb = 0;    // the node's colour shaded by its mean normal (PointNormals::kNode)
  uint16_t intensity = 256, specular = 0;  // the mean normal's diffuse (Q8) and specular terms
};

// The tables the formula reads: the Gaussian samples, also as pairs of
// int16 in 32-bit words (low half first) for the SIMD lanes' multiply-adds —
// (g0, g1), (g2, 0), (n0, n1), (q0, q1), (q2, 0) — with kLaneSlack zero
// entries past the last sample, so 4 lanes may always be loaded.
inline constexpr uint32_t kLaneSlack = 8;
struct PointTables {
  const Gaussian3Q12* position = nullptr;
  const Gaussian2Q12* normal = nullptr;
  const Gaussian3Q12* color = nullptr;
  const ShadingTables* shading = nullptr;
  const uint32_t *g01 = nullptr, *g2 = nullptr, *n01 = nullptr, *q01 = nullptr, *q2 = nullptr;
  // Every node's base colour is this frame's grey (the model has no colour,
  // or it is ignored): the loops need not read it per node.
  bool uniform_base = false;
  uint32_t base_rgb = 0;
  // Where that base is a grey (r = g = b = v) and specular terms stay below
  // 256, shading it is two lookups (the scalar loop's shortcut, the same
  // values as shade()): grey_diffuse[i] = (v diffuse[i]) >> 8 and
  // grey_shade[d + s] = min(d + s, 255) as 0xRRGGBB. Null otherwise.
  const uint32_t* grey_diffuse = nullptr;  // kIntensityEntries (words: one LDR on 32-bit ARM)
  const uint32_t* grey_shade = nullptr;    // kGreyShades
  const uint32_t* grey_shade565 = nullptr; // the same as RGB565
};
inline constexpr int kGreyShades = 511;

// The grey shortcut's tables for base colour `rgb` (false: not a grey, or a
// specular term above 255): kIntensityEntries diffuse terms, kGreyShades
// shades as 0xRRGGBB and as many as RGB565.
bool build_grey_shades(const ShadingTables& shading, uint32_t rgb, uint32_t* diffuse, uint32_t* shades,
                       uint32_t* shades565);

// Bytes of the paired tables for `samples` samples; fills them from the Gaussian tables.
size_t point_lane_bytes(uint32_t samples);
void build_point_lanes(const Gaussian3Q12* position, const Gaussian2Q12* normal, const Gaussian3Q12* color,
                       uint32_t samples, void* storage, PointTables* out);

// A node drawn inside the tile pass (PointRenderer::draw_node says which):
// every slope and depth term fits 16 bits and the node's depths stay inside
// the depth word, so each position term is an int32 (pairs of int16 for the
// SIMD lanes' multiply-adds: element 3 is zero).
struct TileNode {
  int16_t mx[4] = {}, my[4] = {};  // 1/256 px per sigma: sum |.| < 2^15, so |m . g| < 2^29
  int16_t dz[4] = {};              // depth per sigma, scaled by 2^dshift: |dz . g| < 2^30.4
  int32_t x0_q4 = 0, y0_q4 = 0;    // the mean's square's corner: x0 - (size - 1) * 8, Q4
  uint32_t depth0 = 0;             // the mean's depth; every point's is in [0, 2^32 - 2]
  int16_t span[4] = {};            // pixels covered, inclusive: x lo, x hi, y lo, y hi
  uint16_t count = 0;
  uint8_t dshift = 0;
  PointShade shade;
};

// The tile pass's nodes: one row of 32-bit words a node (int16 pairs low
// half first), kTileFields words long and kTileStride apart (its tile
// links between). A tile's nodes are set up in the cache's order, not the
// screen's, so the tile pass reads them scattered:
// a row is 2-3 cache lines, where a structure of arrays cost a line per
// field read (docs/fixed_point.md, "Speed"). `TileNode` is one node's
// fields as store takes them; the loops read a row through `TileRow`.
enum class TileField : uint8_t {
  kMx01, kMx2, kMy01, kMy2, kDz01, kDz2,  // (m0, m1), (m2, 0) pairs
  kX0, kY0, kDepth0,
  kSpanX, kSpanY,                         // (lo, hi) pairs
  kCountShift,                            // count | dshift << 16
  kSn, kLt, kHt, kL0H0,                   // pairs
  kBaseRgb, kNodeRgb, kLighting,          // lighting: intensity | specular << 16
  kS0_01, kS0_2, kS1_01, kS1_2,           // kSurface
  kCa01R, kCa01G, kCa01B, kCa2R, kCa2G, kCa2B,  // colour per point
  kCount
};
inline constexpr int kTileFields = static_cast<int>(TileField::kCount);
// A row's words: its fields, then the links that file it in up to 2 x 2
// tiles (the raster keeps the rows among its bins: PointRaster's items).
inline constexpr int kTileLinks = 4;
inline constexpr int kTileStride = kTileFields + kTileLinks;

class TileNodes {
 public:
  static size_t bytes(uint32_t capacity) { return size_t{4} * kTileStride * capacity; }
  void init(void* storage, uint32_t capacity) {
    words_ = static_cast<uint32_t*>(storage);
    capacity_ = capacity;
  }
  // Node i's row: its field f is row(i)[f].
  uint32_t* row(uint32_t i) { return words_ + size_t{i} * kTileStride; }
  const uint32_t* row(uint32_t i) const { return words_ + size_t{i} * kTileStride; }
  const uint32_t* words() const { return words_; }
  uint32_t capacity() const { return capacity_; }

  void store(uint32_t i, const TileNode& n);
  // store's two halves from their parts (each int16 term in an int32): the
  // point formula's position terms (span: x lo, x hi, y lo, y hi), and the
  // node's shading — its surface and colour terms where the loops read
  // them (kSurface: PointNormals::kSurface; kColor: colour per point),
  // those words left as they were otherwise.
  void store_terms(uint32_t i, const int32_t mx[3], const int32_t my[3], const int32_t dz[3], int32_t x0_q4,
                   int32_t y0_q4, uint32_t depth0, const int32_t span[4], uint32_t count, uint32_t dshift);
  template <bool kSurface = true, bool kColor = true>
  void store_shade(uint32_t i, const PointShade& s);

 private:
  uint32_t* words_ = nullptr;
  uint32_t capacity_ = 0;
};

inline uint32_t int16_pair(int32_t lo, int32_t hi) {
  return static_cast<uint16_t>(lo) | uint32_t{static_cast<uint16_t>(hi)} << 16;
}
inline int16_t pair_lo(uint32_t w) { return static_cast<int16_t>(w & 0xFFFFu); }
inline int16_t pair_hi(uint32_t w) { return static_cast<int16_t>(w >> 16); }

// One node's row (TileNodes::row) as the tile pass's loops read it: the
// words themselves, int16 pairs unsplit, without a TileNode's unpacking.
class TileRow {
 public:
  explicit TileRow(const uint32_t* words) : w_(words) {}
  uint32_t operator[](TileField f) const { return w_[static_cast<int>(f)]; }
  int16_t lo(TileField f) const { return pair_lo((*this)[f]); }
  int16_t hi(TileField f) const { return pair_hi((*this)[f]); }
  uint32_t count() const { return (*this)[TileField::kCountShift] & 0xFFFFu; }
  uint32_t dshift() const { return (*this)[TileField::kCountShift] >> 16; }
  int32_t x0_q4() const { return static_cast<int32_t>((*this)[TileField::kX0]); }
  int32_t y0_q4() const { return static_cast<int32_t>((*this)[TileField::kY0]); }
  uint32_t depth0() const { return (*this)[TileField::kDepth0]; }
  // Whether every square lies in the tile of `tile` px at (px0, py0): its
  // points need no clip there.
  bool inside_tile(int px0, int py0, int tile) const {
    return lo(TileField::kSpanX) >= px0 && hi(TileField::kSpanX) < px0 + tile && lo(TileField::kSpanY) >= py0 &&
           hi(TileField::kSpanY) < py0 + tile;
  }

 private:
  const uint32_t* w_;
};

inline void TileNodes::store_terms(uint32_t i, const int32_t mx[3], const int32_t my[3], const int32_t dz[3],
                                   int32_t x0_q4, int32_t y0_q4, uint32_t depth0, const int32_t span[4], uint32_t count,
                                   uint32_t dshift) {
  uint32_t* const r = row(i);
  const auto set = [&](TileField f, uint32_t v) { r[static_cast<int>(f)] = v; };
  set(TileField::kMx01, int16_pair(mx[0], mx[1]));
  set(TileField::kMx2, int16_pair(mx[2], 0));
  set(TileField::kMy01, int16_pair(my[0], my[1]));
  set(TileField::kMy2, int16_pair(my[2], 0));
  set(TileField::kDz01, int16_pair(dz[0], dz[1]));
  set(TileField::kDz2, int16_pair(dz[2], 0));
  set(TileField::kX0, static_cast<uint32_t>(x0_q4));
  set(TileField::kY0, static_cast<uint32_t>(y0_q4));
  set(TileField::kDepth0, depth0);
  set(TileField::kSpanX, int16_pair(span[0], span[1]));
  set(TileField::kSpanY, int16_pair(span[2], span[3]));
  set(TileField::kCountShift, count | dshift << 16);
}

template <bool kSurface, bool kColor>
inline void TileNodes::store_shade(uint32_t i, const PointShade& s) {
  uint32_t* const r = row(i);
  const auto set = [&](TileField f, uint32_t v) { r[static_cast<int>(f)] = v; };
  set(TileField::kSn, int16_pair(s.sn[0], s.sn[1]));
  set(TileField::kLt, int16_pair(s.lt[0], s.lt[1]));
  set(TileField::kHt, int16_pair(s.ht[0], s.ht[1]));
  set(TileField::kL0H0, int16_pair(s.l0, s.h0));
  set(TileField::kBaseRgb, s.base_rgb);
  set(TileField::kNodeRgb, s.node_rgb);
  set(TileField::kLighting, s.intensity | uint32_t{s.specular} << 16);
  if constexpr (kSurface) {
    set(TileField::kS0_01, int16_pair(s.surface[0][0], s.surface[0][1]));
    set(TileField::kS0_2, int16_pair(s.surface[0][2], 0));
    set(TileField::kS1_01, int16_pair(s.surface[1][0], s.surface[1][1]));
    set(TileField::kS1_2, int16_pair(s.surface[1][2], 0));
  }
  if constexpr (kColor) {
    for (int c = 0; c < 3; ++c) {
      set(static_cast<TileField>(static_cast<int>(TileField::kCa01R) + c), int16_pair(s.ca[0][c], s.ca[1][c]));
      set(static_cast<TileField>(static_cast<int>(TileField::kCa2R) + c), int16_pair(s.ca[2][c], 0));
    }
  }
}

inline void TileNodes::store(uint32_t i, const TileNode& n) {
  const int32_t mx[3] = {n.mx[0], n.mx[1], n.mx[2]}, my[3] = {n.my[0], n.my[1], n.my[2]}, dz[3] = {n.dz[0], n.dz[1], n.dz[2]};
  const int32_t span[4] = {n.span[0], n.span[1], n.span[2], n.span[3]};
  store_terms(i, mx, my, dz, n.x0_q4, n.y0_q4, n.depth0, span, n.count, n.dshift);
  store_shade(i, n.shade);
}

inline uint32_t clamp255(int32_t v) { return v < 0 ? 0u : v > 255 ? 255u : static_cast<uint32_t>(v); }

// Colour after shading: channel * intensity (Q8) + specular, saturated.
inline uint32_t shade(uint32_t r, uint32_t g, uint32_t b, uint32_t intensity, uint32_t specular) {
  const uint32_t rr = ((r * intensity) >> 8) + specular, gg = ((g * intensity) >> 8) + specular,
                 bb = ((b * intensity) >> 8) + specular;
  return ((rr > 255 ? 255 : rr) << 16) | ((gg > 255 ? 255 : gg) << 8) | (bb > 255 ? 255 : bb);
}

// sigma_n n >> 12 clamped to 4 rad (Q12): the cos/sinc table ends at
// theta^2 = 16, so a larger angle reads its last cell either way.
// sigma_n <= 2^14, |n| <= 2^15: the product is below 2^29.
inline int32_t clamp_angle_q12(int32_t v) { return v > 16384 ? 16384 : v < -16384 ? -16384 : v; }
inline int32_t normal_angle_q12(int32_t sigma_n, int32_t n) { return clamp_angle_q12((sigma_n * n) >> 12); }

// The products of two words' low and high int16 halves. On 32-bit ARM with
// the DSP multiplies each is one SMULBB or SMULTT, said with the ACLE's
// multiply-accumulate (it has no plain multiply): written as C, GCC hoists
// a loop-invariant operand's half out of the loop, sign-extended, and the
// loop then keeps twice as many terms live (docs/fixed_point.md, "ARMv5").
inline int32_t mul_lo(uint32_t a, uint32_t b) {
#if defined(__ARM_FEATURE_DSP)
  return __smlabb(static_cast<int32_t>(a), static_cast<int32_t>(b), 0);
#else
  return static_cast<int16_t>(a) * static_cast<int16_t>(b);
#endif
}
inline int32_t mul_hi(uint32_t a, uint32_t b) {
#if defined(__ARM_FEATURE_DSP)
  return __smlatt(static_cast<int32_t>(a), static_cast<int32_t>(b), 0);
#else
  return (static_cast<int32_t>(a) >> 16) * (static_cast<int32_t>(b) >> 16);
#endif
}

// The intensity table's index of L.n for the sampled normal at angles
// (al, be): |al|, |be| <= 2^14 and |(t1, t2)| <= 2^14 (+ rounding) give
// |al t1 + be t2| <= 2^28.6 and a Q12 term below 23,200 (it fits 16 bits);
// cos l0 + sinc term < 2^28.6, the Q26 L.n, indexed by lit_entry_q26
// without a clamp (|L.n| <= 1.26: the sum with its offset stays within
// [0, 2^27.5)).
// `t12` is the (t1, t2) pair and n0 (Q12) the low half of `n0_pair`, or
// its high half (kHigh: the (l0, h0) pair serves both terms); every
// operand fits 16 bits, so on 32-bit ARM with the DSP multiplies
// (pair_dot, below) it is four of them, the table's entry one 32-bit load.
template <bool kHigh>
inline int lit_index(const CosSincQ14& cs, int32_t al, int32_t be, uint32_t t12, uint32_t n0_pair) {
#if defined(__ARM_FEATURE_DSP) && !defined(__ARM_BIG_ENDIAN)
  using Word [[gnu::may_alias]] = uint32_t;
  const int32_t c = static_cast<int32_t>(*reinterpret_cast<const Word*>(&cs));  // cos | sinc << 16
  const int32_t n0 = static_cast<int32_t>(n0_pair);
  const int32_t along = __smlabt(be, static_cast<int32_t>(t12), mul_lo(static_cast<uint32_t>(al), t12)) >> 14;
  // The offset of lit_entry_q26 as the chain's start: the same sum.
  const int32_t start = kHigh ? __smlabt(c, n0, kIntensityOffsetQ26) : __smlabb(c, n0, kIntensityOffsetQ26);
  return lit_entry(__smlatb(c, along, start));
#else
  const int32_t along = (al * static_cast<int16_t>(t12) + be * (static_cast<int32_t>(t12) >> 16)) >> 14;
  const int32_t n0 = kHigh ? pair_hi(n0_pair) : pair_lo(n0_pair);
  return lit_entry_q26(cs.cos * n0 + cs.sinc * along);
#endif
}

// A node's terms as int16 pairs in 32-bit words (low half first), the way
// the scalar loops read them: a 3-term dot product of a sample's pairs is
// then two 16 x 16-bit multiply-accumulates and one multiply (ARMv5TE's
// SMULxy/SMLAxy; plain multiplies elsewhere) instead of three loads, three
// sign-extensions and three multiplies.
//
// On ARMv5TE and later 32-bit ARM the ACLE's multiply-accumulates say so
// outright: written as C, the compiler hoists the node's halves out of the
// loop, sign-extended, and a point loop's 20-odd terms then live on the
// stack (docs/fixed_point.md, "ARMv5"). The sums are the same: every
// caller's terms keep them below 2^31, where SMLAxy does not saturate.
// pair_dot_acc is `acc` plus the product (the chain starts at it).
inline int32_t pair_dot_acc(int32_t acc, uint32_t g01, uint32_t g2, uint32_t a01, uint32_t a2) {
#if defined(__ARM_FEATURE_DSP)
  return __smlabb(static_cast<int32_t>(g2), static_cast<int32_t>(a2),
                  __smlatt(static_cast<int32_t>(g01), static_cast<int32_t>(a01),
                           __smlabb(static_cast<int32_t>(g01), static_cast<int32_t>(a01), acc)));
#else
  return acc + static_cast<int16_t>(g01) * static_cast<int16_t>(a01) +
         (static_cast<int32_t>(g01) >> 16) * (static_cast<int32_t>(a01) >> 16) +
         static_cast<int16_t>(g2) * static_cast<int16_t>(a2);
#endif
}
// The sum alone (on the DSP targets SMULBB, then the two accumulates).
inline int32_t pair_dot(uint32_t g01, uint32_t g2, uint32_t a01, uint32_t a2) { return pair_dot_acc(0, g01, g2, a01, a2); }

struct PackedShade {
  uint32_t sn = 0, lt = 0, ht = 0;            // (sigma_n1, sigma_n2), (L.t1, L.t2), (H.t1, H.t2)
  uint32_t l0h0 = 0;                          // (l0, h0)
  uint32_t s0_01 = 0, s0_2 = 0, s1_01 = 0, s1_2 = 0;  // surface[0], surface[1]
  uint32_t ca01[3] = {}, ca2[3] = {};         // colour axes per channel
  uint32_t r = 0, g = 0, b = 0;               // base colour
  uint32_t node_rgb = 0, intensity = 256, specular = 0;
  PackedShade() = default;
  explicit PackedShade(const PointShade& s)
      : sn(int16_pair(s.sn[0], s.sn[1])), lt(int16_pair(s.lt[0], s.lt[1])), ht(int16_pair(s.ht[0], s.ht[1])),
        l0h0(int16_pair(s.l0, s.h0)), s0_01(int16_pair(s.surface[0][0], s.surface[0][1])), s0_2(int16_pair(s.surface[0][2], 0)),
        s1_01(int16_pair(s.surface[1][0], s.surface[1][1])), s1_2(int16_pair(s.surface[1][2], 0)),
        r(s.base_rgb >> 16), g((s.base_rgb >> 8) & 0xFFu), b(s.base_rgb & 0xFFu), node_rgb(s.node_rgb),
        intensity(s.intensity), specular(s.specular) {
    for (int c = 0; c < 3; ++c) {
      ca01[c] = int16_pair(s.ca[0][c], s.ca[1][c]);
      ca2[c] = int16_pair(s.ca[2][c], 0);
    }
  }
  // The same terms from a tile node's row, whose words are these pairs.
  explicit PackedShade(const TileRow& row)
      : sn(row[TileField::kSn]), lt(row[TileField::kLt]), ht(row[TileField::kHt]), l0h0(row[TileField::kL0H0]),
        s0_01(row[TileField::kS0_01]), s0_2(row[TileField::kS0_2]), s1_01(row[TileField::kS1_01]),
        s1_2(row[TileField::kS1_2]), r(row[TileField::kBaseRgb] >> 16), g((row[TileField::kBaseRgb] >> 8) & 0xFFu),
        b(row[TileField::kBaseRgb] & 0xFFu), node_rgb(row[TileField::kNodeRgb]), intensity(row[TileField::kLighting] & 0xFFFFu),
        specular(row[TileField::kLighting] >> 16) {
    for (int c = 0; c < 3; ++c) {
      ca01[c] = row[static_cast<TileField>(static_cast<int>(TileField::kCa01R) + c)];
      ca2[c] = row[static_cast<TileField>(static_cast<int>(TileField::kCa2R) + c)];
    }
  }
};

// Whether a grey model's points take the grey shortcut's tables
// (PointTables::grey_shade): asked a point at a time, or known for a node's
// loop (the tile pass decides once a node).
enum class GreyTables { kAsk, kYes, kNo };

// The colour of sample j (the formula's last three lines) from the node's
// packed terms and the sample's position pairs, as 0xRRGGBB — or, for
// kRgb565, as RGB565: what the scalar loops run.
template <PointNormals kNormals, bool kColorPoints, bool kSpecular, bool kRgb565 = false, bool kClampAngles = true,
          GreyTables kGrey = GreyTables::kAsk>
[[gnu::always_inline]] inline uint32_t point_color(const PackedShade& s, const PointTables& t, uint32_t j, uint32_t g01,
                                                   uint32_t g2) {
  const auto encode = [](uint32_t rgb) { return kRgb565 ? uint32_t{rgb565(rgb)} : rgb; };
  constexpr bool kShadePoints = kNormals != PointNormals::kNode;
  if constexpr (!kColorPoints && !kShadePoints) {
    return encode(s.node_rgb);
  } else {
    uint32_t r = s.r, g = s.g, b = s.b;
    if constexpr (kColorPoints) {
      const uint32_t q01 = t.q01[j], q2 = t.q2[j];
      r = clamp255(static_cast<int32_t>(r) + (pair_dot(q01, q2, s.ca01[0], s.ca2[0]) >> 19));
      g = clamp255(static_cast<int32_t>(g) + (pair_dot(q01, q2, s.ca01[1], s.ca2[1]) >> 19));
      b = clamp255(static_cast<int32_t>(b) + (pair_dot(q01, q2, s.ca01[2], s.ca2[2]) >> 19));
    }
    if constexpr (!kShadePoints) {
      return encode(shade(r, g, b, s.intensity, s.specular));
    } else {
      int32_t al, be;
      if constexpr (kNormals == PointNormals::kSurface) {
        al = pair_dot(g01, g2, s.s0_01, s.s0_2) >> 12;
        be = pair_dot(g01, g2, s.s1_01, s.s1_2) >> 12;
      } else {
        const uint32_t n01 = t.n01[j];
        al = mul_lo(n01, s.sn) >> 12;
        be = mul_hi(n01, s.sn) >> 12;
      }
      if constexpr (kClampAngles) {
        al = clamp_angle_q12(al);
        be = clamp_angle_q12(be);
      }
      // |al|, |be| <= 2^14 (clamped, or angles_in_range): cell < kCosSincCells.
      const uint32_t cell = static_cast<uint32_t>(al * al + be * be) >> kCosSincShift;
#if STIPPLE_CHECK_RANGES
      if (cell >= static_cast<uint32_t>(kCosSincCells)) __builtin_trap();
#endif
      const CosSincQ14& cs = t.shading->cos_sinc[cell];
      const int il = lit_index<false>(cs, al, be, s.lt, s.l0h0);
      const uint32_t specular = kSpecular ? t.shading->specular[lit_index<true>(cs, al, be, s.ht, s.l0h0)] : 0;
      if constexpr (!kColorPoints) {
        if (kGrey == GreyTables::kYes || (kGrey == GreyTables::kAsk && t.grey_shade != nullptr))
          return (kRgb565 ? t.grey_shade565 : t.grey_shade)[t.grey_diffuse[il] + specular];
      }
      return encode(shade(r, g, b, t.shading->diffuse[il], specular));
    }
  }
}

// Depth-tests a point's square (first pixel x, y within the tile) into the
// tile's words: whole when the node lies `inside` the tile, else clipped to it.
template <class Word>
[[gnu::always_inline]] inline void ztest_point(Word* words, int tile_log2, int size, uint32_t wh, bool inside, int32_t x, int32_t y, Word w) {
  const int tile = 1 << tile_log2;
  if (inside) {
#if STIPPLE_CHECK_RANGES
    if (x < 0 || y < 0 || x + size > tile || y + size > tile) __builtin_trap();  // outside the span it was filed by
#endif
    ztest_square(words + (y << tile_log2) + x, tile, wh, w);
  } else {
    const int32_t xa = x < 0 ? 0 : x, ya = y < 0 ? 0 : y;
    const int32_t xb = x + size > tile ? tile : x + size, yb = y + size > tile ? tile : y + size;
    if (xa < xb && ya < yb)
      ztest_square(words + (ya << tile_log2) + xa, tile, static_cast<uint32_t>((xb - xa) | (yb - ya) << 4), w);
  }
}

// Draws node `n`'s points into the words of the tile whose first pixel is
// (px0, py0) — 2^tile_log2 words a row, pack_word's format — each a square of
// `size` px (1..3), clipped to the tile when the node's span leaves it.
// Scalar: the reference for the lanes below and what ARMv5 runs.
//
// It runs in two passes over each chunk of kScalarChunk points: where each
// point lands (the node's position terms), then the colour and the z-test
// of those that land in the tile (its shading terms and the tables). One
// pass kept some 20 terms live a point, and on 32-bit ARM, with 13
// registers to hold them, reloaded a dozen from the stack every point;
// each pass's terms fit the registers, and a chunk's positions lie on the
// stack between them (docs/fixed_point.md, "ARMv5").
inline constexpr uint32_t kScalarChunk = 32;

// Whether no point of the node needs clamp_angle_q12: every sample
// component is within kGaussianClip, so |sigma_n n| >> 12 (kSampled) and
// |surface_k . g| >> 12 (kSurface) stay within 2^14 where sigma_n, or
// sum |surface_k|, is at most 2^26 / kGaussianClip (4,681: 1.14 rad) —
// nearly every node. The clamp is then two compares an angle saved.
// (Per node normal, kNode, no point turns at all.)
template <PointNormals kNormals>
inline bool angles_in_range(const PackedShade& s) {
  constexpr int32_t kMax = (int32_t{1} << 26) / kGaussianClip;
  const auto abs16 = [](int32_t v) { return v < 0 ? -v : v; };
  if constexpr (kNormals == PointNormals::kNode) {
    return true;
  } else if constexpr (kNormals == PointNormals::kSurface) {
    const auto sum = [&](uint32_t p01, uint32_t p2) { return abs16(pair_lo(p01)) + abs16(pair_hi(p01)) + abs16(pair_lo(p2)); };
    return sum(s.s0_01, s.s0_2) <= kMax && sum(s.s1_01, s.s1_2) <= kMax;
  } else {
    return abs16(pair_lo(s.sn)) <= kMax && abs16(pair_hi(s.sn)) <= kMax;
  }
}

// A chunk's points that land in the tile, as draw_tile_node_scalar's first
// pass leaves them: the sample (of a node inside the tile, `first` plus
// the point's place: not stored); where, in the tile; the depth (its upper
// half alone, shifted down, for 32-bit words: the part they keep). A point whose
// square lies wholly in the tile is kept from the front, as its first
// pixel's word; one across the tile's edge (only a node across it has
// such points) from the back, as (x, y), an int16 pair, to be clipped.
struct ScalarChunk {
  uint32_t first = 0;
  uint16_t sample[kScalarChunk];
  uint32_t at[kScalarChunk], depth[kScalarChunk];
  uint32_t whole = 0;             // [0, whole): wholly in the tile
  uint32_t edge = kScalarChunk;  // [edge, kScalarChunk): across its edge
};

// The first pass over samples [first, end); the depths shifted down by
// kDepthShift; tiles of 2^kTileLog2 px where the caller knows it (0: tile_log2).
template <bool kInside, int kDepthShift, int kTileLog2>
[[gnu::always_inline]] inline void place_points(const TileRow& n, const PointTables& t, int size, int tile_log2, int px0,
                                                int py0, uint32_t first, uint32_t end, ScalarChunk& out) {
  if constexpr (kTileLog2 != 0) tile_log2 = kTileLog2;
  const int tile = 1 << tile_log2;
  // (x0 + (m . g >> 16)) >> 4 is (x0 2^16 + m . g) >> 20 (floors of
  // power-of-two divisions compose): the mean's corner, relative to the
  // tile, within 3 tiles of 128 px (2^12.6 in Q4), times 2^16 is the sum's
  // start, and the sum stays below 2^29 + 2^28.6.
  const int32_t x0 = (n.x0_q4() - (px0 << 4)) * 65536, y0 = (n.y0_q4() - (py0 << 4)) * 65536;
  const uint32_t mx01 = n[TileField::kMx01], mx2 = n[TileField::kMx2];
  const uint32_t my01 = n[TileField::kMy01], my2 = n[TileField::kMy2];
  const uint32_t dz01 = n[TileField::kDz01], dz2 = n[TileField::kDz2];
  const uint32_t depth0 = n.depth0(), dshift = n.dshift();
  // The last first pixel of a square wholly in the tile, either axis.
  const uint32_t last = static_cast<uint32_t>(tile - size);
  uint32_t whole = 0, edge = kScalarChunk;
  // Two points a pass: on ARMv5 a pair shares some of the reloads of the
  // node's spilled terms and one count and branch (27 -> 26 instructions
  // a point inside a tile; the colour pass unrolled measured dearer).
#pragma GCC unroll 2
  for (uint32_t j = first; j < end; ++j) {
    const uint32_t g01 = t.g01[j], g2 = t.g2[j];
    const int32_t x = pair_dot_acc(x0, g01, g2, mx01, mx2) >> 20;
    const int32_t y = pair_dot_acc(y0, g01, g2, my01, my2) >> 20;
    uint32_t k;
    if constexpr (kInside) {
#if STIPPLE_CHECK_RANGES
      if (x < 0 || y < 0 || x + size > tile || y + size > tile) __builtin_trap();  // outside the span it was filed by
#endif
      k = whole++;
      out.at[k] = static_cast<uint32_t>((y << tile_log2) + x);
    } else {
      // A node across a tile's edge is drawn in each tile it touches: a
      // point whose square lies wholly in another tile is that tile's to
      // shade (on the bunny at 240 x 320, nearly half the points met here:
      // 16,649 of 35,230); most of the rest lie wholly in this one and need
      // no clipping. (Testing x before computing y measured dearer.)
      if (static_cast<uint32_t>(x) <= last && static_cast<uint32_t>(y) <= last) {
        k = whole++;
        out.at[k] = static_cast<uint32_t>((y << tile_log2) + x);
      } else {
        if (x <= -size || y <= -size || x >= tile || y >= tile) continue;
        k = --edge;
        out.at[k] = int16_pair(x, y);
      }
    }
    if constexpr (!kInside) out.sample[k] = static_cast<uint16_t>(j);  // else first + k
    out.depth[k] = (depth0 + static_cast<uint32_t>(pair_dot(g01, g2, dz01, dz2) >> dshift)) >> kDepthShift;
  }
  out.first = first;
  out.whole = whole;
  out.edge = edge;
}

// The second pass: the colour and the z-test of the chunk's points [begin,
// end), wholly in the tile (kWhole) or across its edge, their samples in
// order (kInOrder: a node inside the tile) or listed; squares of kSize px
// and tiles of 2^kTileLog2 where the caller knows them (0: `size`, `tile_log2`).
template <PointNormals kNormals, bool kColorPoints, bool kSpecular, bool kWhole, bool kInOrder, bool kClampAngles,
          GreyTables kGrey, int kSize, int kTileLog2, class Word>
[[gnu::always_inline]] inline void shade_points(const PackedShade& shade, const PointTables& t, int size, Word* words,
                                                int tile_log2, const ScalarChunk& in, uint32_t begin, uint32_t end) {
  if constexpr (kSize != 0) size = kSize;
  if constexpr (kTileLog2 != 0) tile_log2 = kTileLog2;
  const uint32_t wh = static_cast<uint32_t>(size | size << 4);
  for (uint32_t k = begin; k < end; ++k) {
    const uint32_t j = kInOrder ? in.first + k : in.sample[k];
    const uint32_t color =
        point_color<kNormals, kColorPoints, kSpecular, sizeof(Word) == 4, kClampAngles, kGrey>(shade, t, j, t.g01[j], t.g2[j]);
    // An RGB565 colour (the uint32_t words') is below 2^16 — the grey
    // table's entries too — and the depth is its upper half already
    // (place_points): pack_word's value without its masks.
    const Word w = sizeof(Word) == 4 ? static_cast<Word>(in.depth[k] << 16 | color) : pack_word<Word>(in.depth[k], color);
    if constexpr (kWhole)
      ztest_square(words + in.at[k], 1 << tile_log2, wh, w);
    else
      ztest_point(words, tile_log2, size, wh, false, pair_lo(in.at[k]), pair_hi(in.at[k]), w);
  }
}

// A chunk's second pass: the points wholly in the tile unclipped, then (a
// node across its edge) the rest clipped.
template <PointNormals kNormals, bool kColorPoints, bool kSpecular, bool kInside, bool kClampAngles, GreyTables kGrey,
          int kSize, int kTileLog2, class Word>
[[gnu::always_inline]] inline void shade_chunk(const PackedShade& shade, const PointTables& t, int size, Word* words,
                                               int tile_log2, const ScalarChunk& chunk) {
  shade_points<kNormals, kColorPoints, kSpecular, true, kInside, kClampAngles, kGrey, kSize, kTileLog2>(
      shade, t, size, words, tile_log2, chunk, 0, chunk.whole);
  if constexpr (!kInside)
    shade_points<kNormals, kColorPoints, kSpecular, false, false, kClampAngles, kGrey, kSize, kTileLog2>(
        shade, t, size, words, tile_log2, chunk, chunk.edge, kScalarChunk);
}

template <PointNormals kNormals, bool kColorPoints, bool kSpecular, bool kInside, int kTileLog2, class Word>
void draw_tile_node_chunks(const TileRow& n, const PointTables& t, int size, Word* words, int tile_log2, int px0, int py0) {
  const uint32_t count = n.count();
  const PackedShade shade(n);
  const bool clamp = !angles_in_range<kNormals>(shade);
  // The grey shortcut, where a point could take it, decided for the node.
  constexpr bool kMayGrey = !kColorPoints && kNormals != PointNormals::kNode;
  const bool grey = kMayGrey && t.grey_shade != nullptr;
  ScalarChunk chunk;
  for (uint32_t first = 0; first < count; first += kScalarChunk) {
    const uint32_t end = count - first < kScalarChunk ? count : first + kScalarChunk;
    place_points<kInside, sizeof(Word) == 4 ? 16 : 0, kTileLog2>(n, t, size, tile_log2, px0, py0, first, end, chunk);
    // The common cases — angles in range, 2 px squares, grey or not —
    // with their tests out of the loop; the rest ask a point at a time.
    if (clamp)
      shade_chunk<kNormals, kColorPoints, kSpecular, kInside, true, GreyTables::kAsk, 0, kTileLog2>(
          shade, t, size, words, tile_log2, chunk);
    else if (size != 2)
      shade_chunk<kNormals, kColorPoints, kSpecular, kInside, false, GreyTables::kAsk, 0, kTileLog2>(
          shade, t, size, words, tile_log2, chunk);
    else if (grey)
      shade_chunk<kNormals, kColorPoints, kSpecular, kInside, false, GreyTables::kYes, 2, kTileLog2>(
          shade, t, size, words, tile_log2, chunk);
    else
      shade_chunk<kNormals, kColorPoints, kSpecular, kInside, false, GreyTables::kNo, 2, kTileLog2>(
          shade, t, size, words, tile_log2, chunk);
  }
}

template <PointNormals kNormals, bool kColorPoints, bool kSpecular, int kTileLog2, class Word>
void draw_tile_node_tiled(const TileRow& n, const PointTables& t, int size, Word* words, int tile_log2, int px0,
                          int py0) {
  if (n.inside_tile(px0, py0, 1 << tile_log2))
    draw_tile_node_chunks<kNormals, kColorPoints, kSpecular, true, kTileLog2>(n, t, size, words, tile_log2, px0, py0);
  else
    draw_tile_node_chunks<kNormals, kColorPoints, kSpecular, false, kTileLog2>(n, t, size, words, tile_log2, px0, py0);
}

// The default tile's loops know its size: a row's offset and the pixel
// index's shift are immediates, which on ARMv5 frees the registers two
// spilled terms took (docs/fixed_point.md, "ARMv5"). Other tiles ask.
template <PointNormals kNormals, bool kColorPoints, bool kSpecular, class Word>
void draw_tile_node_scalar(const TileRow& n, const PointTables& t, int size, Word* words, int tile_log2, int px0,
                           int py0) {
  if (tile_log2 == kDefaultTileLog2)
    draw_tile_node_tiled<kNormals, kColorPoints, kSpecular, kDefaultTileLog2>(n, t, size, words, tile_log2, px0, py0);
  else
    draw_tile_node_tiled<kNormals, kColorPoints, kSpecular, 0>(n, t, size, words, tile_log2, px0, py0);
}

}  // namespace stipple

// The same loop in the target's SIMD lanes, where it has them.
#if defined(__SSE2__)
#include "raster/point_kernel_sse2.h"
#elif defined(__ARM_NEON)
#include "raster/point_kernel_neon.h"
#endif

namespace stipple {

// The baseline lanes this build draws points in (PointLanes::kBaseline).
#if defined(__SSE2__)
inline constexpr const char* kBaselineLanes = "sse2";
#elif defined(__ARM_NEON)
inline constexpr const char* kBaselineLanes = "neon";
#else
inline constexpr const char* kBaselineLanes = "scalar";
#endif

// The tile pass's per-node loop on this target.
template <PointNormals kNormals, bool kColorPoints, bool kSpecular, class Word>
inline void draw_tile_node(const TileRow& n, const PointTables& t, int size, Word* words, int tile_log2, int px0,
                           int py0) {
#if defined(__SSE2__)
  sse2::draw_tile_node<kNormals, kColorPoints, kSpecular>(n, t, size, words, tile_log2, px0, py0);
#elif defined(__ARM_NEON)
  neon::draw_tile_node<kNormals, kColorPoints, kSpecular>(n, t, size, words, tile_log2, px0, py0);
#else
  draw_tile_node_scalar<kNormals, kColorPoints, kSpecular>(n, t, size, words, tile_log2, px0, py0);
#endif
}

}  // namespace stipple
