// stipple raster — the per-node set-up in AVX2 lanes. See node_lanes.h;
// built with -mavx2 and called only where avx2::supported(). Every step
// names the scalar line it repeats (PointRenderer::draw_node,
// NodeProjection::setup, FrameAngles, ppn_index); each bound is stated
// there and in docs/fixed_point.md.
#include "raster/node_lanes.h"

#if defined(__x86_64__) || defined(__i386__)

#include <immintrin.h>

#include "raster/points_per_node.h"

namespace stipple {
namespace avx2 {
namespace {

using V = __m256i;

inline V set1(int32_t v) { return _mm256_set1_epi32(v); }
inline V add(V a, V b) { return _mm256_add_epi32(a, b); }
inline V sub(V a, V b) { return _mm256_sub_epi32(a, b); }
inline V band(V a, V b) { return _mm256_and_si256(a, b); }
inline V bor(V a, V b) { return _mm256_or_si256(a, b); }
inline V pair(V lo, V hi) { return bor(band(lo, set1(0xFFFF)), _mm256_slli_epi32(hi, 16)); }
inline V gather(const void* base, V index) { return _mm256_i32gather_epi32(static_cast<const int*>(base), index, 4); }
inline V gather16(const uint16_t* base, V index) {
  return band(_mm256_i32gather_epi32(reinterpret_cast<const int*>(base), index, 2), set1(0xFFFF));
}
// (a b + c d + 2^13) >> 14 for (a, c) and (b, d) int16 pairs: rot_q14.
inline V rot(V ac, V bd) { return _mm256_srai_epi32(add(_mm256_madd_epi16(ac, bd), set1(1 << 13)), 14); }

// 64-bit products of int32 lanes: lanes 0, 2, 4, 6 and 1, 3, 5, 7.
struct Wide {
  V even, odd;
};
inline Wide mul64(V a, V b) {
  return Wide{_mm256_mul_epi32(a, b), _mm256_mul_epi32(_mm256_srli_epi64(a, 32), _mm256_srli_epi64(b, 32))};
}
// (w + add) >> shift (shift <= 32) back in 8 int32 lanes, for results that
// fit 32 bits: their low 32 bits are the same from a logical shift.
inline V narrow(Wide w, int64_t plus, int shift) {
  const __m256i c = _mm256_set1_epi64x(plus);
  const V e = _mm256_srli_epi64(_mm256_add_epi64(w.even, c), shift);
  const V o = _mm256_slli_epi64(_mm256_srli_epi64(_mm256_add_epi64(w.odd, c), shift), 32);
  return _mm256_blend_epi32(e, o, 0xAA);
}
// Lanes whose product lies outside [-2^bits, 2^bits).
inline V beyond(Wide w, int bits) {
  const __m256i hi = _mm256_set1_epi64x((int64_t{1} << bits) - 1), lo = _mm256_set1_epi64x(-(int64_t{1} << bits) - 1);
  const V e = bor(_mm256_cmpgt_epi64(w.even, hi), _mm256_cmpgt_epi64(lo, w.even));
  const V o = bor(_mm256_cmpgt_epi64(w.odd, hi), _mm256_cmpgt_epi64(lo, w.odd));
  return _mm256_blend_epi32(e, o, 0xAA);  // each 64-bit result's mask, in its low half (even) or high half (odd)
}
// The difference of two 64-bit results, even and odd lanes alike.
inline Wide sub64(Wide a, Wide b) { return Wide{_mm256_sub_epi64(a.even, b.even), _mm256_sub_epi64(a.odd, b.odd)}; }

// floor(log2 x) for 1 <= x < 2^31.
template <int kStep>
inline V log2_step(V& x, V r) {
  const V sh = band(_mm256_cmpgt_epi32(x, set1((1 << kStep) - 1)), set1(kStep));
  x = _mm256_srlv_epi32(x, sh);
  return add(r, sh);
}
inline V log2_32(V x) {
  V r = _mm256_setzero_si256();
  r = log2_step<16>(x, r);
  r = log2_step<8>(x, r);
  r = log2_step<4>(x, r);
  r = log2_step<2>(x, r);
  return log2_step<1>(x, r);
}
// half_octave (points_per_node.h) of 32-bit lanes below 2^31.
inline V half_octave32(V x) {
  const V top = log2_32(_mm256_max_epi32(x, set1(1)));
  const V bit = band(_mm256_srlv_epi32(x, _mm256_max_epi32(sub(top, set1(1)), _mm256_setzero_si256())), set1(1));
  return band(add(add(top, top), bit), _mm256_cmpgt_epi32(x, set1(1)));
}
// sample_reach_bucket (point_renderer.h) of lanes of 1 or more points.
inline V sample_reach_bucket8(V count) {
  const V t = sub(count, set1(1));
  const V k = log2_32(_mm256_max_epi32(t, set1(1)));
  const V half = band(_mm256_srlv_epi32(t, sub(k, set1(1))), set1(1));
  return _mm256_blendv_epi8(add(add(k, k), half), t, _mm256_cmpgt_epi32(set1(3), count));
}
// half_octave of 4 64-bit lanes (below 2^62), in each lane's low half.
[[gnu::always_inline]] inline __m256i half_octave64(__m256i x) {
  const __m256i one = _mm256_set1_epi64x(1);
  __m256i v = x, r = _mm256_setzero_si256();
  const auto step = [&](int s) {
    const __m256i sh = band(_mm256_cmpgt_epi64(v, _mm256_set1_epi64x((int64_t{1} << s) - 1)), _mm256_set1_epi64x(s));
    v = _mm256_srlv_epi64(v, sh);
    r = _mm256_add_epi64(r, sh);
  };
  step(32);
  step(16);
  step(8);
  step(4);
  step(2);
  step(1);
  const __m256i below = _mm256_sub_epi64(r, one);  // top - 1 (top >= 1 where x > 1)
  const __m256i bit = band(_mm256_srlv_epi64(x, band(below, _mm256_cmpgt_epi64(r, _mm256_setzero_si256()))), one);
  return band(_mm256_add_epi64(_mm256_add_epi64(r, r), bit), _mm256_cmpgt_epi64(x, one));
}

inline V intensity_index8(V l) {
  const V i = _mm256_srai_epi32(add(l, set1(kIntensityOffsetQ14)), 7);
  return _mm256_min_epi32(_mm256_max_epi32(i, _mm256_setzero_si256()), set1(kIntensityEntries - 1));
}

// Lane orders that left-pack a mask's lanes.
struct Packing {
  uint8_t order[256][8];
  constexpr Packing() : order{} {
    for (int m = 0; m < 256; ++m) {
      int k = 0;
      for (int l = 0; l < 8; ++l)
        if (m >> l & 1) order[m][k++] = static_cast<uint8_t>(l);
      while (k < 8) order[m][k++] = 0;
    }
  }
};
constexpr Packing kPacking;

// An 8 x 8 transpose of 32-bit elements: v[i] lane k becomes v[k] lane i.
inline void transpose8(V v[8]) {
  V t[8], u[8];
#pragma GCC unroll 4
  for (int i = 0; i < 4; ++i) {
    t[2 * i] = _mm256_unpacklo_epi32(v[2 * i], v[2 * i + 1]);
    t[2 * i + 1] = _mm256_unpackhi_epi32(v[2 * i], v[2 * i + 1]);
  }
#pragma GCC unroll 2
  for (int h = 0; h < 2; ++h) {  // rows 0-3, then 4-7
    u[4 * h] = _mm256_unpacklo_epi64(t[4 * h], t[4 * h + 2]);
    u[4 * h + 1] = _mm256_unpackhi_epi64(t[4 * h], t[4 * h + 2]);
    u[4 * h + 2] = _mm256_unpacklo_epi64(t[4 * h + 1], t[4 * h + 3]);
    u[4 * h + 3] = _mm256_unpackhi_epi64(t[4 * h + 1], t[4 * h + 3]);
  }
#pragma GCC unroll 4
  for (int k = 0; k < 4; ++k) {
    v[k] = _mm256_permute2x128_si256(u[k], u[4 + k], 0x20);
    v[4 + k] = _mm256_permute2x128_si256(u[k], u[4 + k], 0x31);
  }
}

// One batch of eight nodes as the stages below leave it: which lanes are
// set up here (live), culled, or left to the scalar set-up (fallback).
struct Lanes {
  V live, culled, fallback;
  V X, Y, Z;             // the mean in camera space
  V frame[3][3];         // the position frame in camera space (Q14)
  V sigma[3];            // sigma_p, clamped (MU)
  V axes[3][3];          // the axes in camera space (MU)
  V x0, y0, mx[3], my[3];  // the projection (NodeProjection: Q4; 1/256 px a sigma)
  V count;               // points to draw
  V dz[3], dshift, depth0;  // depth terms (draw_node's)
  V depth_in_word;       // the depths stay inside the depth word
};

// The position frame (FrameAngles::position_frame, turn) and the axes in
// camera space: (frame sigma + 2^13) >> 14, sigma <= 2^25.
template <class FieldOf>
[[gnu::always_inline]] inline void position_axes(const NodeLaneFrame& f, const FieldOf& field, Lanes& l) {
  const V zero = _mm256_setzero_si256();
  V(&frame)[3][3] = l.frame;
  const V theta = gather(f.theta_p, field(Field::kFpTheta));  // (sin, cos)
  const V phi = field(Field::kFpPhi);
  const V gamma_index = band(sub(_mm256_sllv_epi32(field(Field::kFpPsi), set1(f.gamma_psi_shift_p)),
                                 _mm256_sllv_epi32(phi, set1(f.gamma_phi_shift_p))),
                             set1(static_cast<int32_t>(f.gamma_mask_p)));
  const V gamma = gather(f.gamma_p, gamma_index);
  const V cs_t = bor(_mm256_srli_epi32(theta, 16), _mm256_slli_epi32(sub(zero, theta), 16));  // (cos, -sin)
  const V gc_gs = bor(_mm256_srli_epi32(gamma, 16), _mm256_slli_epi32(gamma, 16));         // (cos, sin)
  const V ngs_gc = bor(band(sub(zero, gamma), set1(0xFFFF)), band(gamma, set1(static_cast<int32_t>(0xFFFF0000u))));
  const V tp = _mm256_slli_epi32(phi, 2);  // CameraPhi: 4 words
  const V w0 = gather(f.position, tp), w1 = gather(f.position, add(tp, set1(1))), w2 = gather(f.position, add(tp, set1(2)));
  const V t0[3] = {w0, _mm256_srli_epi32(w0, 16), w1};  // low halves are t0
  const V t1_hi[3] = {band(w1, set1(static_cast<int32_t>(0xFFFF0000u))), _mm256_slli_epi32(w2, 16),
                      band(w2, set1(static_cast<int32_t>(0xFFFF0000u)))};  // t1 in the high half
#pragma GCC unroll 8
  for (int k = 0; k < 3; ++k) {
    const V t0t2 = bor(band(t0[k], set1(0xFFFF)), set1(static_cast<int32_t>(static_cast<uint32_t>(f.column2[k]) << 16)));
    const V u = rot(t0t2, cs_t);
    const V ut1 = bor(band(u, set1(0xFFFF)), t1_hi[k]);
    frame[0][k] = rot(ut1, gc_gs);
    frame[1][k] = rot(ut1, ngs_gc);
    frame[2][k] = rot(t0t2, theta);
  }
  const V sp3 = _mm256_mullo_epi32(field(Field::kSigmaP), set1(3));
#pragma GCC unroll 8
  for (int k = 0; k < 3; ++k) {
    const V sigma = _mm256_min_epi32(gather(f.sigma_p, add(sp3, set1(k))), set1(1 << 25));
    l.sigma[k] = sigma;
#pragma GCC unroll 8
    for (int i = 0; i < 3; ++i) l.axes[k][i] = narrow(mul64(frame[k][i], sigma), 1 << 13, 14);
  }
}

// NodeProjection::setup: u = 2^46 / Z, one division a lane; lanes whose
// slopes pass 2^15 fall back.
[[gnu::always_inline]] inline void project(const NodeLaneFrame& f, V Zs, Lanes& l) {
  const V ones = _mm256_cmpeq_epi32(_mm256_setzero_si256(), _mm256_setzero_si256());
  const V X = l.X, Y = l.Y;
  const V(&axes)[3][3] = l.axes;
  V(&mx)[3] = l.mx;
  V(&my)[3] = l.my;
  alignas(32) int32_t zs[8], us[8];
  _mm256_store_si256(reinterpret_cast<__m256i*>(zs), Zs);
#pragma GCC unroll 8
  for (int k = 0; k < 8; ++k) us[k] = static_cast<int32_t>((int64_t{1} << 46) / zs[k]);
  const V u = _mm256_load_si256(reinterpret_cast<const __m256i*>(us));
  const V focal = set1(f.focal_q4);
  const V xr = narrow(mul64(X, u), 0, 30), yr = narrow(mul64(Y, u), 0, 30);
  l.x0 = add(set1(f.cx_q4), narrow(mul64(focal, xr), 0, 16));
  l.y0 = add(set1(f.cy_q4), narrow(mul64(focal, yr), 0, 16));
  const V fu = narrow(mul64(focal, u), 0, 20);
#pragma GCC unroll 8
  for (int k = 0; k < 3; ++k) {
    const V dx = sub(axes[k][0], narrow(mul64(xr, axes[k][2]), 0, 16));
    const V dy = sub(axes[k][1], narrow(mul64(yr, axes[k][2]), 0, 16));
    const Wide px = mul64(dx, fu), py = mul64(dy, fu);
    // Beyond 2^15 a slope (2^37 before the shift): not a lane's node.
    l.fallback = bor(l.fallback, band(l.live, bor(beyond(px, 37), beyond(py, 37))));
    mx[k] = narrow(px, 0, 22);
    my[k] = narrow(py, 0, 22);
  }
  l.live = band(l.live, _mm256_xor_si256(l.fallback, ones));
}

// The 3.5 sigma extent on screen (L1) culls nodes wholly off screen; the
// points: ppn_index of the screen covariance, then the table.
[[gnu::always_inline]] inline void footprint(const NodeLaneFrame& f, Lanes& l) {
  const V zero = _mm256_setzero_si256(), ones = _mm256_cmpeq_epi32(zero, zero);
  const V x0 = l.x0, y0 = l.y0;
  V vx4[3], vy4[3], ex = zero, ey = zero;
#pragma GCC unroll 8
  for (int k = 0; k < 3; ++k) {
    vx4[k] = _mm256_srai_epi32(l.mx[k], 4);
    vy4[k] = _mm256_srai_epi32(l.my[k], 4);
    ex = add(ex, _mm256_abs_epi32(vx4[k]));
    ey = add(ey, _mm256_abs_epi32(vy4[k]));
  }
  ex = _mm256_srai_epi32(_mm256_mullo_epi32(ex, set1(7)), 1);
  ey = _mm256_srai_epi32(_mm256_mullo_epi32(ey, set1(7)), 1);
  V a = zero, b = zero, cc = zero;
#pragma GCC unroll 8
  for (int k = 0; k < 3; ++k) {
    a = add(a, _mm256_mullo_epi32(vx4[k], vx4[k]));
    b = add(b, _mm256_mullo_epi32(vx4[k], vy4[k]));
    cc = add(cc, _mm256_mullo_epi32(vy4[k], vy4[k]));
  }
  // A possible close-up — a disc, or more points (a + c past close_up_wide:
  // screen_sigma_beyond's bound) — is the scalar set-up's.
  if (f.close_ups) {
    const V wide = band(l.live, _mm256_cmpgt_epi32(add(a, cc), set1(f.close_up_wide)));
    l.fallback = bor(l.fallback, wide);
    l.live = band(l.live, _mm256_xor_si256(wide, ones));
  }
  const V off = bor(bor(_mm256_cmpgt_epi32(zero, add(x0, ex)), _mm256_cmpgt_epi32(sub(x0, ex), set1(f.width_q4 - 1))),
                    bor(_mm256_cmpgt_epi32(zero, add(y0, ey)), _mm256_cmpgt_epi32(sub(y0, ey), set1(f.height_q4 - 1))));
  l.culled = bor(l.culled, band(l.live, off));
  l.live = band(l.live, _mm256_xor_si256(off, ones));

  const V t = half_octave32(add(a, cc));
  const Wide ac = mul64(a, cc), bb = mul64(b, b);
  const Wide det = sub64(ac, bb);
  const V ho_det = _mm256_blend_epi32(half_octave64(_mm256_slli_epi64(det.even, 2)),
                                      _mm256_slli_epi64(half_octave64(_mm256_slli_epi64(det.odd, 2)), 32), 0xAA);
  const V det_pos = _mm256_blend_epi32(_mm256_cmpgt_epi64(det.even, _mm256_setzero_si256()),
                                       _mm256_cmpgt_epi64(det.odd, _mm256_setzero_si256()), 0xAA);
  V d = _mm256_blendv_epi8(set1(kPpnAspects - 1), sub(add(t, t), ho_det), det_pos);
  d = _mm256_min_epi32(_mm256_max_epi32(d, zero), set1(kPpnAspects - 1));
  const V size_index = _mm256_min_epi32(t, set1(kPpnSizes - 1));
  const V measured = gather16(f.ppn, add(_mm256_mullo_epi32(size_index, set1(kPpnAspects)), d));
  l.count = _mm256_min_epi32(
      _mm256_max_epi32(_mm256_srli_epi32(add(_mm256_mullo_epi32(measured, set1(static_cast<int32_t>(f.quality_q8))), set1(128)), 8),
                       set1(1)),
      set1(static_cast<int32_t>(f.samples)));

}

// Depth: depth0 = (Z - near) << shift, dz = (A_z << shift) >> e in 16 bits;
// whether every depth of the node stays inside the word.
[[gnu::always_inline]] inline void depth_terms(const NodeLaneFrame& f, Lanes& l) {
  const V zero = _mm256_setzero_si256();
  const V Z = l.Z;
  const V(&axes)[3][3] = l.axes;
  V(&dz)[3] = l.dz;
  const V s_d = set1(f.depth_shift);
  const V az_max = _mm256_max_epi32(_mm256_max_epi32(_mm256_abs_epi32(axes[0][2]), _mm256_abs_epi32(axes[1][2])),
                                    _mm256_abs_epi32(axes[2][2]));
  const V bits = add(log2_32(_mm256_max_epi32(az_max, set1(1))), set1(1));
  const V e = band(_mm256_max_epi32(sub(add(bits, s_d), set1(15)), zero), _mm256_cmpgt_epi32(az_max, zero));
  const V left = _mm256_max_epi32(sub(s_d, e), zero), right = _mm256_max_epi32(sub(e, s_d), zero);
  V dsum = zero;
#pragma GCC unroll 8
  for (int k = 0; k < 3; ++k) {
    dz[k] = _mm256_srav_epi32(_mm256_sllv_epi32(axes[k][2], left), right);
    dsum = add(dsum, _mm256_abs_epi32(dz[k]));
  }
  const V dshift = l.dshift = sub(set1(12), e);
  const V reach = _mm256_srlv_epi32(_mm256_mullo_epi32(dsum, set1(kGaussianClip)), _mm256_max_epi32(dshift, zero));
  const V dn = sub(Z, set1(f.near));
  const V fits = _mm256_cmpeq_epi32(_mm256_srl_epi32(dn, _mm_cvtsi32_si128(32 - f.depth_shift)), zero);
  const V depth0 = l.depth0 = _mm256_sll_epi32(dn, _mm_cvtsi32_si128(f.depth_shift));
  const V above = _mm256_cmpeq_epi32(_mm256_max_epu32(depth0, add(reach, set1(1))), depth0);  // depth0 > reach
  const V below = _mm256_cmpeq_epi32(_mm256_min_epu32(depth0, sub(set1(static_cast<int32_t>(0xFFFFFFFEu)), reach)), depth0);

  l.depth_in_word = band(fits, band(above, below));
}

// A node's shading constants in lanes (FrameAngles::light_terms; the
// surface's turn as draw_node's kSurface block).
struct LaneShade {
  V sn, lt, ht, l0h0, intensity, specular;
  V surface[2][3];
  V node_rgb;  // the node's colour, shaded
};
template <PointNormals kNormals, bool kSpecular, class FieldOf>
[[gnu::always_inline]] inline LaneShade lane_shade(const NodeLaneFrame& f, const FieldOf& field, const Lanes& l) {
  const V zero = _mm256_setzero_si256();
  const V(&frame)[3][3] = l.frame;
  const V(&sigma_c)[3] = l.sigma;
  LaneShade sh{zero, zero, zero, zero, set1(256), zero, {{zero, zero, zero}, {zero, zero, zero}}, zero};
  V &sn = sh.sn, &lt = sh.lt, &ht = sh.ht, &l0h0 = sh.l0h0, &intensity = sh.intensity, &specular = sh.specular;
  V(&surface)[2][3] = sh.surface;
  if (f.lit) {
    const V th = gather(f.theta_n, field(Field::kFnTheta));
    const V ph = field(Field::kFnPhi);
    const V gi = band(sub(_mm256_sllv_epi32(field(Field::kFnPsi), set1(f.gamma_psi_shift_n)),
                          _mm256_sllv_epi32(ph, set1(f.gamma_phi_shift_n))),
                      set1(static_cast<int32_t>(f.gamma_mask_n)));
    const V ga = gather(f.gamma_n, gi);
    const V cs_n = bor(_mm256_srli_epi32(th, 16), _mm256_slli_epi32(sub(zero, th), 16));
    const V gcs = bor(_mm256_srli_epi32(ga, 16), _mm256_slli_epi32(ga, 16));
    const V ngc = bor(band(sub(zero, ga), set1(0xFFFF)), band(ga, set1(static_cast<int32_t>(0xFFFF0000u))));
    const V lp = _mm256_slli_epi32(ph, 1);  // LightPhi: 2 words
    const V wl = gather(f.light, lp), wh = gather(f.light, add(lp, set1(1)));
    const auto terms = [&](V w, int16_t vz, V* t1t2, V* n0) {
      const V wxz = bor(band(w, set1(0xFFFF)), set1(static_cast<int32_t>(static_cast<uint32_t>(static_cast<uint16_t>(vz)) << 16)));
      const V uu = rot(wxz, cs_n);
      const V uwy = bor(band(uu, set1(0xFFFF)), band(w, set1(static_cast<int32_t>(0xFFFF0000u))));
      *t1t2 = pair(rot(uwy, gcs), rot(uwy, ngc));
      *n0 = rot(wxz, th);
    };
    V l2, h2;
    terms(wl, f.light_z, &lt, &l2);
    terms(wh, f.half_z, &ht, &h2);
    const V sn2 = _mm256_slli_epi32(field(Field::kSigmaN), 1);
    // Signed (the curvature's sign) for the surface's turn, its magnitude for sn.
    const auto clamp_sn = [&](V v) { return _mm256_min_epi32(_mm256_max_epi32(v, set1(-(4 << 12))), set1(4 << 12)); };
    const V sigma_n[2] = {clamp_sn(gather(f.sigma_n, sn2)), clamp_sn(gather(f.sigma_n, add(sn2, set1(1))))};
    sn = pair(_mm256_abs_epi32(sigma_n[0]), _mm256_abs_epi32(sigma_n[1]));
    l0h0 = pair(_mm256_srai_epi32(add(l2, set1(2)), 2), _mm256_srai_epi32(add(h2, set1(2)), 2));
    intensity = gather16(f.shading->diffuse, intensity_index8(l2));
    if (kSpecular) specular = gather(f.shading->specular, intensity_index8(h2));
    if constexpr (kNormals == PointNormals::kSurface) {
      // The normal frame's tangents in camera space (turn, its first two axes).
      const V tn = _mm256_slli_epi32(ph, 2);
      const V n0 = gather(f.normal, tn), n1 = gather(f.normal, add(tn, set1(1))), n2 = gather(f.normal, add(tn, set1(2)));
      const V u0[3] = {n0, _mm256_srli_epi32(n0, 16), n1};
      const V u1_hi[3] = {band(n1, set1(static_cast<int32_t>(0xFFFF0000u))), _mm256_slli_epi32(n2, 16),
                          band(n2, set1(static_cast<int32_t>(0xFFFF0000u)))};
      V tangent[2][3];
#pragma GCC unroll 8
      for (int comp = 0; comp < 3; ++comp) {
        const V t0t2 =
            bor(band(u0[comp], set1(0xFFFF)), set1(static_cast<int32_t>(static_cast<uint32_t>(f.column2[comp]) << 16)));
        const V uu = rot(t0t2, cs_n);
        const V ut1 = bor(band(uu, set1(0xFFFF)), u1_hi[comp]);
        tangent[0][comp] = rot(ut1, gcs);
        tangent[1][comp] = rot(ut1, ngc);
      }
      // sigma scaled to 15 bits, w_k = (sigma_i a_i . t_k) >> 15, normalized
      // through the rsqrt table (draw_node's kSurface block).
      const V smax = _mm256_max_epi32(_mm256_max_epi32(sigma_c[0], sigma_c[1]), sigma_c[2]);
      const V scale = _mm256_max_epi32(sub(add(log2_32(_mm256_max_epi32(smax, set1(1))), set1(1)), set1(15)),
                                       _mm256_setzero_si256());
      V s_scaled[3];
#pragma GCC unroll 8
      for (int i = 0; i < 3; ++i) s_scaled[i] = _mm256_srlv_epi32(sigma_c[i], scale);
#pragma GCC unroll 8
      for (int k = 0; k < 2; ++k) {
        V w[3], s2 = zero;
        const V txy = pair(tangent[k][0], tangent[k][1]);
#pragma GCC unroll 8
        for (int i = 0; i < 3; ++i) {
          const V dot = add(_mm256_madd_epi16(pair(frame[i][0], frame[i][1]), txy), _mm256_mullo_epi32(frame[i][2], tangent[k][2]));
          const V cosine = _mm256_srai_epi32(add(dot, set1(1 << 13)), 14);
          w[i] = _mm256_srai_epi32(_mm256_mullo_epi32(s_scaled[i], cosine), 15);
          s2 = add(s2, _mm256_mullo_epi32(w[i], w[i]));
        }
        // rsqrt_scale: s2 = m 4^r with m in [256, 1024); 2^14 / sqrt(s2) = rsqrt[m - 256] >> (5 + r).
        const V top = log2_32(_mm256_max_epi32(s2, set1(1)));
        const V r = _mm256_srai_epi32(sub(top, set1(8)), 1);
        const V m = _mm256_sllv_epi32(_mm256_srlv_epi32(s2, _mm256_max_epi32(add(r, r), zero)),
                                      _mm256_max_epi32(sub(zero, add(r, r)), zero));
        const V mul = gather16(f.shading->rsqrt, _mm256_max_epi32(sub(m, set1(256)), zero));
        const V shift = add(r, set1(5));
        const V some = _mm256_cmpgt_epi32(s2, zero);
#pragma GCC unroll 8
        for (int i = 0; i < 3; ++i) {
          const V n = _mm256_srav_epi32(_mm256_mullo_epi32(w[i], mul), shift);
          const V turn = band(_mm256_min_epi32(_mm256_max_epi32(n, set1(-16416)), set1(16416)), some);
          surface[k][i] = _mm256_srai_epi32(add(_mm256_mullo_epi32(sigma_n[k], turn), set1(1 << 13)), 14);
        }
      }
    }
  }
  const auto shade_channel = [&](int32_t channel) {
    const V v = add(_mm256_srli_epi32(_mm256_mullo_epi32(set1(channel), intensity), 8), specular);
    return _mm256_min_epi32(v, set1(255));
  };
  sh.node_rgb = bor(bor(_mm256_slli_epi32(shade_channel(static_cast<int32_t>(f.base_rgb >> 16)), 16),
                             _mm256_slli_epi32(shade_channel(static_cast<int32_t>((f.base_rgb >> 8) & 0xFF)), 8)),
                         shade_channel(static_cast<int32_t>(f.base_rgb & 0xFF)));
  return sh;
}

// The tile pass's lanes: slopes and depth terms in 16 bits, the depths
// inside the word, within 2 x 2 tiles (pixel_span: the reach of the
// count's samples, sample_reach_bucket; lanes whose slopes reach 2^15 wrap
// here and are not tile lanes). The rest of the live lanes fall back.
struct LaneTiles {
  V lo_x, hi_x, lo_y, hi_y;  // the span on screen (px)
  V tx0, ty0, tx1, ty1;      // the tiles it touches
  V tile;                    // the lanes that wait for the tile pass
};
[[gnu::always_inline]] inline LaneTiles tile_lanes(const NodeLaneFrame& f, Lanes& l) {
  const V zero = _mm256_setzero_si256(), ones = _mm256_cmpeq_epi32(zero, zero);
  const V(&mx)[3] = l.mx;
  const V(&my)[3] = l.my;
  const V x0 = l.x0, y0 = l.y0, dshift = l.dshift;
  LaneTiles t;
  V &lo_x = t.lo_x, &hi_x = t.hi_x, &lo_y = t.lo_y, &hi_y = t.hi_y;
  const V bucket = sample_reach_bucket8(l.count);
  V sx = zero, sy = zero, rx = zero, ry = zero;
#pragma GCC unroll 8
  for (int k = 0; k < 3; ++k) {
    const V g = _mm256_i32gather_epi32(f.sample_reach, add(_mm256_slli_epi32(bucket, 2), set1(k)), 4);
    sx = add(sx, _mm256_abs_epi32(mx[k]));
    sy = add(sy, _mm256_abs_epi32(my[k]));
    rx = add(rx, _mm256_mullo_epi32(_mm256_abs_epi32(mx[k]), g));
    ry = add(ry, _mm256_mullo_epi32(_mm256_abs_epi32(my[k]), g));
  }
  const int32_t corner = (f.size - 1) * 8;
  const auto span = [&](V p0, V offsets, V* lo, V* hi) {
    const V dd = _mm256_srai_epi32(offsets, 16);
    *lo = _mm256_srai_epi32(sub(sub(p0, dd), set1(1 + corner)), 4);
    *hi = add(_mm256_srai_epi32(sub(add(p0, dd), set1(corner)), 4), set1(f.size - 1));
  };
  span(x0, rx, &lo_x, &hi_x);
  span(y0, ry, &lo_y, &hi_y);
  const __m128i tl = _mm_cvtsi32_si128(f.tile_log2);
  const V tx0 = t.tx0 = _mm256_sra_epi32(_mm256_max_epi32(lo_x, zero), tl);
  const V ty0 = t.ty0 = _mm256_sra_epi32(_mm256_max_epi32(lo_y, zero), tl);
  const V tx1 = t.tx1 = _mm256_sra_epi32(_mm256_min_epi32(hi_x, set1(f.width - 1)), tl);
  const V ty1 = t.ty1 = _mm256_sra_epi32(_mm256_min_epi32(hi_y, set1(f.height - 1)), tl);
  const V small = band(band(_mm256_cmpgt_epi32(set1(1 << 15), sx), _mm256_cmpgt_epi32(set1(1 << 15), sy)),
                       _mm256_cmpgt_epi32(dshift, set1(-1)));
  const V on_screen = band(band(_mm256_cmpgt_epi32(hi_x, set1(-1)), _mm256_cmpgt_epi32(hi_y, set1(-1))),
                           band(_mm256_cmpgt_epi32(set1(f.width), lo_x), _mm256_cmpgt_epi32(set1(f.height), lo_y)));
  const V few_tiles = band(_mm256_cmpgt_epi32(set1(2), sub(tx1, tx0)), _mm256_cmpgt_epi32(set1(2), sub(ty1, ty0)));
  t.tile = band(l.live, band(band(small, l.depth_in_word), band(on_screen, few_tiles)));
  l.fallback = bor(l.fallback, band(l.live, _mm256_xor_si256(t.tile, ones)));
  return t;
}


// The TileNodes of the tile lanes, left-packed from `base` (TileNodes::store):
// fields 0-23 of the 8 lanes, as three 8 x 8 transposes to 8-word pieces of rows.
template <PointNormals kNormals>
[[gnu::always_inline]] inline void store_tile_nodes(const NodeLaneFrame& f, const Lanes& l, const LaneShade& sh,
                                                    const LaneTiles& t, uint32_t tile_mask, TileNodes& out,
                                                    uint32_t base) {
  const V(&mx)[3] = l.mx;
  const V(&my)[3] = l.my;
  const V(&dz)[3] = l.dz;
  const V(&surface)[2][3] = sh.surface;
  const int32_t corner = (f.size - 1) * 8;
  const V order = _mm256_cvtepu8_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(kPacking.order[tile_mask])));
  V fields[24] = {};
  const auto put = [&](TileField which, V v) { fields[static_cast<int>(which)] = v; };
  put(TileField::kMx01, pair(mx[0], mx[1]));
  put(TileField::kMx2, band(mx[2], set1(0xFFFF)));
  put(TileField::kMy01, pair(my[0], my[1]));
  put(TileField::kMy2, band(my[2], set1(0xFFFF)));
  put(TileField::kDz01, pair(dz[0], dz[1]));
  put(TileField::kDz2, band(dz[2], set1(0xFFFF)));
  put(TileField::kX0, sub(l.x0, set1(corner)));
  put(TileField::kY0, sub(l.y0, set1(corner)));
  put(TileField::kDepth0, l.depth0);
  put(TileField::kSpanX, pair(t.lo_x, t.hi_x));
  put(TileField::kSpanY, pair(t.lo_y, t.hi_y));
  put(TileField::kCountShift, bor(l.count, _mm256_slli_epi32(l.dshift, 16)));
  put(TileField::kSn, sh.sn);
  put(TileField::kLt, sh.lt);
  put(TileField::kHt, sh.ht);
  put(TileField::kL0H0, sh.l0h0);
  put(TileField::kBaseRgb, set1(static_cast<int32_t>(f.base_rgb)));
  put(TileField::kNodeRgb, sh.node_rgb);
  put(TileField::kLighting, bor(sh.intensity, _mm256_slli_epi32(sh.specular, 16)));
  if constexpr (kNormals == PointNormals::kSurface) {
    put(TileField::kS0_01, pair(surface[0][0], surface[0][1]));
    put(TileField::kS0_2, band(surface[0][2], set1(0xFFFF)));
    put(TileField::kS1_01, pair(surface[1][0], surface[1][1]));
    put(TileField::kS1_2, band(surface[1][2], set1(0xFFFF)));
  }
  // (Field 23 on, the per-point colour's, is not read: the lanes take no model colour.)
  static_assert(static_cast<int>(TileField::kS1_2) < 24, "the lanes write fields 0-23");
#pragma GCC unroll 3
  for (int piece = 0; piece < 3; ++piece) {
    V rows[8];
#pragma GCC unroll 8
    for (int i = 0; i < 8; ++i) rows[i] = _mm256_permutevar8x32_epi32(fields[8 * piece + i], order);
    transpose8(rows);
#pragma GCC unroll 8
    for (int k = 0; k < 8; ++k) _mm256_storeu_si256(reinterpret_cast<__m256i*>(out.row(base + k) + 8 * piece), rows[k]);
  }

}

}  // namespace

