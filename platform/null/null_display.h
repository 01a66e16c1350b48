// stipple platform — the null display: no screen. It keeps the last frame
// as an Image, counts frames, optionally writes each one to a PPM file, and
// replays input events a test or script queued. Its clock is simulated: it
// advances by `frame_us` with each present, so a scripted run is the same
// run every time. Every test that needs a screen uses it. The image and the
// file name are sized when it is made: present() allocates nothing.
#pragma once

#include <cstdint>
#include <string>

#include "platform/display.h"
#include "platform/image.h"

namespace stipple {

class NullDisplay final : public Display {
 public:
  // `path`: where present() writes each frame as PPM; empty: nowhere. One
  // printf conversion (%d, %05d, ...) in it takes the frame number.
  NullDisplay(uint16_t width, uint16_t height, PixelFormat format, std::string path = {}, uint32_t frame_us = 33333);

  uint16_t width() const override { return width_; }
  uint16_t height() const override { return height_; }
  PixelFormat format() const override { return format_; }
  bool present(const uint8_t* frame, size_t stride, uint16_t width, uint16_t height, PixelFormat format,
               std::string& error) override;
  bool poll(InputEvent* event) override;
  uint64_t now_us() const override { return uint64_t{frames_} * frame_us_; }

  // Queues an event for poll() (at most kMaxQueued pending; false when full).
  bool push_input(const InputEvent& event);
  static constexpr int kMaxQueued = 64;

  const Image& last_frame() const { return image_; }
  uint32_t frames() const { return frames_; }

 private:
  uint16_t width_, height_;
  PixelFormat format_;
  std::string path_;
  Image image_;
  char name_[4096] = {}, temp_[4096 + 8] = {};
  uint32_t frames_ = 0;
  uint32_t frame_us_;
  InputEvent queue_[kMaxQueued];
  int head_ = 0, count_ = 0;
};

}  // namespace stipple
