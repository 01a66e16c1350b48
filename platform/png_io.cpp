// stipple platform — PNG read/write with libpng's simplified API (1.6).
#include "platform/png_io.h"

#include "platform/file_io.h"

#include <png.h>

#include <cstdio>
#include <filesystem>

namespace stipple {

bool write_png(const std::string& path, const Image& img, std::string& error) {
  const int width = img.width, height = img.height;
  const std::vector<uint8_t>& rgb = img.rgb;
  if (width <= 0 || height <= 0 || rgb.size() != static_cast<size_t>(width) * static_cast<size_t>(height) * 3) {
    error = path + ": image size does not match its pixels";
    return false;
  }
  png_image image{};
  image.version = PNG_IMAGE_VERSION;
  image.width = static_cast<png_uint_32>(width);
  image.height = static_cast<png_uint_32>(height);
  image.format = PNG_FORMAT_RGB;
  // Encoded in memory, then written as every output is: atomically, under
  // a temporary name of this process's own (platform/file_io.h).
  png_alloc_size_t bytes = 0;
  if (!png_image_write_to_memory(&image, nullptr, &bytes, 0, rgb.data(), width * 3, nullptr)) {
    error = path + ": " + image.message;
    return false;
  }
  std::vector<uint8_t> encoded(bytes);
  if (!png_image_write_to_memory(&image, encoded.data(), &bytes, 0, rgb.data(), width * 3, nullptr)) {
    error = path + ": " + image.message;
    return false;
  }
  encoded.resize(bytes);
  return write_file_atomic(path, encoded, error);
}

bool read_png(const std::string& path, Image& img, std::string& error) {
  int& width = img.width;
  int& height = img.height;
  std::vector<uint8_t>& rgb = img.rgb;
  png_image image{};
  image.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_file(&image, path.c_str())) {
    error = path + ": " + image.message;
    return false;
  }
  // Bound the allocation by the file and a sane maximum before taking it.
  const uint64_t pixels = uint64_t{image.width} * image.height;
  std::error_code ec;
  const uintmax_t file_bytes = std::filesystem::file_size(path, ec);
  const auto refuse = [&](const std::string& why) {
    error = path + ": the header claims " + std::to_string(image.width) + " x " + std::to_string(image.height) +
            " pixels, " + why;
    png_image_free(&image);
    return false;
  };
  if (!ec && pixels > png_pixels_bound(file_bytes))
    return refuse("more than its " + std::to_string(file_bytes) + " bytes can hold (a damaged or hostile file)");
  if (pixels > kPngMaxPixels)
    return refuse("more than the " + std::to_string(kPngMaxPixels) + " this reader takes");
  image.format = PNG_FORMAT_RGB;
  width = static_cast<int>(image.width);
  height = static_cast<int>(image.height);
  rgb.assign(PNG_IMAGE_SIZE(image), 0);
  if (!png_image_finish_read(&image, nullptr, rgb.data(), 0, nullptr)) {
    error = path + ": " + image.message;
    png_image_free(&image);
    return false;
  }
  return true;
}

}  // namespace stipple
