// stipple raster — close-ups: a disc's set-up. See close_up.h.
#include "raster/close_up.h"

#include "core/divide.h"
#include "raster/projection.h"

namespace stipple {
namespace {

int bit_length64(uint64_t v) { return v == 0 ? 0 : 64 - __builtin_clzll(v); }
// The bits of v past its top `bits` (0 when it fits).
int excess_bits(int64_t v, int bits) {
  const int n = bit_length64(static_cast<uint64_t>(v));
  return n > bits ? n - bits : 0;
}

// v >> s for s >= 0, v << -s otherwise (|v| << -s within 63 bits: the callers' bounds).
int64_t shift_right(int64_t v, int s) { return s >= 0 ? v >> s : v * (int64_t{1} << -s); }

// One tangent's E = ((n.c) t - (t.c) n) / sigma (Q28 units of the unit
// vectors' products, over MU), scaled to 13 bits: the vector, and the
// shift that scaled it (E = vector 2^shift). False when it vanishes.
bool tangent_terms(const int16_t t[3], const int16_t n[3], int64_t nc, const int32_t c[3], int32_t sigma,
                   int32_t out[3], int* shift) {
  if (sigma < 1) return false;
  const int64_t tc = int64_t{t[0]} * c[0] + int64_t{t[1]} * c[1] + int64_t{t[2]} * c[2];  // below 2^46
  int64_t q[3];
  uint64_t most = 0;
  for (int i = 0; i < 3; ++i) {
    // Each product below 2^46 * 2^14: the difference within 2^61.
    q[i] = floor_div(nc * t[i] - tc * n[i], sigma);
    if (static_cast<uint64_t>(abs64(q[i])) > most) most = static_cast<uint64_t>(abs64(q[i]));
  }
  if (most == 0) return false;
  *shift = bit_length64(most) - 13;
  for (int i = 0; i < 3; ++i) out[i] = static_cast<int32_t>(shift_right(q[i], *shift));
  return true;
}

}  // namespace

bool set_up_close_up(const CloseUpFrame& f, const int32_t c[3], const int16_t frame[3][3], const int32_t sigma[3],
                     CloseUp* out) {
  // The normal: the axis of the smallest sigma; the tangents the others.
  const int kn = sigma[2] <= sigma[1] ? (sigma[2] <= sigma[0] ? 2 : 0) : (sigma[1] <= sigma[0] ? 1 : 0);
  const int k1 = kn == 0 ? 1 : 0, k2 = kn == 2 ? 1 : 2;
  int16_t n[3] = {frame[kn][0], frame[kn][1], frame[kn][2]};
  // n.c (Q14 MU, below 2^46): the plane faces the eye, n.c > 0.
  int64_t nc = int64_t{n[0]} * c[0] + int64_t{n[1]} * c[1] + int64_t{n[2]} * c[2];
  if (nc == 0) return false;  // edge on, through the eye
  if (nc < 0) {
    nc = -nc;
    for (int i = 0; i < 3; ++i) n[i] = static_cast<int16_t>(-n[i]);
  }
  int32_t a[3], b[3];
  int sa = 0, sb = 0;
  if (!tangent_terms(frame[k1], n, nc, c, sigma[k1], a, &sa) || !tangent_terms(frame[k2], n, nc, c, sigma[k2], b, &sb))
    return false;
  CloseUp& s = *out;
  // U = a.d with d in pixels from (8 - cx, 8 - cy, f) / 16 at pixel (0, 0):
  // |a| < 2^13, |d| < 2^21 in Q4 — int64. W likewise with n (Q14).
  const int64_t dx = 8 - int64_t{f.cx_q4}, dy = 8 - int64_t{f.cy_q4}, dz = f.focal_q4;
  const auto at_origin = [&](const int32_t v[3]) { return (v[0] * dx + v[1] * dy + v[2] * dz) >> 4; };
  s.ax = a[0], s.ay = a[1], s.bx = b[0], s.by = b[1], s.nx = n[0], s.ny = n[1];
  s.u00 = at_origin(a);
  s.v00 = at_origin(b);
  const int32_t n32[3] = {n[0], n[1], n[2]};
  s.w00 = at_origin(n32);
  // u in Q12 = U / W 2^(14 + 12 - 28 + shift) with W's reciprocal r 2^-(e+15):
  // (U r) >> (e + 17 - shift)... for E = a 2^shift over the Q28 product units.
  s.ku = static_cast<int8_t>(17 - sa);
  s.kv = static_cast<int8_t>(17 - sb);
  // Depth: z = (n.c) f_q4 / (16 W) MU (W = 2^14 n.d, n.c in Q14 MU), the
  // word z << depth_shift; (n.c) f_q4 kept as its top 31 bits zm 2^sz.
  const int sn = excess_bits(nc, 24);
  const int64_t k = (nc >> sn) * f.focal_q4;  // below 2^44
  const int sk = excess_bits(k, 31);
  s.zm = static_cast<int32_t>(k >> sk);
  const int kz = sn + sk + f.depth_shift - 19;
  if (kz < -100 || kz > 100) return false;
  s.kz = static_cast<int8_t>(kz);
  s.near_word = int64_t{f.near} * (int64_t{1} << f.depth_shift);
  // The bounding box: the projection of the 3 sigma square in the plane
  // (the disc lies in it), clipped to the space beyond the near plane —
  // what of the disc can be drawn at all. Corners are 3 sigma (< 2^26.6)
  // from the mean; each clipped edge's point one division, each vertex two.
  int64_t square[4][3];
  for (int corner = 0; corner < 4; ++corner)
    for (int i = 0; i < 3; ++i) {
      const int64_t e1 = int64_t{frame[k1][i]} * sigma[k1] * kCloseUpCut, e2 = int64_t{frame[k2][i]} * sigma[k2] * kCloseUpCut;
      const bool plus1 = corner == 1 || corner == 2, plus2 = corner >= 2;  // around the square
      square[corner][i] = c[i] + ((plus1 ? e1 : -e1) + (plus2 ? e2 : -e2)) / (1 << 14);
    }
  const int64_t z_min = int64_t{f.near} + 1;
  int64_t lo[2] = {INT64_MAX, INT64_MAX}, hi[2] = {INT64_MIN, INT64_MIN};
  const auto project = [&](const int64_t p[3]) {
    const int64_t x = f.cx_q4 + floor_div(int64_t{f.focal_q4} * p[0], p[2]), y = f.cy_q4 + floor_div(int64_t{f.focal_q4} * p[1], p[2]);
    lo[0] = x < lo[0] ? x : lo[0], hi[0] = x > hi[0] ? x : hi[0];
    lo[1] = y < lo[1] ? y : lo[1], hi[1] = y > hi[1] ? y : hi[1];
  };
  int vertices = 0;
  for (int edge = 0; edge < 4; ++edge) {
    const int64_t* from = square[edge];
    const int64_t* to = square[(edge + 1) & 3];
    const bool from_in = from[2] >= z_min, to_in = to[2] >= z_min;
    if (from_in) project(from), ++vertices;
    if (from_in != to_in) {  // the edge crosses the near plane: its point there
      int64_t p[3];
      for (int i = 0; i < 2; ++i) p[i] = from[i] + floor_div((to[i] - from[i]) * (z_min - from[2]), to[2] - from[2]);
      p[2] = z_min;
      project(p), ++vertices;
    }
  }
  if (vertices == 0) return false;  // wholly behind the near plane
  int64_t box[4];
  box[0] = (lo[0] >> 4) - 1 > 0 ? (lo[0] >> 4) - 1 : 0;
  box[1] = (hi[0] >> 4) + 1 < f.width - 1 ? (hi[0] >> 4) + 1 : f.width - 1;
  box[2] = (lo[1] >> 4) - 1 > 0 ? (lo[1] >> 4) - 1 : 0;
  box[3] = (hi[1] >> 4) + 1 < f.height - 1 ? (hi[1] >> 4) + 1 : f.height - 1;
  if (box[0] > box[1] || box[2] > box[3]) return false;  // off screen
  for (int i = 0; i < 4; ++i) s.box[i] = static_cast<int16_t>(box[i]);
  return true;
}

}  // namespace stipple
