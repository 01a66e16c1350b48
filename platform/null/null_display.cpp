// stipple platform — the null display. See null_display.h.
#include "platform/null/null_display.h"

#include <cerrno>
#include <cstdio>
#include <cstring>

namespace stipple {

NullDisplay::NullDisplay(uint16_t width, uint16_t height, PixelFormat format, std::string path, uint32_t frame_us)
    : width_(width), height_(height), format_(format), path_(std::move(path)), frame_us_(frame_us) {
  image_.width = width;
  image_.height = height;
  image_.rgb.assign(static_cast<size_t>(width) * height * 3, 0);
}

bool NullDisplay::present(const uint8_t* frame, size_t stride, uint16_t width, uint16_t height, PixelFormat format,
                          std::string& error) {
  const uint16_t w = width < width_ ? width : width_, h = height < height_ ? height : height_;
  // Into the kept image (its storage was sized at construction): crop, expand.
  for (int y = 0; y < h; ++y) {
    const uint8_t* src = frame + static_cast<size_t>(y) * stride;
    uint8_t* dst = image_.rgb.data() + static_cast<size_t>(y) * width_ * 3;
    for (int x = 0; x < w; ++x) {
      if (format == PixelFormat::kRgb888) {
        dst[3 * x] = src[3 * x], dst[3 * x + 1] = src[3 * x + 1], dst[3 * x + 2] = src[3 * x + 2];
      } else {
        const uint32_t v = rgb888_from_565(static_cast<uint16_t>(src[2 * x] | (src[2 * x + 1] << 8)));
        dst[3 * x] = static_cast<uint8_t>(v >> 16), dst[3 * x + 1] = static_cast<uint8_t>(v >> 8),
        dst[3 * x + 2] = static_cast<uint8_t>(v);
      }
    }
  }
  const uint32_t index = frames_++;
  if (path_.empty()) return true;
  // The file: written beside its name, then renamed over it (atomic).
  const int n = path_.find('%') != std::string::npos ? std::snprintf(name_, sizeof name_, path_.c_str(), index)
                                                     : std::snprintf(name_, sizeof name_, "%s", path_.c_str());
  if (n < 0 || n >= static_cast<int>(sizeof name_)) return error = path_ + ": file name too long", false;
  std::snprintf(temp_, sizeof temp_, "%s.tmp", name_);
  std::FILE* f = std::fopen(temp_, "wb");
  if (f == nullptr) return error = std::string(name_) + ": " + std::strerror(errno), false;
  // The first failure's reason (a full disk: "No space left on device").
  int why = 0;
  const bool wrote = std::fprintf(f, "P6\n%d %d\n255\n", image_.width, image_.height) > 0 &&
                     std::fwrite(image_.rgb.data(), 1, image_.rgb.size(), f) == image_.rgb.size();
  if (!wrote) why = errno;
  const bool closed = std::fclose(f) == 0;
  if (!closed && why == 0) why = errno;
  if (!wrote || !closed || std::rename(temp_, name_) != 0) {
    if (why == 0) why = errno;
    std::remove(temp_);
    return error = std::string(name_) + ": cannot write the frame: " + std::strerror(why), false;
  }
  return true;
}

bool NullDisplay::poll(InputEvent* event) {
  if (count_ == 0) return false;
  *event = queue_[head_];
  head_ = (head_ + 1) % kMaxQueued;
  --count_;
  return true;
}

bool NullDisplay::push_input(const InputEvent& event) {
  if (count_ == kMaxQueued) return false;
  queue_[(head_ + count_) % kMaxQueued] = event;
  ++count_;
  return true;
}

}  // namespace stipple
