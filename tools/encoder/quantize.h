// stipple host — double-precision quantizers and dequantizers of node fields
// (TOG05 §5). The fixed-point client decodes the same integers with tables.
//
// Frames (fp, fn, fc) are three angles. The third axis f3 is
//   f3 = (cos phi sin theta, sin phi sin theta, cos theta);
// x' and y' are the x and y axes rotated by theta about a = (-sin phi, cos phi, 0)
// (Rodrigues; a is z x f3 normalised, defined from phi even at the poles), and
//   f1 = cos psi x' + sin psi y',  f2 = cos psi y' - sin psi x'.
// Levels (b = the field's bits):
//   theta = q * range / (2^b - 1), range pi (full sphere) or pi/2 (hemisphere),
//           so the poles are exact;
//   phi   = q * 2 pi / 2^b (wraps at the seam);
//   psi   = q * pi / 2^b (f1's sign is free: a Gaussian is symmetric).
// The encoder quantizes theta and phi, then picks the psi that best matches
// f1 in the decoded (x', y') plane, so the error does not compound.
#pragma once

#include <cstdint>

#include "core/node_format.h"
#include "tools/encoder/node_stats.h"

namespace stipple {

struct AngleBits {
  int theta = 8, phi = 10, psi = 6;
  bool hemisphere = false;  // f3's sign is free too (colour frames)
};

struct FrameCode {
  uint16_t theta = 0, phi = 0, psi = 0;
};

// The angle widths of the frame whose theta field is `theta_field` (kFpTheta,
// kFnTheta or kFcTheta; phi and psi follow it). Colour frames are hemispheric.
AngleBits frame_bits(const RecordLayout& layout, Field theta_field, bool hemisphere);

FrameCode encode_frame(const Mat3& frame, const AngleBits& bits);
Mat3 decode_frame(const FrameCode& code, const AngleBits& bits);

// Uniform scalar quantizer on [lo, hi] with 2^bits cells; decodes to the cell centre.
uint16_t quantize_cell(double v, double lo, double hi, int bits);
double dequantize_cell(uint16_t q, double lo, double hi, int bits);

// Colour channel in [0, 1] with 2^bits levels including 0 and 1.
uint16_t quantize_unit(double v, int bits);
double dequantize_unit(uint16_t q, int bits);

// Version 2's class table codes (docs/format.md §2, core/spg_format.h).
// sigma_p: a 16-bit float relative to `largest_extent` (the stored box's
// largest side), rounded to the nearest code (12 significant bits, so within
// 2^-12 of the value; at most about 2 x the extent, saturated above).
uint16_t sigma_p_code(double sigma, double largest_extent);
double sigma_p_of_code(uint16_t code, double largest_extent);
// sigma_n (radians) and sigma_c (0..1): Q12, the value the client's integer
// conversion of the float32 gives (round half away from zero), saturated.
uint16_t q12_code(double value);
// The same of either sign as two's complement (kAttrCurvatureSign's sigma_n),
// within +-32767.
uint16_t q12_signed_code(double value);

}  // namespace stipple
