// The screen-space resolve (raster/resolve.h): pinholes filled with their
// neighbours' mean, the fringe at a silhouette trimmed but never the frame's
// border, 3 x 3 means rounded, both pixel formats, and the raster's coverage
// bits saying exactly which pixels a point wrote.
#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "raster/point_raster.h"
#include "raster/resolve.h"

namespace stipple {
namespace {

// A frame with its coverage, drawn by hand: `set` covers a pixel with a colour.
struct Picture {
  uint16_t width, height;
  PixelFormat format;
  std::vector<uint8_t> pixels, coverage;
  std::vector<uint64_t> scratch;

  Picture(uint16_t w, uint16_t h, PixelFormat f = PixelFormat::kRgb888)
      : width(w), height(h), format(f), pixels(size_t{w} * h * bytes_per_pixel(f), 0), coverage(coverage_bytes(w, h), 0),
        scratch(resolve_scratch_bytes(w, f) / 8) {}
  size_t stride() const { return size_t{width} * bytes_per_pixel(format); }
  // Covers a pixel with a colour.
  void set(int x, int y, uint32_t rgb) {
    paint(x, y, rgb);
    coverage[y * coverage_row_bytes(width) + (x >> 3)] |= static_cast<uint8_t>(1u << (x & 7));
  }
  // Writes a pixel without covering it (what the raster does with the clear colour).
  void paint(int x, int y, uint32_t rgb) {
    uint8_t* p = &pixels[y * stride() + static_cast<size_t>(x) * bytes_per_pixel(format)];
    if (format == PixelFormat::kRgb565) {
      const uint16_t v = rgb565(rgb);
      p[0] = static_cast<uint8_t>(v);
      p[1] = static_cast<uint8_t>(v >> 8);
    } else {
      p[0] = static_cast<uint8_t>(rgb >> 16);
      p[1] = static_cast<uint8_t>(rgb >> 8);
      p[2] = static_cast<uint8_t>(rgb);
    }
  }
  uint32_t at(int x, int y) const {  // 0xRRGGBB (RGB565 expanded)
    const uint8_t* p = &pixels[y * stride() + static_cast<size_t>(x) * bytes_per_pixel(format)];
    return format == PixelFormat::kRgb565 ? rgb888_from_565(static_cast<uint16_t>(p[0] | (p[1] << 8)))
                                          : (uint32_t{p[0]} << 16) | (uint32_t{p[1]} << 8) | p[2];
  }
  void resolve(uint32_t clear = 0) {
    resolve_frame(pixels.data(), stride(), format, width, height, coverage.data(), clear, scratch.data());
  }
};

uint32_t grey(uint32_t v) { return v << 16 | v << 8 | v; }

TEST(Resolve, FillsAPinholeWithItsNeighboursMean) {
  Picture p(16, 16);
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x)
      if (x != 7 || y != 7) p.set(x, y, grey(x == 6 ? 90 : 100));
  p.resolve();
  // The hole's 8 neighbours: three of 90 (x = 6), five of 100: mean 96.25.
  // After the fill the hole is covered; the blend then takes its 3 x 3
  // (the filled 96 and eight neighbours): (3 * 90 + 5 * 100 + 96) / 9 = 96.2.
  EXPECT_EQ(p.at(7, 7), grey(96));
  // Far from the hole the blend is the plain 3 x 3 mean: 100 at x = 9...
  EXPECT_EQ(p.at(9, 3), grey(100));
  // ... and (3 x 90 + 6 x 100) / 9 = 96.67 -> 97 beside the 90 column.
  EXPECT_EQ(p.at(7, 3), grey(97));
}

TEST(Resolve, TrimsTheFringeButNotTheFrameBorder) {
  // The left half covered, up to and including column 7.
  Picture p(16, 8);
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 16; ++x) x <= 7 ? p.set(x, y, grey(200)) : p.paint(x, y, 0x102030);
  p.resolve(0x102030);
  for (int y = 0; y < 8; ++y) {
    // The border column 0 and the top and bottom rows stay: beyond the frame counts as covered.
    for (int x = 0; x <= 6; ++x) EXPECT_EQ(p.at(x, y), grey(200)) << x << "," << y;
    // Column 7 touches the uncovered column 8: trimmed to the clear colour.
    EXPECT_EQ(p.at(7, y), 0x102030u) << y;
    // Outside: at most 3 covered neighbours, never filled.
    for (int x = 8; x < 16; ++x) EXPECT_EQ(p.at(x, y), 0x102030u) << x << "," << y;
  }
}

