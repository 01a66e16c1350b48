// stipple core — fixed-point camera. See camera.h.
#include "core/camera.h"

#include "core/fixed_range.h"
#include "core/fixed_trig.h"

namespace stipple {
namespace {

int32_t dot_q14(const int32_t row[3], const int64_t v[3]) {
  const int64_t s = row[0] * v[0] + row[1] * v[1] + row[2] * v[2];
  return narrow<int32_t>((s + (1 << 13)) >> 14);
}

}  // namespace

void orbit_basis(SpgAxis up, int32_t basis[3][3]) {
  const int k = up == SpgAxis::kNone ? 1 : spg_axis_index(up);  // kNone: +y
  const int32_t sign = spg_axis_negative(up) ? -1 : 1;
  int32_t y[3] = {0, 0, 0}, z[3] = {0, 0, 0};
  y[k] = sign;
  z[(k + 1) % 3] = 1;
  const int32_t x[3] = {y[1] * z[2] - y[2] * z[1], y[2] * z[0] - y[0] * z[2], y[0] * z[1] - y[1] * z[0]};
  for (int i = 0; i < 3; ++i) {
    basis[i][0] = x[i];
    basis[i][1] = y[i];
    basis[i][2] = z[i];
  }
}

bool orbit_camera(const OrbitView& view, uint16_t width, uint16_t height, Camera* out) {
  constexpr uint32_t kDegree = 11930465u;  // 2^32 / 360
  if (width == 0 || height == 0) return false;
  if (view.distance_mu < kCameraMinDistance || view.distance_mu > kCameraMaxDistance) return false;
  for (int a = 0; a < 3; ++a)
    if (view.target_mu[a] < -kCameraMaxCoord || view.target_mu[a] > kCameraMaxCoord) return false;
  if (view.fov < kDegree || view.fov > 170 * kDegree) return false;

  const SinCosQ14 y = sincos_q14(view.yaw), p = sincos_q14(view.pitch);
  // back b: from the target to the eye; right r; up u = b x r.
  const int32_t b[3] = {mul_q14(y.sin, p.cos), p.sin, mul_q14(y.cos, p.cos)};
  const int32_t r[3] = {y.cos, 0, -y.sin};
  const int32_t u[3] = {-mul_q14(y.sin, p.sin), p.cos, -mul_q14(y.cos, p.sin)};
  // Into the world: w = B v, a signed permutation (exact).
  int32_t basis[3][3];
  orbit_basis(view.up, basis);
  int32_t bw[3], rw[3], uw[3];
  for (int i = 0; i < 3; ++i) {
    bw[i] = basis[i][0] * b[0] + basis[i][1] * b[1] + basis[i][2] * b[2];
    rw[i] = basis[i][0] * r[0] + basis[i][1] * r[1] + basis[i][2] * r[2];
    uw[i] = basis[i][0] * u[0] + basis[i][1] * u[1] + basis[i][2] * u[2];
  }
  Camera c;
  for (int a = 0; a < 3; ++a) {
    c.rotation[0][a] = rw[a];
    c.rotation[1][a] = -uw[a];
    c.rotation[2][a] = -bw[a];
    c.eye[a] = view.target_mu[a] +
               narrow<int32_t>((static_cast<int64_t>(view.distance_mu) * bw[a] + (1 << 13)) >> 14);
  }
  // f = (height / 2) / tan(fov / 2), in Q4: 8 h cos / sin. One division per camera.
  const SinCosQ14 half = sincos_q14(view.fov / 2);
  c.focal_q4 = narrow<int32_t>((int64_t{8} * height * half.cos + half.sin / 2) / half.sin);
  if (c.focal_q4 < 1) c.focal_q4 = 1;
  c.center_q4[0] = 8 * width;
  c.center_q4[1] = 8 * height;
  // Depth range: the model's box (2^24 MU on its largest side, diagonal
  // below 2^25) seen from the orbit distance.
  c.near_mu = view.distance_mu >> 6 > kCameraMinDistance ? view.distance_mu >> 6 : kCameraMinDistance;
  c.far_mu = view.distance_mu + (1 << 25);
  *out = c;
  return true;
}

void camera_space(const Camera& camera, const int32_t p[3], int32_t out[3]) {
  const int64_t d[3] = {int64_t{p[0]} - camera.eye[0], int64_t{p[1]} - camera.eye[1], int64_t{p[2]} - camera.eye[2]};
  for (int k = 0; k < 3; ++k) out[k] = dot_q14(camera.rotation[k], d);
}

void camera_rotate(const Camera& camera, const int32_t v[3], int32_t out[3]) {
  const int64_t d[3] = {v[0], v[1], v[2]};
  for (int k = 0; k < 3; ++k) out[k] = dot_q14(camera.rotation[k], d);
}

}  // namespace stipple
