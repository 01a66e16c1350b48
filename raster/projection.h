// stipple raster — projecting a node's Gaussian samples to the screen.
//
// Per node and frame, `NodeProjection::setup` takes the decoded node to
// camera space — the mean (X, Y, Z) and the sigma-scaled axes A (MU per
// sigma) — and linearizes the projection at the mean:
//   x0 = cx + f X / Z,  M = f / Z (A_xy - (X, Y)/Z A_z)  (1/256 px per sigma),
// with one division (u = 2^46 / Z). Per point, sample g (Q12) lands at
//   kAffine      x = x0 + M g / 2^16                        no division
//   kReciprocal  x = cx + f X_p r / 2^(e+16), 1/Z_p ~ r 2^-(e+16) from a
//                1024-entry table indexed by the 10 bits below Z_p's top bit
//   kExact       x = cx + floor(f X_p / Z_p)                two divisions
//                (floor_div: without a divide instruction when the build
//                has STIPPLE_HW_DIVIDE off, core/divide.h)
// with X_p = X + (A g)_x / 2^12 (likewise Y_p, Z_p). Every position is
// floored to 1/16 px. Ranges (camera.h): |X|, |Y| <= 8 Z, Z <= 2^30, the
// near plane >= 2^12 MU, so u < 2^35, |X/Z| < 2^19 in Q16, and every product
// below stays under 2^63; setup refuses nodes whose |M| reaches 2^28 (a node
// millions of pixels wide, which the cut must refine). Measured errors of
// each mode are in docs/fixed_point.md (tests/portable/projection_test.cpp).
#pragma once

#include <cstdint>

#include "core/camera.h"
#include "core/divide.h"
#include "core/fixed_range.h"
#include "core/gaussian_table.h"
#include "core/node_decoder.h"

namespace stipple {

enum class Projection : uint8_t { kAffine, kReciprocal, kExact };

inline constexpr int kReciprocalBits = 10;
inline constexpr int64_t kMaxScreenSlope = int64_t{1} << 28;  // 1/256 px per sigma

// Entry i = 2^26 / (1024 + i + 1/2), rounded: 1024 entries in (2^15, 2^16).
void build_reciprocal_table(uint16_t out[1 << kReciprocalBits]);

inline int64_t abs64(int64_t v) { return v < 0 ? -v : v; }
// Whether a screen slope is out of range, |v| >= kMaxScreenSlope, for |v|
// below 2^62: v + 2^28 - 1 outside [0, 2^29 - 2] — one unsigned compare,
// where two 64-bit absolute values cost ARMv5 ~15 instructions a node.
inline bool slope_beyond(int64_t v) {
  return static_cast<uint64_t>(v + (kMaxScreenSlope - 1)) > static_cast<uint64_t>(2 * kMaxScreenSlope - 2);
}


struct ScreenSample {
  int32_t x_q4, y_q4;
  int64_t z;  // MU
};

// Its fields are setup's to write and are read only after setup returned
// true: no default values, which every node's set-up would clear first (on
// ARMv5 a call to memset a node).
struct NodeProjection {
  int64_t X, Y, Z;                // mean, camera space, MU
  int32_t A[3][3];                // A[k]: axis k in camera space, MU per sigma
  int32_t x0_q4, y0_q4;           // the mean on screen
  int32_t mx[3], my[3];           // 1/256 px per sigma
  int32_t focal_q4, cx_q4, cy_q4;

  // False when the node is not drawn: its mean behind the near plane or
  // outside a ~165 degree cone, or its projection too large.
  bool setup(const Camera& camera, const FixedNode& node) {
    int32_t c[3], a[3][3];
    camera_space(camera, node.mean, c);
    if (!in_view(camera, c)) return false;
    for (int k = 0; k < 3; ++k) camera_rotate(camera, node.axis[k], a[k]);
    return setup(camera, c, a);
  }
  // Whether a camera-space mean is drawn at all: beyond the near plane, inside the cone.
  static bool in_view(const Camera& camera, const int32_t c[3]) {
    const int64_t z = c[2];
    return z > camera.near_mu && abs64(c[0]) <= 8 * z && abs64(c[1]) <= 8 * z;
  }
  // The same from the mean and the axes in camera space (MU; the mean
  // in_view, every axis component within 2^25 + 2^11: sigma <= 2^25).
  // kKeep false leaves X, Y, Z and A unset — only the exact and reciprocal
  // projections' point() reads them — which spares the affine set-up
  // storing twelve words a node (ARMv5: ~45 instructions).
  template <bool kKeep = true>
  bool setup(const Camera& camera, const int32_t c[3], const int32_t a[3][3]) {
    if constexpr (kKeep) {
      X = c[0];
      Y = c[1];
      Z = c[2];
      for (int k = 0; k < 3; ++k)
        for (int i = 0; i < 3; ++i) A[k][i] = a[k][i];
    }
    focal_q4 = camera.focal_q4;
    cx_q4 = camera.center_q4[0];
    cy_q4 = camera.center_q4[1];
    // u = 2^46 / Z < 2^34, floored — without a divide instruction where
    // the build has none (core/divide.h: the same quotient).
    const int64_t u = floor_div(int64_t{1} << 46, c[2]);
    // Z > 2^15 (every node but the nearest): u < 2^31 and f / Z below
    // 2^31, so each product below is one 32 x 32-bit multiply into 64
    // (ARMv5's SMULL) — the same values as in int64.
    if (u < (int64_t{1} << 31)) return slopes(c, a, static_cast<int32_t>(u));
    return slopes(c, a, u);
  }

