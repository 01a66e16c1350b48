// stipple raster — per-frame Euler tables. See node_setup.h.
#include "raster/node_setup.h"

#include "core/arena.h"
#include "core/fixed_range.h"

namespace stipple {

size_t frame_angles_bytes(int max_angle_bits) {
  const size_t n = size_t{1} << max_angle_bits;
  return align8(2 * n * sizeof(CameraPhi)) + align8(n * sizeof(LightPhi));
}

void FrameAngles::init(void* storage, int max_angle_bits) {
  const size_t n = size_t{1} << max_angle_bits;
  uint8_t* at = static_cast<uint8_t*>(storage);
  position_ = reinterpret_cast<CameraPhi*>(at);
  normal_ = position_ + n;
  light_ = reinterpret_cast<LightPhi*>(at + align8(2 * n * sizeof(CameraPhi)));
  max_bits_ = max_angle_bits;
}

bool FrameAngles::build(const Camera& camera, const NodeDecoder& decoder, const int16_t light_q14[3],
                        const int16_t half_q14[3]) {
  const EulerTables& p = decoder.euler(FrameField::kPosition);
  const EulerTables& n = decoder.euler(FrameField::kNormal);
  if (p.phi_bits > max_bits_ || n.phi_bits > max_bits_) return false;
  const auto& r = camera.rotation;
  for (int i = 0; i < 3; ++i) column2_[i] = static_cast<int16_t>(r[i][2]);
  // T(phi) = R Rz(phi): column 0 = cos R_0 + sin R_1, column 1 = cos R_1 - sin R_0.
  const auto table = [&](const EulerTables& e, CameraPhi* out) {
    for (uint32_t q = 0; q < (1u << e.phi_bits); ++q) {
      const int32_t c = e.phi[q].cos, s = e.phi[q].sin;
      for (int i = 0; i < 3; ++i) {
        out[q].t0[i] = static_cast<int16_t>(rot_q14(c, r[i][0], s, r[i][1]));
        out[q].t1[i] = static_cast<int16_t>(rot_q14(c, r[i][1], -s, r[i][0]));
      }
    }
  };
  table(p, position_);
  if (n.phi != nullptr) {
    table(n, normal_);
    // Rz(phi)^T v = (cos v_x + sin v_y, cos v_y - sin v_x).
    for (uint32_t q = 0; q < (1u << n.phi_bits); ++q) {
      const int32_t c = n.phi[q].cos, s = n.phi[q].sin;
      light_[q].l[0] = static_cast<int16_t>(rot_q14(c, light_q14[0], s, light_q14[1]));
      light_[q].l[1] = static_cast<int16_t>(rot_q14(c, light_q14[1], -s, light_q14[0]));
      light_[q].h[0] = static_cast<int16_t>(rot_q14(c, half_q14[0], s, half_q14[1]));
      light_[q].h[1] = static_cast<int16_t>(rot_q14(c, half_q14[1], -s, half_q14[0]));
    }
    light_z_ = light_q14[2];
    half_z_ = half_q14[2];
  }
  return true;
}

// The same with R = I: T(phi) = Rz(phi), t0 = (cos, sin, 0), t1 = (-sin, cos, 0), t2 = z.
void FrameAngles::model_frame(const EulerTables& e, const NodeFields& f, Field theta, int16_t axis[3][3]) {
  const int t = static_cast<int>(theta);
  const uint32_t q_phi = f.v[t + 1];
  const SinCosQ14 th = e.theta[f.v[t]], ph = e.phi[q_phi], ga = e.gamma[e.gamma_index(q_phi, f.v[t + 2])];
  const CameraPhi tp{{ph.cos, ph.sin, 0}, {static_cast<int16_t>(-ph.sin), ph.cos, 0}, {0, 0}};
  const int16_t t2[3] = {0, 0, kQ14One};
  turn(th, ga, tp, t2, axis);
}

}  // namespace stipple
