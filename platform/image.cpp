// stipple platform — images. See image.h.
#include "platform/image.h"

#include <cmath>
#include <limits>

#include "platform/file_io.h"

namespace stipple {

void image_from_frame(const uint8_t* frame, size_t stride, int width, int height, PixelFormat format, Image& out) {
  out.width = width;
  out.height = height;
  out.rgb.resize(static_cast<size_t>(width) * height * 3);
  for (int y = 0; y < height; ++y) {
    const uint8_t* row = frame + static_cast<size_t>(y) * stride;
    uint8_t* dst = out.rgb.data() + static_cast<size_t>(y) * width * 3;
    if (format == PixelFormat::kRgb888) {
      for (int i = 0; i < 3 * width; ++i) dst[i] = row[i];
      continue;
    }
    for (int x = 0; x < width; ++x) {
      const uint32_t v = rgb888_from_565(static_cast<uint16_t>(row[2 * x] | (row[2 * x + 1] << 8)));
      dst[3 * x] = static_cast<uint8_t>(v >> 16);
      dst[3 * x + 1] = static_cast<uint8_t>(v >> 8);
      dst[3 * x + 2] = static_cast<uint8_t>(v);
    }
  }
}

double image_psnr(const Image& a, const Image& b) {
  if (a.rgb.size() != b.rgb.size() || a.rgb.empty()) return 0;
  double sum = 0;
  for (size_t i = 0; i < a.rgb.size(); ++i) {
    const double d = static_cast<double>(a.rgb[i]) - b.rgb[i];
    sum += d * d;
  }
  if (sum == 0) return std::numeric_limits<double>::infinity();
  return 10 * std::log10(255.0 * 255.0 / (sum / static_cast<double>(a.rgb.size())));
}

bool write_ppm(const std::string& path, const Image& image, std::string& error) {
  const std::string header = "P6\n" + std::to_string(image.width) + " " + std::to_string(image.height) + "\n255\n";
  std::vector<uint8_t> bytes(header.begin(), header.end());
  bytes.insert(bytes.end(), image.rgb.begin(), image.rgb.end());
  return write_file_atomic(path, bytes, error);
}

}  // namespace stipple
