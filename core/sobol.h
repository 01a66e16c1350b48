// stipple core — Sobol low-discrepancy sequence, integer only.
//
// Direction numbers are the first dimensions of Joe & Kuo's file
// `new-joe-kuo-6.21201` (S. Joe and F. Y. Kuo, "Constructing Sobol sequences
// with better two-dimensional projections", SIAM J. Sci. Comput. 30, 2008).
// Dimension 0 is the van der Corput sequence. Points are 32-bit fixed-point
// fractions in [0, 1): value / 2^32. `sobol_point` computes point `index`
// directly (one XOR per set bit of the Gray code of `index`); no state, no heap.
#pragma once

#include <cstdint>

namespace stipple {

inline constexpr int kSobolDimensions = 8;

// Component `dim` (0 .. kSobolDimensions-1) of Sobol point `index`, as a
// 0.32 fixed-point fraction. Point 0 is the origin in every dimension.
uint32_t sobol_u32(uint32_t index, int dim);

}  // namespace stipple
