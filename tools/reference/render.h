// stipple host — the double-precision reference renderer the fixed-point
// client (tools/embedded/embedded.h) is measured against.
#pragma once

#include <cstdint>
#include <vector>

#include "tools/embedded/embedded.h"
#include "tools/reference/spg_model.h"

namespace stipple {

// The client's orbit camera and lighting in doubles, for a model whose
// bounding box is [bbox_min, bbox_max] (scan units): model units, rows of R
// right, down, forward; the light and half vector in the model.
struct ReferenceCamera {
  Mat3 R;
  Vec3 eye, bbox_min, light, half;
  double to_mu = 1, focal = 1, cx = 0, cy = 0, near = 1, ambient = 0.25, strength = 0.25;
  Vec3 camera_space(const Vec3& scan_point) const { return R * ((scan_point - bbox_min) * to_mu - eye); }
};
ReferenceCamera reference_camera(const Vec3& bbox_min, const Vec3& bbox_max, const SpgHeader& header,
                                 const ClientConfig& config, const ViewSpec& spec);

// A colour buffer (0xRRGGBB per pixel) as the client's image: RGB565
// formats quantized as the client quantizes.
Image image_of(const std::vector<uint32_t>& color_buf, const ClientConfig& config);

// The same frame in double precision: the same cut, the same samples (Sobol
// through libm) and points-per-node table, exact perspective per point,
// exact exponential-map normals and libm shading, a double z-buffer with the
// same point squares. RGB565 formats are quantized the same way at the end.
Image render_reference(const DecodedModel& model, const std::vector<uint32_t>& cut, const ClientConfig& config,
                       const ViewSpec& spec);

}  // namespace stipple
