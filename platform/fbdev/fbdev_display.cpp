// stipple platform — the Linux framebuffer display. See fbdev_display.h.
#include "platform/fbdev/fbdev_display.h"

#include <fcntl.h>
#include <linux/fb.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace stipple {

FbdevDisplay::~FbdevDisplay() {
  if (map_ != nullptr) munmap(map_, map_bytes_);
  if (fd_ >= 0) ::close(fd_);
}

bool FbdevDisplay::open(const std::string& device, std::string& error) {
  fd_ = ::open(device.c_str(), O_RDWR);
  if (fd_ < 0) return error = device + ": " + std::strerror(errno), false;
  fb_var_screeninfo var{};
  fb_fix_screeninfo fix{};
  if (ioctl(fd_, FBIOGET_VSCREENINFO, &var) != 0 || ioctl(fd_, FBIOGET_FSCREENINFO, &fix) != 0)
    return error = device + ": not a framebuffer (" + std::strerror(errno) + ")", false;
  if (var.bits_per_pixel != 16 && var.bits_per_pixel != 24 && var.bits_per_pixel != 32)
    return error = device + ": " + std::to_string(var.bits_per_pixel) + " bits per pixel is not supported (16, 24, 32)", false;
  width_ = static_cast<uint16_t>(var.xres < 4096 ? var.xres : 4096);
  height_ = static_cast<uint16_t>(var.yres < 4096 ? var.yres : 4096);
  bytes_per_pixel_ = static_cast<int>(var.bits_per_pixel / 8);
  stride_ = fix.line_length;
  const fb_bitfield fields[3] = {var.red, var.green, var.blue};
  for (int c = 0; c < 3; ++c) {
    shift_[c] = static_cast<int>(fields[c].offset);
    length_[c] = static_cast<int>(fields[c].length);
  }
  format_ = bytes_per_pixel_ == 2 && shift_[0] == 11 && length_[0] == 5 && shift_[1] == 5 && length_[1] == 6 &&
                    shift_[2] == 0 && length_[2] == 5
                ? PixelFormat::kRgb565
                : PixelFormat::kRgb888;
  map_bytes_ = stride_ * var.yres_virtual;
  void* map = mmap(nullptr, map_bytes_, PROT_READ | PROT_WRITE, MAP_SHARED, fd_, 0);
  if (map == MAP_FAILED) return error = device + ": mmap: " + std::strerror(errno), false;
  map_ = static_cast<uint8_t*>(map);
  return true;
}

bool FbdevDisplay::present(const uint8_t* frame, size_t stride, uint16_t width, uint16_t height, PixelFormat format,
                           std::string& error) {
  if (map_ == nullptr) return error = "framebuffer: not open", false;
  const int w = width < width_ ? width : width_, h = height < height_ ? height : height_;
  for (int y = 0; y < h; ++y) {
    const uint8_t* src = frame + static_cast<size_t>(y) * stride;
    uint8_t* row = map_ + static_cast<size_t>(y) * stride_;
    if (format == format_ && format == PixelFormat::kRgb565) {  // the device's own layout
      std::memcpy(row, src, static_cast<size_t>(w) * 2);
      continue;
    }
    for (int x = 0; x < w; ++x) {
      uint32_t rgb;
      if (format == PixelFormat::kRgb565) rgb = rgb888_from_565(static_cast<uint16_t>(src[2 * x] | (src[2 * x + 1] << 8)));
      else rgb = (uint32_t{src[3 * x]} << 16) | (uint32_t{src[3 * x + 1]} << 8) | src[3 * x + 2];
      const uint8_t c[3] = {static_cast<uint8_t>(rgb >> 16), static_cast<uint8_t>(rgb >> 8), static_cast<uint8_t>(rgb)};
      uint32_t v = 0;
      for (int k = 0; k < 3; ++k) v |= static_cast<uint32_t>(c[k] >> (8 - length_[k])) << shift_[k];
      for (int b = 0; b < bytes_per_pixel_; ++b) row[x * bytes_per_pixel_ + b] = static_cast<uint8_t>(v >> (8 * b));
    }
  }
  return true;
}

}  // namespace stipple
