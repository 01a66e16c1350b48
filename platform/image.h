// stipple platform — the one picture type of the host side and the
// programs: 8-bit RGB, rows top to bottom, 3 bytes a pixel, no padding. PNG
// (png_io.h, host only) and PPM files read and write it; frames in the
// client's native pixel formats convert to it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "raster/point_raster.h"

namespace stipple {

struct Image {
  int width = 0, height = 0;
  std::vector<uint8_t> rgb;  // width x height x 3
};

// A native frame (`height` rows of `stride` bytes in `format`) as RGB888 in
// `out`, whose storage is reused when it is large enough (no allocation for
// a second frame of the same size). RGB565 expands by bit replication,
// which keeps every bit of the frame.
void image_from_frame(const uint8_t* frame, size_t stride, int width, int height, PixelFormat format, Image& out);

// The pixel at (x, y) as 0xRRGGBB.
inline uint32_t pixel_at(const Image& image, int x, int y) {
  const uint8_t* p = &image.rgb[(static_cast<size_t>(y) * static_cast<size_t>(image.width) + static_cast<size_t>(x)) * 3];
  return (uint32_t{p[0]} << 16) | (uint32_t{p[1]} << 8) | p[2];
}

// PSNR over all channels; +inf when equal, 0 when the sizes differ.
double image_psnr(const Image& a, const Image& b);

// Binary PPM (P6, maxval 255), written atomically; error names the path.
bool write_ppm(const std::string& path, const Image& image, std::string& error);

}  // namespace stipple
