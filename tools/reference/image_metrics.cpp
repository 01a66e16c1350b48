// stipple host — a picture against its reference. See image_metrics.h.
#include "tools/reference/image_metrics.h"

#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

namespace stipple {

ImageComparison compare_images(const Image& a, const Image& b, uint32_t background) {
  ImageComparison r;
  if (a.width != b.width || a.height != b.height || a.rgb.size() != b.rgb.size()) return ImageComparison{0, 0, 0, 0, 0, 0};
  const int w = a.width, h = a.height;
  const size_t n = static_cast<size_t>(w) * h;
  std::vector<double> la(n), lb(n);
  std::vector<char> ca(n), cb(n);
  const auto covered = [&](const Image& im, size_t i) {
    const uint32_t v = (uint32_t{im.rgb[3 * i]} << 16) | (uint32_t{im.rgb[3 * i + 1]} << 8) | im.rgb[3 * i + 2];
    return v != background;
  };
  double se = 0;
  long both = 0, lit = 0, dark = 0, in_b = 0, outside = 0, in_a = 0, missing = 0;
  for (size_t i = 0; i < n; ++i) {
    ca[i] = covered(a, i);
    cb[i] = covered(b, i);
    la[i] = 0.299 * a.rgb[3 * i] + 0.587 * a.rgb[3 * i + 1] + 0.114 * a.rgb[3 * i + 2];
    lb[i] = 0.299 * b.rgb[3 * i] + 0.587 * b.rgb[3 * i + 1] + 0.114 * b.rgb[3 * i + 2];
    if (ca[i] || cb[i]) {
      ++r.object_pixels;
      for (int k = 0; k < 3; ++k) {
        const double d = double(a.rgb[3 * i + k]) - b.rgb[3 * i + k];
        se += d * d;
      }
    }
    in_a += ca[i];
    in_b += cb[i];
    outside += cb[i] && !ca[i];
    missing += ca[i] && !cb[i];
    if (ca[i] && cb[i]) {
      ++both;
      if (la[i] >= 64) {
        ++lit;
        dark += lb[i] < la[i] / 2;
      }
    }
  }
  const double mse = r.object_pixels ? se / (3.0 * static_cast<double>(r.object_pixels)) : 0;
  r.object_psnr = mse > 0 ? 10 * std::log10(255.0 * 255.0 / mse) : std::numeric_limits<double>::infinity();
  r.dark_where_lit = lit ? static_cast<double>(dark) / static_cast<double>(lit) : 0;
  r.outside = in_b ? static_cast<double>(outside) / static_cast<double>(in_b) : 0;
  r.missing = in_a ? static_cast<double>(missing) / static_cast<double>(in_a) : 0;
  r.iou = r.object_pixels ? static_cast<double>(both) / static_cast<double>(r.object_pixels) : 1;
  // SSIM of the luma over 8x8 windows every 4 px that hold object pixels.
  const double c1 = (0.01 * 255) * (0.01 * 255), c2 = (0.03 * 255) * (0.03 * 255);
  double sum = 0;
  long windows = 0;
  for (int y = 0; y + 8 <= h; y += 4)
    for (int x = 0; x + 8 <= w; x += 4) {
      bool object = false;
      double ma = 0, mb = 0;
      for (int dy = 0; dy < 8; ++dy)
        for (int dx = 0; dx < 8; ++dx) {
          const size_t i = static_cast<size_t>(y + dy) * w + x + dx;
          object = object || ca[i] || cb[i];
          ma += la[i];
          mb += lb[i];
        }
      if (!object) continue;
      ma /= 64;
      mb /= 64;
      double va = 0, vb = 0, cov = 0;
      for (int dy = 0; dy < 8; ++dy)
        for (int dx = 0; dx < 8; ++dx) {
          const size_t i = static_cast<size_t>(y + dy) * w + x + dx;
          va += (la[i] - ma) * (la[i] - ma);
          vb += (lb[i] - mb) * (lb[i] - mb);
          cov += (la[i] - ma) * (lb[i] - mb);
        }
      va /= 63;
      vb /= 63;
      cov /= 63;
      sum += ((2 * ma * mb + c1) * (2 * cov + c2)) / ((ma * ma + mb * mb + c1) * (va + vb + c2));
      ++windows;
    }
  r.ssim = windows ? sum / static_cast<double>(windows) : 1;
  return r;
}

std::string silhouette_verdict(const ImageComparison& m) {
  char text[256];
  if (m.iou >= 0.8) {
    std::snprintf(text, sizeof text, "silhouettes agree (IoU %.2f): the PSNR and SSIM measure the shading", m.iou);
  } else if (m.missing >= m.outside) {
    std::snprintf(text, sizeof text,
                  "silhouettes disagree (IoU %.2f): the picture leaves %.0f %% of the reference empty (another view, "
                  "a camera inside, a partial model); the PSNR says little",
                  m.iou, 100 * m.missing);
  } else {
    std::snprintf(text, sizeof text,
                  "silhouettes disagree (IoU %.2f): %.0f %% of the picture lies outside the reference (another view, "
                  "bloated points); the PSNR says little",
                  m.iou, 100 * m.outside);
  }
  return text;
}

}  // namespace stipple
