// Tile-based point rasterizer: depth order, tie rule, clipping, tile edges,
// both pixel formats, and exact agreement with a naive untiled rasterizer.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

#include "raster/point_kernel_avx2.h"
#include "raster/point_raster.h"

namespace stipple {
namespace {

struct Frame {
  RasterConfig config;
  std::vector<uint64_t> arena;
  PointRaster raster;
  std::vector<uint8_t> pixels;

  explicit Frame(RasterConfig c) : config(c), arena(point_raster_bytes(c) / 8 + 1) {
    EXPECT_EQ(raster.init(c, arena.data(), arena.size() * 8), RasterStatus::kOk);
    pixels.assign(static_cast<size_t>(c.width) * c.height * bytes_per_pixel(c.format), 0);
  }
  void draw(uint32_t clear) { raster.draw(clear, pixels.data(), static_cast<size_t>(config.width) * bytes_per_pixel(config.format)); }
  uint32_t at(int x, int y) const {  // RGB565 value or 0xRRGGBB
    const uint8_t* p = &pixels[(static_cast<size_t>(y) * config.width + x) * bytes_per_pixel(config.format)];
    return config.format == PixelFormat::kRgb565 ? static_cast<uint32_t>(p[0] | (p[1] << 8))
                                                 : (uint32_t{p[0]} << 16) | (uint32_t{p[1]} << 8) | p[2];
  }
};

ScreenPoint pt(double x, double y, uint32_t depth, uint32_t rgb) {
  return ScreenPoint{static_cast<int32_t>(x * 16), static_cast<int32_t>(y * 16), depth, rgb};
}

TEST(Raster, Rgb565Packing) {
  EXPECT_EQ(rgb565(0xFF8000), 0xFC00);
  EXPECT_EQ(rgb565(0xFFFFFF), 0xFFFF);
  EXPECT_EQ(rgb565(0x0000FF), 0x001F);
}

TEST(Raster, NearerPointWinsInEitherOrder) {
  for (PixelFormat f : {PixelFormat::kRgb565, PixelFormat::kRgb888}) {
    for (int order = 0; order < 2; ++order) {
      Frame fr({64, 48, 5, f, 16});
      fr.raster.begin_frame();
      const ScreenPoint near = pt(10.5, 10.5, 0x10000000, 0xFF0000), far = pt(10.5, 10.5, 0x20000000, 0x00FF00);
      fr.raster.add(order ? near : far, 1);
      fr.raster.add(order ? far : near, 1);
      fr.draw(0x000000);
      EXPECT_EQ(fr.at(10, 10), f == PixelFormat::kRgb565 ? rgb565(0xFF0000) : 0xFF0000u);
      EXPECT_EQ(fr.at(11, 10), 0u);  // clear colour elsewhere
    }
  }
}

TEST(Raster, EqualDepthResolvesDeterministically) {
  Frame a({32, 32, 4, PixelFormat::kRgb888, 16}), b({32, 32, 4, PixelFormat::kRgb888, 16});
  const ScreenPoint p = pt(5, 5, 777, 0x123456), q = pt(5, 5, 777, 0x654321);
  a.raster.add(p, 2);
  a.raster.add(q, 2);
  b.raster.add(q, 2);
  b.raster.add(p, 2);
  a.draw(0xFFFFFF);
  b.draw(0xFFFFFF);
  EXPECT_EQ(a.pixels, b.pixels);
  EXPECT_EQ(a.at(5, 5), 0x123456u);  // the smaller colour value
}

TEST(Raster, PointOnATileCornerIsDrawnExactlyOncePerPixel) {
  Frame fr({64, 64, 5, PixelFormat::kRgb888, 16});  // tiles meet at (32, 32)
  fr.raster.add(pt(32.0, 32.0, 5, 0xABCDEF), 3);     // covers 31..33 on both axes
  fr.draw(0x000000);
  int covered = 0;
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x) {
      const bool inside = x >= 31 && x <= 33 && y >= 31 && y <= 33;
      EXPECT_EQ(fr.at(x, y), inside ? 0xABCDEFu : 0u) << x << "," << y;
      covered += fr.at(x, y) != 0;
    }
  EXPECT_EQ(covered, 9);
}

TEST(Raster, ClipsAtTheScreenEdgesAndRespectsTheBudget) {
  Frame fr({20, 10, 3, PixelFormat::kRgb565, 3});
  EXPECT_TRUE(fr.raster.add(pt(0.2, 0.2, 1, 0xFFFFFF), 3));    // corner: 2 x 2 visible
  EXPECT_TRUE(fr.raster.add(pt(-5, 4, 1, 0xFFFFFF), 3));       // off screen: ignored
  EXPECT_TRUE(fr.raster.add(pt(19.9, 9.9, 1, 0xFFFFFF), 2));   // bottom-right: 1 pixel visible
  EXPECT_EQ(fr.raster.points(), 2u);
  EXPECT_TRUE(fr.raster.add(pt(10, 5, 1, 0xFFFFFF), 1));
  EXPECT_FALSE(fr.raster.add(pt(11, 5, 1, 0xFFFFFF), 1));      // budget of 3 is full
  fr.draw(0x000000);
  int lit = 0;
  for (int y = 0; y < 10; ++y)
    for (int x = 0; x < 20; ++x) lit += fr.at(x, y) != 0;
  EXPECT_EQ(lit, 4 + 1 + 1);
  EXPECT_NE(fr.at(0, 0), 0u);
  EXPECT_NE(fr.at(19, 9), 0u);
}

TEST(Raster, ArenaAndConfigChecks) {
  RasterConfig c{240, 320, 5, PixelFormat::kRgb565, 30000};
  const size_t need = point_raster_bytes(c);
  EXPECT_GT(need, 0u);
  std::vector<uint64_t> arena(need / 8);
  PointRaster r;
  EXPECT_EQ(r.init(c, arena.data(), need - 8), RasterStatus::kArenaTooSmall);
  EXPECT_EQ(r.init(c, arena.data(), need), RasterStatus::kOk);
  c.tile_log2 = 9;
  EXPECT_EQ(point_raster_bytes(c), 0u);
  EXPECT_EQ(r.init(c, arena.data(), need), RasterStatus::kBadConfig);
}

// Items (the renderer's tile-pass nodes) share the bins' pool: max_nodes
// of them always fit, more as their points spare the bins, never so many
// that a point of the budget loses the bins' room, and neither overwrites
// the other; each is handed to the tile function in every tile it is filed in.
TEST(Raster, ItemsShareThePoolWithTheBins) {
  RasterConfig c{128, 128, 6, PixelFormat::kRgb565, 6400};  // 2 x 2 tiles of 64 px
  c.max_nodes = 10;
  c.item_words = 30;  // 136 bytes with the links
  Frame fr(c);
  PointRaster& r = fr.raster;
  // 6,400 points: 8,000 entries, 125 chunks of 512 bytes, and 4 + 4 more;
  // 10 items' 1,360 bytes round up to 3 chunks, 1,536 bytes: 11 items of
  // 136 bytes. An item of 1 point spares the bins too little to lend more.
  EXPECT_EQ(point_raster_items(c), 136u * 512 / 136);
  EXPECT_EQ(r.item_capacity(), point_raster_items(c));
  uint32_t n = 0;
  for (; r.item_room(1); ++n) r.take_item(1);
  EXPECT_EQ(n, 11u);
  // Items of 64 points spare the bins 80 entries each, more than their
  // 136 bytes: every one fits until the budget is full.
  r.begin_frame();
  for (n = 0; r.item_room(64); ++n) r.take_item(64);
  EXPECT_EQ(n, 100u);
  EXPECT_EQ(r.points(), 6400u);
  EXPECT_FALSE(r.add(pt(10, 10, 1, 0xFFFFFF), 1));  // the budget is full

  // 40 items of 40 points, each filed in the tile (k % 4) — the first in
  // all four — then the rest of the budget binned, one pixel a point: every
  // point fits, and each item's words are as written.
  r.begin_frame();
  for (uint32_t k = 0; k < 40; ++k) {
    ASSERT_TRUE(r.item_room(40)) << k;
    r.take_item(40);
    for (uint32_t w = 0; w < c.item_words; ++w) r.item_words(k)[w] = k * 1000 + w;
    if (k == 0)
      for (int t = 0; t < 4; ++t) r.file_item(k, t, static_cast<uint32_t>(t));
    else
      r.file_item(k, 0, k % 4);
  }
  std::mt19937 rng(7);
  for (uint32_t i = 0; i < 4800; ++i) {
    const double x = static_cast<double>(rng() % 128) + 0.5, y = static_cast<double>(rng() % 128) + 0.5;
    ASSERT_TRUE(r.add(pt(x, y, 1000 + i, 0x00FF00), 1)) << i;
  }
  EXPECT_EQ(r.points(), 6400u);
  for (uint32_t k = 0; k < 40; ++k)
    for (uint32_t w = 0; w < c.item_words; ++w) ASSERT_EQ(r.item_words(k)[w], k * 1000 + w) << k << " " << w;
  struct Seen {
    const PointRaster* raster;
    std::vector<uint32_t> items[4];
  } seen{&r, {}};
  r.draw(0, fr.pixels.data(), 128 * 2, nullptr, [](void* context, uint32_t tile, int, int, void*) {
    Seen& s = *static_cast<Seen*>(context);
    for (uint32_t l = s.raster->first_link(tile); l != PointRaster::kNoLink; l = s.raster->next_link(l))
      s.items[tile].push_back(s.raster->item_of(l));
  }, &seen);
  for (uint32_t t = 0; t < 4; ++t) {
    std::vector<uint32_t> want;
    for (uint32_t k = 40; k-- > 0;)  // the last filed first
      if (k == 0 || k % 4 == t) want.push_back(k);
    EXPECT_EQ(seen.items[t], want) << "tile " << t;
  }
  EXPECT_EQ(r.items(), 40u);  // 4 times the 10 items owned: lent by the bins

  // No items configured: none taken, none held.
  c.max_nodes = 0;
  Frame bare(c);
  EXPECT_FALSE(bare.raster.item_room(1));
  EXPECT_EQ(point_raster_items(c), 0u);
  c.max_nodes = 10;
  c.item_words = 0;  // items of no words
  EXPECT_EQ(point_raster_bytes(c), 0u);
}

// Naive reference: every pixel takes the minimum packed word of the points
// covering it, with the same covering rule and no tiles.
std::vector<uint8_t> naive(const RasterConfig& c, const std::vector<std::pair<ScreenPoint, int>>& pts, uint32_t clear) {
  const bool r565 = c.format == PixelFormat::kRgb565;
  auto pack = [&](uint32_t depth, uint32_t rgb) -> uint64_t {
    return r565 ? ((depth & 0xFFFF0000u) | rgb565(rgb)) : ((uint64_t{depth} << 32) | (rgb & 0xFFFFFF));
  };
  std::vector<uint64_t> words(static_cast<size_t>(c.width) * c.height, pack(0xFFFFFFFFu, clear));
  for (const auto& [p, s] : pts) {
    const int x0 = (p.x_q4 - (s - 1) * 8) >> 4, y0 = (p.y_q4 - (s - 1) * 8) >> 4;
    for (int y = y0; y < y0 + s; ++y)
      for (int x = x0; x < x0 + s; ++x)
        if (x >= 0 && y >= 0 && x < c.width && y < c.height) {
          uint64_t& w = words[static_cast<size_t>(y) * c.width + x];
          w = std::min(w, pack(p.depth, p.rgb));
        }
  }
  std::vector<uint8_t> out;
  for (uint64_t w : words) {
    if (r565) {
      out.push_back(static_cast<uint8_t>(w));
      out.push_back(static_cast<uint8_t>(w >> 8));
    } else {
      out.push_back(static_cast<uint8_t>(w >> 16));
      out.push_back(static_cast<uint8_t>(w >> 8));
      out.push_back(static_cast<uint8_t>(w));
    }
  }
  return out;
}

TEST(Raster, TiledEqualsNaiveForRandomPoints) {
  std::mt19937 rng(42);
  for (PixelFormat f : {PixelFormat::kRgb565, PixelFormat::kRgb888})
    for (uint8_t tile_log2 : {uint8_t{3}, uint8_t{5}, uint8_t{7}}) {
      const RasterConfig c{101, 67, tile_log2, f, 5000};  // sizes not multiples of the tile
      Frame fr(c);
      std::vector<std::pair<ScreenPoint, int>> pts;
      for (int i = 0; i < 4000; ++i) {
        const ScreenPoint p{static_cast<int32_t>(rng() % (110 * 16)) - 4 * 16, static_cast<int32_t>(rng() % (76 * 16)) - 4 * 16,
                            static_cast<uint32_t>(rng() % 64) << 24, static_cast<uint32_t>(rng() & 0xFFFFFF)};  // many equal depths
        const int s = 1 + static_cast<int>(rng() % 3);
        ASSERT_TRUE(fr.raster.add(p, s));
        pts.push_back({p, s});
      }
      fr.draw(0x334455);
      ASSERT_EQ(fr.pixels, naive(c, pts, 0x334455)) << "format " << static_cast<int>(f) << " tile " << int{tile_log2};
    }
}

// The write-out into a frame at any address and of any width: RGB565 rows
// go out four, two and one pixels at a time by the row's alignment and
// length (odd addresses a pixel at a time), and nothing outside the frame's
// rows is written.
TEST(Raster, WritesFramesAtEveryAlignmentAndWidth) {
  std::mt19937 rng(7);
  for (PixelFormat f : {PixelFormat::kRgb565, PixelFormat::kRgb888})
    for (uint16_t width = 1; width <= 21; ++width)
      for (size_t offset = 0; offset < 4; ++offset) {
        const RasterConfig c{width, 5, 3, f, 400};  // 8 px tiles: rows of 1..8 px, every remainder
        Frame fr(c);
        std::vector<std::pair<ScreenPoint, int>> pts;
        for (int i = 0; i < 3 * width; ++i) {
          const ScreenPoint p{static_cast<int32_t>(rng() % ((width + 2) * 16)) - 16, static_cast<int32_t>(rng() % (7 * 16)) - 16,
                              static_cast<uint32_t>(rng()), static_cast<uint32_t>(rng() & 0xFFFFFF)};
          const int s = 1 + static_cast<int>(rng() % 3);
          ASSERT_TRUE(fr.raster.add(p, s));
          pts.push_back({p, s});
        }
        const size_t row = static_cast<size_t>(width) * bytes_per_pixel(f), stride = row + 3;  // each row at another alignment
        std::vector<uint8_t> frame(offset + stride * c.height + 8, 0xA5);
        fr.raster.draw(0x102030, frame.data() + offset, stride);
        const std::vector<uint8_t> want = naive(c, pts, 0x102030);
        for (int y = 0; y < c.height; ++y) {
          const uint8_t* got = frame.data() + offset + y * stride;
          ASSERT_TRUE(std::equal(got, got + row, want.begin() + static_cast<ptrdiff_t>(y * row)))
              << "format " << static_cast<int>(f) << " width " << width << " offset " << offset << " row " << y;
          for (size_t k = row; k < stride; ++k) ASSERT_EQ(got[k], 0xA5) << "the gap after row " << y << " was written";
        }
        for (size_t k = 0; k < offset; ++k) ASSERT_EQ(frame[k], 0xA5) << "a byte before the frame was written";
      }
}

}  // namespace
}  // namespace stipple

