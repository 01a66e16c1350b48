// stipple raster — a node's record straight to what its points need, per frame.
//
// The client never decodes a record into model space. A frame field is
// F = Rz(phi) Ry(theta) Rz(gamma) in Euler form (core/node_decoder.h), so
// with the camera's rotation R
//   R F = T(phi) Ry(theta) Rz(gamma),  T(phi) = R Rz(phi),
// where T is one table a frame (`FrameAngles`, one entry per value of the
// phi field: 1,024 for the paper's layout) and the two plane rotations
// are per node: 24 products of Q14 values, each below 2^29, for the three
// axes in camera space. The normal frame is only ever dotted with the light
// and half vectors, so it needs less: F^T L = Rz(gamma)^T Ry(theta)^T
// (Rz(phi)^T L), again a table a frame and 8 products a vector. Every sum
// below is of two Q14 x Q14 products (< 2^29 each): int32 throughout, on
// ARMv5 as on x86-64 (docs/fixed_point.md, "The per-node set-up").
//
// The set-up (PointRenderer::draw_node; eight nodes at a time in
// raster/node_lanes.h) then projects (raster/projection.h), sizes the node in
// points (raster/points_per_node.h) and forms the per-point constants of
// the point formula (raster/point_kernel.h).
#pragma once

#include <cstddef>
#include <cstdint>

#include "core/camera.h"
#include "core/node_decoder.h"
#include "raster/projection.h"
#include "raster/shading.h"

namespace stipple {

// T(phi) = R Rz(phi): columns 0 and 1 (column 2 is R's own), Q14, rows x, y, z.
struct CameraPhi {
  int16_t t0[3], t1[3];
  int16_t pad[2];
};
// Rz(phi)^T L and Rz(phi)^T H, x and y (z is L's and H's own), Q14.
struct LightPhi {
  int16_t l[2], h[2];
};

// Bytes of a frame's tables for angle fields up to `max_angle_bits` wide.
size_t frame_angles_bytes(int max_angle_bits);

// One frame's tables, in storage of frame_angles_bytes(max_angle_bits).
class FrameAngles {
 public:
  void init(void* storage, int max_angle_bits);
  // False (nothing built) when a phi field is wider than max_angle_bits.
  // `light_q14`, `half_q14`: model space.
  [[nodiscard]] bool build(const Camera& camera, const NodeDecoder& decoder, const int16_t light_q14[3],
                           const int16_t half_q14[3]);

  // The three axes of the position frame in camera space (Q14): axis[k][c].
  void position_frame(const EulerTables& e, const NodeFields& f, int16_t axis[3][3]) const {
    const uint32_t q_phi = f[Field::kFpPhi];
    turn(e.theta[f[Field::kFpTheta]], e.gamma[e.gamma_index(q_phi, f[Field::kFpPsi])], position_[q_phi], column2_, axis);
  }
  // The first two axes of the normal frame in camera space (Q14).
  void normal_tangents(const EulerTables& e, const NodeFields& f, int16_t axis[2][3]) const {
    const uint32_t q_phi = f[Field::kFnPhi];
    turn<2>(e.theta[f[Field::kFnTheta]], e.gamma[e.gamma_index(q_phi, f[Field::kFnPsi])], normal_[q_phi], column2_, axis);
  }
  // The three axes of a frame in model space (Q14): no camera, so no table
  // (the colour frame's, which the camera does not turn).
  static void model_frame(const EulerTables& e, const NodeFields& f, Field theta, int16_t axis[3][3]);
  // L.f1, L.f2, L.f3 and H.f1, H.f2, H.f3 of the normal frame (Q14).
  //   F^T v = Rz(gamma)^T Ry(theta)^T (Rz(phi)^T v): with w = Rz(phi)^T v
  //   (the table) and u = cos(theta) w_x - sin(theta) v_z,
  //   v.f1 = cos(gamma) u + sin(gamma) w_y,  v.f2 = cos(gamma) w_y - sin(gamma) u,
  //   v.f3 = sin(theta) w_x + cos(theta) v_z.
  void light_terms(const EulerTables& e, const NodeFields& f, int32_t l[3], int32_t h[3]) const {
    const uint32_t q_phi = f[Field::kFnPhi];
    const SinCosQ14 th = e.theta[f[Field::kFnTheta]], ga = e.gamma[e.gamma_index(q_phi, f[Field::kFnPsi])];
    const LightPhi& w = light_[q_phi];
    const int32_t ul = rot_q14(th.cos, w.l[0], -th.sin, light_z_), uh = rot_q14(th.cos, w.h[0], -th.sin, half_z_);
    l[0] = rot_q14(ga.cos, ul, ga.sin, w.l[1]);
    l[1] = rot_q14(ga.cos, w.l[1], -ga.sin, ul);
    l[2] = rot_q14(th.sin, w.l[0], th.cos, light_z_);
    h[0] = rot_q14(ga.cos, uh, ga.sin, w.h[1]);
    h[1] = rot_q14(ga.cos, w.h[1], -ga.sin, uh);
    h[2] = rot_q14(th.sin, w.h[0], th.cos, half_z_);
  }

  // (a b + c d) / 2^14, rounded, for Q14 operands (|.| <= 2^14 + a few
  // LSB): each product is below 2^28.1, their sum below 2^29.1 — int32.
  static int32_t rot_q14(int32_t a, int32_t b, int32_t c, int32_t d) { return (a * b + c * d + (1 << 13)) >> 14; }
  // T Ry(theta) Rz(gamma): with u = cos(theta) t0 - sin(theta) t2,
  //   axis 0 = cos(gamma) u + sin(gamma) t1,  axis 1 = cos(gamma) t1 - sin(gamma) u,
  //   axis 2 = sin(theta) t0 + cos(theta) t2
  // — the first kAxes of them.
  template <int kAxes = 3>
  static void turn(SinCosQ14 th, SinCosQ14 ga, const CameraPhi& tp, const int16_t t2[3], int16_t axis[][3]) {
    for (int c = 0; c < 3; ++c) {
      const int32_t u = rot_q14(th.cos, tp.t0[c], -th.sin, t2[c]);
      axis[0][c] = static_cast<int16_t>(rot_q14(ga.cos, u, ga.sin, tp.t1[c]));
      axis[1][c] = static_cast<int16_t>(rot_q14(ga.cos, tp.t1[c], -ga.sin, u));
      if constexpr (kAxes == 3) axis[2][c] = static_cast<int16_t>(rot_q14(th.sin, tp.t0[c], th.cos, t2[c]));
    }
  }

  // The tables themselves (raster/node_lanes.h gathers from them).
  const CameraPhi* position_table() const { return position_; }
  const CameraPhi* normal_table() const { return normal_; }
  const LightPhi* light_table() const { return light_; }
  const int16_t* column2() const { return column2_; }
  int16_t light_z() const { return light_z_; }
  int16_t half_z() const { return half_z_; }

 private:
  CameraPhi* position_ = nullptr;  // over the position frame's phi
  CameraPhi* normal_ = nullptr;    // over the normal frame's phi (kSurface's tangents)
  LightPhi* light_ = nullptr;      // over the normal frame's phi
  int16_t column2_[3] = {};        // R's third column
  int16_t light_z_ = 0, half_z_ = 0;
  int max_bits_ = 0;
};

}  // namespace stipple
