// stipple host — the double-precision reference renderer the fixed-point
// client (tools/embedded/embedded.h) is measured against.
#pragma once

#include <cstdint>
#include <vector>

#include "tools/embedded/embedded.h"
#include "tools/reference/spg_model.h"

namespace stipple {

// The same frame in double precision: the same cut, the same samples (Sobol
// through libm) and points-per-node table, exact perspective per point,
// exact exponential-map normals and libm shading, a double z-buffer with the
// same point squares. RGB565 formats are quantized the same way at the end.
Image render_reference(const DecodedModel& model, const std::vector<uint32_t>& cut, const ClientConfig& config,
                       const ViewSpec& spec);

}  // namespace stipple
