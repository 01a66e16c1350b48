// stipple — frame sinks. See frame_sink.h.
#include "tools/handheld/frame_sink.h"

#include <fcntl.h>
#include <linux/fb.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <vector>

#include "platform/file_io.h"

namespace stipple {

bool write_ppm(const std::string& path, const Image& image, std::string& error) {
  const std::string header = "P6\n" + std::to_string(image.width) + " " + std::to_string(image.height) + "\n255\n";
  std::vector<uint8_t> bytes(header.begin(), header.end());
  bytes.insert(bytes.end(), image.rgb.begin(), image.rgb.end());
  return write_file_atomic(path, bytes, error);
}

Framebuffer::~Framebuffer() {
  if (map_ != nullptr) munmap(map_, map_bytes_);
  if (fd_ >= 0) close(fd_);
}

bool Framebuffer::open(const std::string& device, std::string& error) {
  fd_ = ::open(device.c_str(), O_RDWR);
  if (fd_ < 0) return error = device + ": " + std::strerror(errno), false;
  fb_var_screeninfo var{};
  fb_fix_screeninfo fix{};
  if (ioctl(fd_, FBIOGET_VSCREENINFO, &var) != 0 || ioctl(fd_, FBIOGET_FSCREENINFO, &fix) != 0)
    return error = device + ": not a framebuffer (" + std::strerror(errno) + ")", false;
  if (var.bits_per_pixel != 16 && var.bits_per_pixel != 24 && var.bits_per_pixel != 32)
    return error = device + ": " + std::to_string(var.bits_per_pixel) + " bits per pixel is not supported (16, 24, 32)", false;
  width_ = static_cast<int>(var.xres);
  height_ = static_cast<int>(var.yres);
  bytes_per_pixel_ = static_cast<int>(var.bits_per_pixel / 8);
  stride_ = fix.line_length;
  const fb_bitfield fields[3] = {var.red, var.green, var.blue};
  for (int c = 0; c < 3; ++c) {
    shift_[c] = static_cast<int>(fields[c].offset);
    length_[c] = static_cast<int>(fields[c].length);
  }
  map_bytes_ = stride_ * var.yres_virtual;
  void* map = mmap(nullptr, map_bytes_, PROT_READ | PROT_WRITE, MAP_SHARED, fd_, 0);
  if (map == MAP_FAILED) return error = device + ": mmap: " + std::strerror(errno), false;
  map_ = static_cast<uint8_t*>(map);
  return true;
}

void Framebuffer::show(const Image& image) {
  const int w = image.width < width_ ? image.width : width_, h = image.height < height_ ? image.height : height_;
  for (int y = 0; y < h; ++y) {
    uint8_t* row = map_ + static_cast<size_t>(y) * stride_;
    for (int x = 0; x < w; ++x) {
      const uint8_t* p = &image.rgb[(static_cast<size_t>(y) * image.width + x) * 3];
      uint32_t v = 0;
      for (int c = 0; c < 3; ++c) v |= static_cast<uint32_t>(p[c] >> (8 - length_[c])) << shift_[c];
      for (int b = 0; b < bytes_per_pixel_; ++b) row[x * bytes_per_pixel_ + b] = static_cast<uint8_t>(v >> (8 * b));
    }
  }
}

}  // namespace stipple
