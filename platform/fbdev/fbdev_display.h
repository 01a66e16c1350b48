// stipple platform — the Linux framebuffer display (/dev/fb0: 16, 24 or 32
// bits per pixel, any channel layout the driver reports). The handheld's
// screen. It has no input of its own (poll() reports none; a device's keys
// come through evdev, not here).
#pragma once

#include <cstdint>
#include <string>

#include "platform/display.h"

namespace stipple {

class FbdevDisplay final : public Display {
 public:
  FbdevDisplay() = default;
  ~FbdevDisplay() override;
  FbdevDisplay(const FbdevDisplay&) = delete;
  FbdevDisplay& operator=(const FbdevDisplay&) = delete;

  // Opens and maps the device; error names it and what failed (a file that
  // is not a framebuffer, an unsupported depth).
  [[nodiscard]] bool open(const std::string& device, std::string& error);

  uint16_t width() const override { return width_; }
  uint16_t height() const override { return height_; }
  // RGB565 when the device is 16-bit 5-6-5 (frames are then copied as they
  // are), else RGB888.
  PixelFormat format() const override { return format_; }
  bool present(const uint8_t* frame, size_t stride, uint16_t width, uint16_t height, PixelFormat format,
               std::string& error) override;
  bool poll(InputEvent*) override { return false; }

 private:
  int fd_ = -1;
  uint8_t* map_ = nullptr;
  size_t map_bytes_ = 0, stride_ = 0;
  uint16_t width_ = 0, height_ = 0;
  int bytes_per_pixel_ = 0;
  PixelFormat format_ = PixelFormat::kRgb888;
  int shift_[3] = {}, length_[3] = {};  // red, green, blue bit fields
};

}  // namespace stipple