template <PointNormals kNormals, bool kSpecular>
uint32_t set_up_nodes(const NodeLaneFrame& f, uint32_t first_slot, uint32_t count, TileNodes& out, uint32_t base,
                      NodeLaneBatch* batches) {
  const uint32_t base0 = base;
  const V zero = _mm256_setzero_si256(), ones = _mm256_cmpeq_epi32(zero, zero);
  const V lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  const V last_slot = set1(static_cast<int32_t>(first_slot + count - 1));
  // The records' fields: a 32-bit window each (node_format.h's FieldWindow).
  struct Window {
    const int* base;
    __m128i shift;
    V mask;
  };
  Window windows[kFieldCount];
#pragma GCC unroll 8
  for (int i = 0; i < kFieldCount; ++i)
    windows[i] = Window{reinterpret_cast<const int*>(f.records + f.window[i].byte), _mm_cvtsi32_si128(f.window[i].shift),
                        set1(f.window[i].mask)};
  for (uint32_t first = first_slot, batch = 0; first < first_slot + count; first += 8, ++batch) {
    // For lanes past the last node, the last node's fields.
    const V active = _mm256_cmpgt_epi32(set1(static_cast<int32_t>(first_slot + count - first)), lane);
    const V slot = _mm256_min_epi32(add(set1(static_cast<int32_t>(first)), lane), last_slot);
    const V at = _mm256_mullo_epi32(slot, set1(static_cast<int32_t>(f.stride)));
    const auto field = [&](Field which) {
      const Window& w = windows[static_cast<int>(which)];
      return band(_mm256_srl_epi32(_mm256_i32gather_epi32(w.base, at, 1), w.shift), w.mask);
    };

    // The mean in camera space: the sum of the three axes' terms.
    const V q[3] = {field(Field::kPosX), field(Field::kPosY), field(Field::kPosZ)};
    V c[3] = {zero, zero, zero};
#pragma GCC unroll 3
    for (int a = 0; a < 3; ++a) {
      const V row = _mm256_mullo_epi32(q[a], set1(3));
#pragma GCC unroll 3
      for (int i = 0; i < 3; ++i) c[i] = add(c[i], gather(f.mean[a] + i, row));
    }
    Lanes l;
    const V X = l.X = c[0], Y = l.Y = c[1], Z = l.Z = c[2];
    // in_view: Z > near, |X| <= 8 Z, |Y| <= 8 Z (|v| <= 8 Z as ceil(|v| / 8) <= Z).
    const auto within = [&](V v) {
      const V ceil8 = _mm256_srli_epi32(add(_mm256_abs_epi32(v), set1(7)), 3);
      return _mm256_cmpeq_epi32(_mm256_min_epu32(ceil8, Z), ceil8);
    };
    const V in_view = band(band(_mm256_cmpgt_epi32(Z, set1(f.near)), within(X)), within(Y));
    const V outside = band(active, _mm256_xor_si256(in_view, ones));
    l.culled = f.close_ups ? _mm256_setzero_si256() : outside;  // with close-ups, the scalar set-up's
    // The lanes' range: 2^46 / Z below 2^31 (and every product below within 64 bits).
    l.fallback = bor(band(band(active, in_view), _mm256_cmpgt_epi32(set1(1 << 16), Z)), f.close_ups ? outside : _mm256_setzero_si256());
    l.live = band(band(active, in_view), _mm256_xor_si256(l.fallback, ones));
    const V Zs = _mm256_blendv_epi8(set1(1 << 16), Z, l.live);  // no division by a culled lane's Z

    position_axes(f, field, l);
    project(f, Zs, l);
    footprint(f, l);
    depth_terms(f, l);
    const LaneShade sh = lane_shade<kNormals, kSpecular>(f, field, l);
    const LaneTiles t = tile_lanes(f, l);
    const uint32_t tile_mask = static_cast<uint32_t>(_mm256_movemask_ps(_mm256_castsi256_ps(t.tile)));
    store_tile_nodes<kNormals>(f, l, sh, t, tile_mask, out, base);

    NodeLaneBatch& r = batches[batch];
    r.tile_mask = tile_mask;
    r.culled_mask = static_cast<uint32_t>(_mm256_movemask_ps(_mm256_castsi256_ps(l.culled)));
    r.tile_count = static_cast<uint32_t>(__builtin_popcount(tile_mask));
    r.culled_count = static_cast<uint32_t>(__builtin_popcount(r.culled_mask));
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(r.count), l.count);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(r.tiles),
                        bor(bor(t.tx0, _mm256_slli_epi32(t.ty0, 12)),
                            bor(_mm256_slli_epi32(band(_mm256_cmpgt_epi32(t.tx1, t.tx0), set1(1)), 24),
                                _mm256_slli_epi32(band(_mm256_cmpgt_epi32(t.ty1, t.ty0), set1(1)), 25))));
    base += r.tile_count;
  }
  return base - base0;
}

void sample_reach_buckets(const uint32_t count[8], int32_t bucket[8]) {
  const V c = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(count));
  _mm256_storeu_si256(reinterpret_cast<__m256i*>(bucket), sample_reach_bucket8(c));
}

#define STIPPLE_SET_UP_NODES(N, S) \
  template uint32_t set_up_nodes<PointNormals::N, S>(const NodeLaneFrame&, uint32_t, uint32_t, TileNodes&, uint32_t, NodeLaneBatch*);
STIPPLE_SET_UP_NODES(kNode, false)
STIPPLE_SET_UP_NODES(kNode, true)
STIPPLE_SET_UP_NODES(kSampled, false)
STIPPLE_SET_UP_NODES(kSampled, true)
STIPPLE_SET_UP_NODES(kSurface, false)
STIPPLE_SET_UP_NODES(kSurface, true)
#undef STIPPLE_SET_UP_NODES

}  // namespace avx2
}  // namespace stipple

#endif
