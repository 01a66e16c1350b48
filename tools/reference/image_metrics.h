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
//   silhouette IoU    the pixels both cover over the pixels either covers.
//                     Object PSNR is over the union, so a picture that
//                     covers almost nothing (a view from behind, the
//                     camera inside the object) can score well on it: the
//                     IoU, and silhouette_verdict, say when the silhouettes
//                     disagree and the PSNR is not the measure to read
#pragma once

#include <cstdint>
#include <string>

#include "platform/image.h"

namespace stipple {

struct ImageComparison {
  long object_pixels = 0;
  double object_psnr = 0;  // dB; +inf when equal over the object
  double ssim = 1;
  double dark_where_lit = 0, outside = 0, missing = 0;  // fractions
  double iou = 1;                                         // silhouette intersection over union
};

// One line on which measure dominates: "silhouettes agree (IoU 0.97): the
// PSNR and SSIM measure the shading", or that they disagree and which way
// (the picture misses most of the reference, or covers where it is empty).
std::string silhouette_verdict(const ImageComparison& m);

// `reference` and `picture` of the same size (else all zero).
ImageComparison compare_images(const Image& reference, const Image& picture, uint32_t background = 0);

}  // namespace stipple
