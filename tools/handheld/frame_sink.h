// stipple — where the handheld program's frames go: a PPM file (the
// headless backend: binary P6, no library needed to write or read it) or a
// Linux framebuffer device (/dev/fb0: 16, 24 or 32 bits per pixel, any
// channel layout the driver reports).
#pragma once

#include <cstdint>
#include <string>

#include "tools/handheld/embedded.h"

namespace stipple {

// Writes `image` as binary PPM (P6, maxval 255), atomically.
bool write_ppm(const std::string& path, const Image& image, std::string& error);

class Framebuffer {
 public:
  Framebuffer() = default;
  ~Framebuffer();
  Framebuffer(const Framebuffer&) = delete;
  Framebuffer& operator=(const Framebuffer&) = delete;

  // Opens and maps the device; error names it and what failed.
  bool open(const std::string& device, std::string& error);
  // Copies the image to the top-left corner (cropped to the screen).
  void show(const Image& image);
  int width() const { return width_; }
  int height() const { return height_; }

 private:
  int fd_ = -1;
  uint8_t* map_ = nullptr;
  size_t map_bytes_ = 0, stride_ = 0;
  int width_ = 0, height_ = 0, bytes_per_pixel_ = 0;
  int shift_[3] = {}, length_[3] = {};  // red, green, blue bit fields
};

}  // namespace stipple
