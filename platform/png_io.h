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

bool read_png(const std::string& path, Image& image, std::string& error);

}  // namespace stipple
