#include "raster/ewa.h"

#include "core/gaussian_table.h"

namespace stipple {

bool set_up_splat(const CloseUpFrame& f, const int32_t c[3], const int16_t frame[3][3], const int32_t sigma[3],
                  Splat* out) {
  // A pixel at the mean's depth, in MU (focal_q4 in 1/16 px; the depth
  // at least the near plane's, as the GL client's max(z, near)).
  const int64_t z = c[2] > f.near ? c[2] : f.near;
  int64_t pixel = f.focal_q4 > 0 ? (z * 16 + f.focal_q4 - 1) / f.focal_q4 : 1;
  if (pixel > (int64_t{1} << 29)) pixel = int64_t{1} << 29;  // sigma^2 + pixel^2 below 2^61
  int32_t widened[3] = {sigma[0], sigma[1], sigma[2]};
  for (int k = 0; k < 2; ++k) {
    const uint64_t r = isqrt64(static_cast<uint64_t>(int64_t{sigma[k]} * sigma[k] + pixel * pixel));
    widened[k] = r > 0x3FFFFFFFu ? 0x3FFFFFFF : static_cast<int32_t>(r);
  }
  if (!set_up_close_up(f, c, frame, widened, &out->disc)) return false;
  const int32_t radius = widened[0] > widened[1] ? widened[0] : widened[1];
  const uint64_t push = f.depth_shift >= 0 ? static_cast<uint64_t>(radius) << f.depth_shift
                                            : static_cast<uint64_t>(radius) >> -f.depth_shift;
  out->push = push > 0xFFFFFFFEu ? 0xFFFFFFFEu : static_cast<uint32_t>(push);
  return true;
}

}  // namespace stipple