 private:
  // The rest of setup, from u = 2^46 / Z (int32_t or int64_t).
  template <class U>
  bool slopes(const int32_t c[3], const int32_t a[3][3], U u) {
    // X/Z, Y/Z in Q16: below 2^19 (|X|, |Y| <= 8 Z).
    const int32_t xr = static_cast<int32_t>((int64_t{c[0]} * u) >> 30), yr = static_cast<int32_t>((int64_t{c[1]} * u) >> 30);
    x0_q4 = cx_q4 + narrow<int32_t>((int64_t{focal_q4} * xr) >> 16);
    y0_q4 = cy_q4 + narrow<int32_t>((int64_t{focal_q4} * yr) >> 16);
    const U fu = static_cast<U>((int64_t{focal_q4} * u) >> 20);  // f / Z in Q26 (Q4 focal): below 2^34 (2^31 for an int32 u)
    for (int k = 0; k < 3; ++k) {
      // (A - (X/Z) A_z): below 2^25 * 9 = 2^28.2 for |A| <= 2^25 + 2^11;
      // times f / Z below 2^62.2; 256 f / Z (A - (X/Z) A_z) after the shift.
      const int32_t dx = a[k][0] - static_cast<int32_t>((int64_t{xr} * a[k][2]) >> 16);
      const int32_t dy = a[k][1] - static_cast<int32_t>((int64_t{yr} * a[k][2]) >> 16);
      const int64_t vx = (int64_t{dx} * fu) >> 22, vy = (int64_t{dy} * fu) >> 22;
      if (slope_beyond(vx) || slope_beyond(vy)) return false;
      mx[k] = static_cast<int32_t>(vx);
      my[k] = static_cast<int32_t>(vy);
    }
    return true;
  }

 public:
  // Sample g on the screen. False when the point is behind the near plane
  // or (per-point modes) outside the ~165 degree cone.
  template <Projection P>
  bool point(const Gaussian3Q12& g, int32_t near_mu, const uint16_t* reciprocal, ScreenSample* out) const {
    const int64_t g0 = g.v[0], g1 = g.v[1], g2 = g.v[2];
    const int64_t z = Z + ((A[0][2] * g0 + A[1][2] * g1 + A[2][2] * g2) >> 12);
    if (z < near_mu) return false;
    out->z = z;
    if constexpr (P == Projection::kAffine) {
      out->x_q4 = x0_q4 + narrow<int32_t>((mx[0] * g0 + mx[1] * g1 + mx[2] * g2) >> 16);
      out->y_q4 = y0_q4 + narrow<int32_t>((my[0] * g0 + my[1] * g1 + my[2] * g2) >> 16);
      return true;
    } else {
      const int64_t xp = X + ((A[0][0] * g0 + A[1][0] * g1 + A[2][0] * g2) >> 12);
      const int64_t yp = Y + ((A[0][1] * g0 + A[1][1] * g1 + A[2][1] * g2) >> 12);
      if (abs64(xp) > 8 * z || abs64(yp) > 8 * z) return false;
      if constexpr (P == Projection::kExact) {
        out->x_q4 = cx_q4 + static_cast<int32_t>(floor_div(focal_q4 * xp, z));
        out->y_q4 = cy_q4 + static_cast<int32_t>(floor_div(focal_q4 * yp, z));
      } else {
        // z = (1024 + i + frac) 2^(e-10) with e >= 12 (z >= near >= 2^12).
        const int e = 63 - __builtin_clzll(static_cast<uint64_t>(z));
        const int64_t r = reciprocal[(z >> (e - kReciprocalBits)) & ((1 << kReciprocalBits) - 1)];
        out->x_q4 = cx_q4 + narrow<int32_t>((((xp * r) >> 16) * focal_q4) >> e);
        out->y_q4 = cy_q4 + narrow<int32_t>((((yp * r) >> 16) * focal_q4) >> e);
      }
      return true;
    }
  }
};

}  // namespace stipple