namespace stipple {
namespace {

// The tiles' clear and write-out in AVX2 (RasterConfig::avx2, where the CPU
// has it) give the scalar loops' pixels and coverage: odd widths (a tile's
// row ending mid-register), both formats, every tile size.
TEST(Raster, Avx2TileFinishWritesTheScalarPixels) {
  if (!avx2::supported()) GTEST_SKIP() << "no AVX2 on this CPU (or not x86-64)";
  for (PixelFormat f : {PixelFormat::kRgb565, PixelFormat::kRgb888}) {
    for (const uint8_t tile_log2 : {uint8_t{3}, uint8_t{5}, uint8_t{6}, uint8_t{7}}) {
      std::vector<uint8_t> pixels[2], coverage[2];
      for (int wide = 0; wide < 2; ++wide) {
        RasterConfig c{100, 37, tile_log2, f, 4000};
        c.avx2 = wide == 1;
        Frame fr(c);
        std::mt19937 points(11);
        fr.raster.begin_frame();
        for (int i = 0; i < 3000; ++i)
          fr.raster.add(ScreenPoint{static_cast<int32_t>(points() % 1700) - 50, static_cast<int32_t>(points() % 700) - 50,
                                    static_cast<uint32_t>(points()), static_cast<uint32_t>(points())},
                        1 + static_cast<int>(points() % 3));
        coverage[wide].assign(static_cast<size_t>((c.width + 7) / 8) * c.height, 0xAA);
        fr.raster.draw(0x123456, fr.pixels.data(), static_cast<size_t>(c.width) * bytes_per_pixel(f), coverage[wide].data());
        pixels[wide] = fr.pixels;
      }
      EXPECT_EQ(pixels[0], pixels[1]) << int(tile_log2);
      EXPECT_EQ(coverage[0], coverage[1]) << int(tile_log2);
    }
  }
}

}  // namespace
}  // namespace stipple
