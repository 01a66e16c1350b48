// stipple platform — PNG files through libpng.
//
// Images are platform/image.h's: 8-bit RGB, rows top to bottom, no padding.
// Functions return false and set `error` to "<path>: <reason>" on failure;
// a failed write leaves no partial file (temporary file + rename).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "platform/image.h"

namespace stipple {

bool write_png(const std::string& path, const Image& image, std::string& error);

// Reads any PNG libpng reads, as RGB. Refused before any pixel memory is
// taken: an image over kPngMaxPixels, or one whose header claims more
// pixels than its file could hold (deflate expands at most 1032:1, and a
// pixel is at least one bit), so a small hostile file cannot make it
// allocate gigabytes.
bool read_png(const std::string& path, Image& image, std::string& error);

// The most pixels read_png takes: 2^27 (a 16384 x 8192 image; 384 MiB as RGB).
inline constexpr uint64_t kPngMaxPixels = uint64_t{1} << 27;
// The most pixels `file_bytes` of PNG can hold: 8 one-bit pixels a byte of
// inflated data, 1032 inflated bytes a byte of deflate stream.
inline constexpr uint64_t png_pixels_bound(uint64_t file_bytes) { return file_bytes * 1032 * 8; }

}  // namespace stipple
