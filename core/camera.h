// stipple core — a fixed-point pinhole camera in model units.
//
// World coordinates are the node decoder's model units (MU, node_decoder.h).
// Camera coordinates: X right, Y down, Z forward (depth), so screen
// x = cx + f X / Z and y = cy + f Y / Z with y growing downwards.
//
// Formats and ranges (docs/fixed_point.md, "Camera"):
//   rotation   Q14 rows right, down, forward; |entry| <= 2^14
//   eye        MU, |eye| <= 2^29 per axis
//   focal_q4   pixels in Q4, 1 .. 2^20
//   center_q4  pixels in Q4
//   near_mu    > 0: points nearer than this are not drawn
// A world point p with |p| <= 2^26 gives |p - eye| < 2^30 per axis; the
// rotated coordinates are sums of three products below 2^44, exact in int64,
// and fit int32 after the Q14 shift.
#pragma once

#include <cstdint>

#include "core/spg_format.h"

namespace stipple {

struct Camera {
  int32_t rotation[3][3] = {};  // Q14; rows: right, down, forward
  int32_t eye[3] = {};          // MU
  int32_t focal_q4 = 0;         // focal length, 1/16 px
  int32_t center_q4[2] = {};    // principal point, 1/16 px
  int32_t near_mu = 1;          // near plane, MU
  int32_t far_mu = 1;           // farthest depth the frame needs to order (depth precision)
};

// An orbit around a target: the eye sits at `distance_mu` from the target in
// the direction given by yaw (about the up axis) and pitch (up from the plane
// across it), looking at the target with `up` up. With up = +y (the default,
// and kNone): yaw 0 looks along -z, yaw 90 along -x. Another up axis turns
// that frame by the signed axis permutation orbit_basis gives: right-handed,
// so no picture is mirrored.
struct OrbitView {
  int32_t target_mu[3] = {};
  int32_t distance_mu = 1 << 25;
  uint32_t yaw = 0, pitch = 0;  // binary angles (2^32 per turn)
  uint32_t fov = 0x10000000u;   // vertical field of view, binary angle (22.5 degrees)
  SpgAxis up = SpgAxis::kPosY;
};

// The orbit's frame for an up axis: columns x', y' = up, z' (each a signed
// unit axis, z' the next axis after up's, x' = y' x z'). For +y it is the
// identity. basis[i][j] is row i (world axis), column j.
void orbit_basis(SpgAxis up, int32_t basis[3][3]);

inline constexpr int32_t kCameraMaxCoord = 1 << 26;     // |target|, |world point| per axis
inline constexpr int32_t kCameraMinDistance = 1 << 12;  // MU
inline constexpr int32_t kCameraMaxDistance = 1 << 28;  // MU

// Builds the camera for a `width` x `height` screen. Fails (returns false,
// `out` untouched) for a distance outside [2^12, 2^28] MU, a target beyond
// 2^26 MU, a field of view outside [1, 170] degrees or an empty screen.
// Integer only: the same camera on every platform.
[[nodiscard]] bool orbit_camera(const OrbitView& view, uint16_t width, uint16_t height, Camera* out);

// Camera coordinates (MU) of world point p (MU, |p| <= 2^26 per axis).
void camera_space(const Camera& camera, const int32_t p[3], int32_t out[3]);

// Camera-space image of a world direction or offset v (MU or Q14): R v >> 14, rounded.
void camera_rotate(const Camera& camera, const int32_t v[3], int32_t out[3]);

}  // namespace stipple
