// stipple platform — PNG files through libpng.
//
// Images are 8-bit RGB, rows top to bottom, 3 bytes per pixel, no padding.
// Functions return false and set `error` to "<path>: <reason>" on failure;
// a failed write leaves no partial file (temporary file + rename).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace stipple {

bool write_png_rgb(const std::string& path, int width, int height, const std::vector<uint8_t>& rgb,
                   std::string& error);

bool read_png_rgb(const std::string& path, int& width, int& height, std::vector<uint8_t>& rgb, std::string& error);

}  // namespace stipple
