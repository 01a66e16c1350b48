// stipple host — a picture against its reference (`stipple truth`): what
// `stipple image-diff` reports beyond the bytes. Background is the pixels
// of the background colour (black unless said); the object is the pixels
// either image covers.
//   object PSNR       over the object's pixels, all three channels
//   SSIM              mean structural similarity of the luma (Wang et al.
//                     2004: 8x8 windows every 4 px, C1 = (0.01 L)^2,
//                     C2 = (0.03 L)^2) over windows that hold object pixels
//   dark where lit    of the pixels both cover where the reference is lit
//                     (luma >= 64), the share the picture shows at under
//                     half the reference's luma: back surfaces seen through
//                     gaps, normals turned away
//   outside           of the pixels the picture covers, the share the
//                     reference does not: bloated silhouettes
//   missing           of the pixels the reference covers, the share the
//                     picture does not: holes
#pragma once

#include <cstdint>

#include "platform/image.h"

namespace stipple {

struct ImageComparison {
  long object_pixels = 0;
  double object_psnr = 0;  // dB; +inf when equal over the object
  double ssim = 1;
  double dark_where_lit = 0, outside = 0, missing = 0;  // fractions
};

// `reference` and `picture` of the same size (else all zero).
ImageComparison compare_images(const Image& reference, const Image& picture, uint32_t background = 0);

}  // namespace stipple
