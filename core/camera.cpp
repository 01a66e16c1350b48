// stipple core — fixed-point camera. See camera.h.
#include "core/camera.h"

#include "core/fixed_trig.h"

namespace stipple {
namespace {

int32_t dot_q14(const int32_t row[3], const int64_t v[3]) {
  const int64_t s = row[0] * v[0] + row[1] * v[1] + row[2] * v[2];
  return static_cast<int32_t>((s + (1 << 13)) >> 14);
}

}  // namespace

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
  Camera c;
  for (int a = 0; a < 3; ++a) {
    c.rotation[0][a] = r[a];
    c.rotation[1][a] = -u[a];
    c.rotation[2][a] = -b[a];
    c.eye[a] = view.target_mu[a] +
               static_cast<int32_t>((static_cast<int64_t>(view.distance_mu) * b[a] + (1 << 13)) >> 14);
  }
  // f = (height / 2) / tan(fov / 2), in Q4: 8 h cos / sin. One division per camera.
  const SinCosQ14 half = sincos_q14(view.fov / 2);
  c.focal_q4 = static_cast<int32_t>((int64_t{8} * height * half.cos + half.sin / 2) / half.sin);
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
