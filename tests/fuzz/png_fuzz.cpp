// Fuzz harness: the PNG reader (platform/png_io.h, libpng's simplified API
// behind our bounds), as `image-diff` and the truth comparisons use it. The
// input is written to a file of this process's own and read back. Checked:
// no crash, no allocation beyond the file's bound (ASan's allocator limit
// catches one), and an accepted image's pixels are exactly width x height x 3
// bytes within png_pixels_bound of the file.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "platform/png_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::string path = "/tmp/stipple_png_fuzz." + std::to_string(static_cast<long>(getpid())) + ".png";
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (f == nullptr) return 0;
  if (size > 0) std::fwrite(data, 1, size, f);
  std::fclose(f);
  stipple::Image img;
  std::string error;
  if (stipple::read_png(path, img, error)) {
    const uint64_t pixels = uint64_t(img.width) * uint64_t(img.height);
    if (img.width <= 0 || img.height <= 0 || img.rgb.size() != pixels * 3) __builtin_trap();
    if (pixels > stipple::png_pixels_bound(size) || pixels > stipple::kPngMaxPixels) __builtin_trap();
  } else if (error.rfind(path + ": ", 0) != 0) {
    __builtin_trap();  // every refusal names the file
  }
  return 0;
}
