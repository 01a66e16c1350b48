// stipple host — reference point generation from decoded nodes (TOG05 §6).
//
// Sample j of a node uses Sobol point j+1 (point 0 is the origin, which would
// put r0 = 0): dimensions 0-2 for the position, 3-4 for the normal, 5-7 for
// the colour. The paper's 3-D Box–Muller variant:
//   tau = sqrt(-2 ln r0), r0 in (0, 1];  r2 in [-1, 1];
//   (x, y, z) = tau (sqrt(1 - r2^2) cos 2 pi r1, sqrt(1 - r2^2) sin 2 pi r1, r2)
// has per-axis variance 2/3 (tau^2 has mean 2, spread over 3 axes). We scale
// tau by sqrt(3/2) so each axis has unit variance, then clip tau at
// gamma = 3.5 (the paper's extent of a node) before scaling by sigma, rotating
// by the frame and adding the mean. Normals: alpha = sigma_n1 tau cos 2 pi r1,
// beta = sigma_n2 tau sin 2 pi r1, wrapped back onto the sphere about fn's z
// (exponential map). Colours: as positions, clamped to [0, 1].
// See docs/sampling.md.
#pragma once

#include "tools/scan/point_cloud.h"
#include "tools/reference/spg_model.h"

namespace stipple {

inline constexpr double kGamma = 3.5;

// Sample `index` (>= 1: Sobol point index, i.e. sample j + 1) of the unit
// 3-D Gaussian from Sobol dimensions first_dim .. first_dim + 2, and of the
// unit 2-D Gaussian from dimensions 3-4, in doubles.
Vec3 reference_gaussian3(uint32_t index, int first_dim);
Vec2 reference_gaussian2(uint32_t index);

// Generates points for the nodes in `cut`: `per_node` points each, or, when
// `per_node` is 0, as many as each node held originals (the paper's PSNR
// experiment). Normals and colours are generated when the model has them.
PointCloud sample_cut(const DecodedModel& model, const std::vector<uint32_t>& cut, uint32_t per_node);

// How many points `sample_cut` would generate. A file's point counts are
// claims: check this against a limit before sampling an untrusted file.
uint64_t cut_sample_count(const DecodedModel& model, const std::vector<uint32_t>& cut, uint32_t per_node);

// Host memory one generated point takes: position, normal and colour in
// doubles (72 bytes) and its binary PLY record (27), rounded up.
inline constexpr uint64_t kBytesPerSample = 100;

// The default limit of the command-line tools: what a quarter of the host's
// memory holds (a file's point counts are only claims), within [2^20, 2^28];
// 2^24 when the memory is unknown.
inline uint64_t default_max_samples(uint64_t memory_bytes) {
  if (memory_bytes == 0) return uint64_t{1} << 24;
  const uint64_t n = memory_bytes / 4 / kBytesPerSample;
  return n < (uint64_t{1} << 20) ? uint64_t{1} << 20 : n > (uint64_t{1} << 28) ? uint64_t{1} << 28 : n;
}

}  // namespace stipple