TEST(Resolve, ACornerIsNotFilledAndALoneSpeckStays) {
  Picture p(12, 12);
  // An L-shaped concave corner: rows 0-5 of columns 0-5 and columns 0-11 of rows 6-11.
  for (int y = 0; y < 12; ++y)
    for (int x = 0; x < 12; ++x)
      if (x <= 5 || y >= 6) p.set(x, y, grey(50));
  p.set(10, 1, grey(255));  // a speck far from the rest
  p.resolve();
  EXPECT_EQ(p.at(6, 5), 0u);    // the corner's outside pixel has 5 covered neighbours: not filled
  EXPECT_EQ(p.at(10, 1), grey(255));  // an isolated speck stays: a dot, not nothing
  // A 2 x 2 point alone (each pixel 3 covered neighbours) stays too.
  Picture q(8, 8);
  for (int y = 3; y < 5; ++y)
    for (int x = 3; x < 5; ++x) q.set(x, y, grey(80));
  q.resolve();
  for (int y = 3; y < 5; ++y)
    for (int x = 3; x < 5; ++x) EXPECT_EQ(q.at(x, y), grey(80)) << x << "," << y;
  EXPECT_EQ(p.at(5, 5), 0u);    // the corner's inside pixel touches the outside: trimmed
  EXPECT_EQ(p.at(2, 2), grey(50));
  EXPECT_EQ(p.at(9, 9), grey(50));
}

TEST(Resolve, BlendsBothPixelFormatsAlike) {
  for (PixelFormat f : {PixelFormat::kRgb565, PixelFormat::kRgb888}) {
    Picture p(24, 20, f);
    std::mt19937 rng(11);
    std::vector<uint32_t> drawn(24 * 20);
    for (int y = 0; y < 20; ++y)
      for (int x = 0; x < 24; ++x) {
        p.set(x, y, drawn[y * 24 + x] = rng() & 0xFFFFFFu);
        drawn[y * 24 + x] = p.at(x, y);  // as the format holds it
      }
    p.resolve();
    // Everything covered: every pixel is the rounded mean of its 3 x 3 block
    // inside the frame (rounded half up), channel by channel as the format
    // stores it: 8-bit channels, or RGB565's 5, 6 and 5 bits.
    const uint32_t shift[3] = {f == PixelFormat::kRgb565 ? 11u : 16u, f == PixelFormat::kRgb565 ? 5u : 8u, 0u};
    const uint32_t mask[3] = {f == PixelFormat::kRgb565 ? 31u : 255u, f == PixelFormat::kRgb565 ? 63u : 255u,
                              f == PixelFormat::kRgb565 ? 31u : 255u};
    const auto stored = [&](uint32_t rgb) { return f == PixelFormat::kRgb565 ? uint32_t{rgb565(rgb)} : rgb; };
    for (int y = 0; y < 20; ++y)
      for (int x = 0; x < 24; ++x) {
        uint32_t sum[3] = {0, 0, 0}, n = 0;
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const int xx = x + dx, yy = y + dy;
            if (xx < 0 || yy < 0 || xx >= 24 || yy >= 20) continue;
            const uint32_t v = stored(drawn[yy * 24 + xx]);
            for (int c = 0; c < 3; ++c) sum[c] += (v >> shift[c]) & mask[c];
            ++n;
          }
        uint32_t mean = 0;
        for (int c = 0; c < 3; ++c) mean |= (2 * sum[c] + n) / (2 * n) << shift[c];
        const uint32_t expect = f == PixelFormat::kRgb565 ? rgb888_from_565(static_cast<uint16_t>(mean)) : mean;
        ASSERT_EQ(p.at(x, y), expect) << x << "," << y;
      }
  }
}

TEST(Resolve, RasterCoverageIsExactlyThePixelsPointsWrote) {
  for (PixelFormat f : {PixelFormat::kRgb565, PixelFormat::kRgb888}) {
    const RasterConfig c{53, 41, 4, f, 400};  // a width that is no multiple of 8 or of the tile
    std::vector<uint64_t> arena(point_raster_bytes(c) / 8 + 1);
    PointRaster raster;
    ASSERT_EQ(raster.init(c, arena.data(), arena.size() * 8), RasterStatus::kOk);
    std::mt19937 rng(5);
    std::vector<uint8_t> covered(53 * 41, 0);
    for (int i = 0; i < 150; ++i) {
      const int32_t x = static_cast<int32_t>(rng() % (58 * 16)) - 40, y = static_cast<int32_t>(rng() % (46 * 16)) - 40;
      const int s = 1 + static_cast<int>(rng() % 3);
      ASSERT_TRUE(raster.add(ScreenPoint{x, y, 1000u + static_cast<uint32_t>(i), 0x000000}, s));  // black points: colour cannot tell
      const int x0 = (x - (s - 1) * 8) >> 4, y0 = (y - (s - 1) * 8) >> 4;
      for (int yy = y0; yy < y0 + s; ++yy)
        for (int xx = x0; xx < x0 + s; ++xx)
          if (xx >= 0 && yy >= 0 && xx < 53 && yy < 41) covered[yy * 53 + xx] = 1;
    }
    std::vector<uint8_t> frame(53 * 41 * bytes_per_pixel(f)), bits(coverage_bytes(53, 41), 0xAA);
    raster.draw(0x000000, frame.data(), 53 * static_cast<size_t>(bytes_per_pixel(f)), bits.data());
    for (int y = 0; y < 41; ++y)
      for (int x = 0; x < 53; ++x)
        ASSERT_EQ((bits[y * coverage_row_bytes(53) + (x >> 3)] >> (x & 7)) & 1, covered[y * 53 + x]) << x << "," << y;
  }
}

}  // namespace
}  // namespace stipple
