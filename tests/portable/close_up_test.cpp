// Close-ups (raster/close_up.h): a node's 3 sigma disc, cast pixel by pixel
// at its tangent plane — its outline, its depth and what it leaves alone.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "raster/close_up.h"
#include "raster/projection.h"

namespace stipple {
namespace {

constexpr int kWidth = 320, kHeight = 240, kTileLog2 = 9;  // one tile the whole screen
constexpr int32_t kFocalPx = 400, kNear = 1 << 12, kFar = 1 << 28;

struct Disc {
  CloseUpFrame frame{16 * kFocalPx, 16 * kWidth / 2, 16 * kHeight / 2, kNear, kWidth, kHeight,
                     __builtin_clz(static_cast<uint32_t>(kFar - kNear))};
  std::vector<uint64_t> words = std::vector<uint64_t>(size_t{1} << (2 * kTileLog2), pack_word<uint64_t>(0xFFFFFFFFu, 0));
  uint16_t reciprocal[1 << kReciprocalBits];
  PointTables tables;
  Disc() { build_reciprocal_table(reciprocal); }

  // A disc of sigma `sigma` (MU) at camera-space `c`, its normal turned by
  // `tilt` radians about the x axis from facing the eye; false when no disc.
  bool draw(const int32_t c[3], int32_t sigma, double tilt) {
    const auto q14 = [](double v) { return static_cast<int16_t>(std::lround(v * 16384)); };
    const int16_t axes[3][3] = {{q14(1), 0, 0},
                                {0, q14(std::cos(tilt)), q14(std::sin(tilt))},
                                {0, q14(-std::sin(tilt)), q14(std::cos(tilt))}};
    const int32_t sigmas[3] = {sigma, sigma, sigma / 10};
    CloseUp s;
    if (!set_up_close_up(frame, c, axes, sigmas, &s)) return false;
    s.shade = PackedShade(PointShade{});
    s.shade.node_rgb = 0x808080;
    draw_close_up<PointNormals::kNode, false>(s, tables, reciprocal, 0, 0, kWidth, kHeight, kTileLog2, words.data());
    return true;
  }
  uint64_t at(int x, int y) const { return words[(size_t{static_cast<size_t>(y)} << kTileLog2) + x]; }
  int covered() const {
    int n = 0;
    for (int y = 0; y < kHeight; ++y)
      for (int x = 0; x < kWidth; ++x) n += (at(x, y) >> 32) != 0xFFFFFFFFu;
    return n;
  }
};

// Facing the eye: a circle of 3 sigma's radius on screen, its depth the
// mean's at the centre.
TEST(CloseUp, AFacingDiscIsItsCircle) {
  Disc d;
  const int32_t z = 1 << 20, sigma = z / 20;  // 20 px a sigma: a 60 px radius
  const int32_t c[3] = {0, 0, z};
  ASSERT_TRUE(d.draw(c, sigma, 0.0));
  const double expected = 3.14159265 * 60 * 60;
  std::printf("facing disc: %d pixels, the circle %.0f\n", d.covered(), expected);
  EXPECT_NEAR(d.covered(), expected, 0.01 * expected);
  // Its outline: inside at 58 px from the centre, outside at 62.
  EXPECT_NE(d.at(160 + 58, 120) >> 32, 0xFFFFFFFFu);
  EXPECT_EQ(d.at(160 + 62, 120) >> 32, 0xFFFFFFFFu);
  EXPECT_NE(d.at(160, 120 - 58) >> 32, 0xFFFFFFFFu);
  EXPECT_EQ(d.at(160, 120 - 62) >> 32, 0xFFFFFFFFu);
  // The depth word at the centre: (z - near) << shift, within 2^-10.
  const double want = static_cast<double>(z - kNear) * std::ldexp(1.0, d.frame.depth_shift);
  const double got = static_cast<double>(d.at(160, 120) >> 32);
  EXPECT_NEAR(got, want, want / 1024);
  // A square's corner pixel of the same colour is untouched.
  EXPECT_EQ(d.at(0, 0), pack_word<uint64_t>(0xFFFFFFFFu, 0));
}

// Turned 60 degrees from the eye: an ellipse of half the area, the near
// half of it nearer than the far half (depth per pixel, perspective
// correct — not the mean's).
TEST(CloseUp, ATurnedDiscIsForeshortenedAndSloped) {
  Disc d;
  const int32_t z = 1 << 20, sigma = z / 20;
  const int32_t c[3] = {0, 0, z};
  ASSERT_TRUE(d.draw(c, sigma, 3.14159265 / 3));
  const double circle = 3.14159265 * 60 * 60;
  std::printf("turned disc: %d pixels, half the circle %.0f\n", d.covered(), circle / 2);
  EXPECT_NEAR(d.covered(), circle / 2, 0.03 * circle / 2);
  const uint64_t up = d.at(160, 120 - 20) >> 32, down = d.at(160, 120 + 20) >> 32;
  EXPECT_NE(up, down);
  EXPECT_NE(up, 0xFFFFFFFFu);
  EXPECT_NE(down, 0xFFFFFFFFu);
}

// Seen from inside a tenth of its sigma: the whole screen, every pixel's
// depth in front of the near plane — and a disc behind the eye draws nothing.
TEST(CloseUp, FromCloseItCoversTheScreenAndBehindNothing) {
  Disc d;
  const int32_t sigma = 1 << 20;
  const int32_t near_c[3] = {sigma / 7, -sigma / 5, sigma / 10};
  ASSERT_TRUE(d.draw(near_c, sigma, 0.2));
  EXPECT_EQ(d.covered(), kWidth * kHeight);
  Disc behind;
  const int32_t back[3] = {0, 0, -(1 << 20)};
  if (behind.draw(back, 1 << 16, 0.0)) {
    EXPECT_EQ(behind.covered(), 0);
  }
  // Edge on through the eye: no disc.
  Disc edge;
  const int32_t side[3] = {0, 1 << 20, 0};
  EXPECT_FALSE(edge.draw(side, 1 << 16, 0.0));
}

}  // namespace
}  // namespace stipple
