// stipple raster — tile-based z-buffer point rasterizer.
//
// Points arrive in screen space: x, y in 1/16 pixel (Q4), a depth where
// smaller is nearer, and an RGB888 colour. `add` bins each point into the
// tiles its square (1-3 px a side) touches; `draw` walks the tiles, keeping
// one tile's depth+colour words hot, and writes the finished frame.
//
// Depth and colour share one word — depth in the high bits, colour in the
// low — so a point costs one load, one compare and one store, and equal
// depths resolve deterministically to the smaller colour value whatever the
// order of the points. RGB565 frames use 32-bit words (16-bit depth), RGB888
// frames 64-bit words (32-bit depth). A pixel belongs to exactly one tile, so
// a point on a tile edge is drawn exactly once per pixel it covers.
//
// Square of size s at (x, y): pixels [floor(x - (s-1)/2), ... + s) on each
// axis (s = 1: the pixel containing the point); clipped to the screen.
// Memory comes from one caller-provided arena (`point_raster_bytes`); nothing
// is allocated afterwards, nothing is thrown, no floating point is used.
#pragma once

#include <cstddef>
#include <cstdint>

namespace stipple {

enum class PixelFormat : uint8_t { kRgb565, kRgb888 };

inline constexpr int bytes_per_pixel(PixelFormat f) { return f == PixelFormat::kRgb565 ? 2 : 3; }

struct RasterConfig {
  uint16_t width = 240, height = 320;
  uint8_t tile_log2 = 5;  // 32 x 32 tiles
  PixelFormat format = PixelFormat::kRgb565;
  uint32_t max_points = 1u << 16;  // points per frame; more are refused by add()
};

struct ScreenPoint {
  int32_t x_q4 = 0, y_q4 = 0;  // 1/16 pixel
  uint32_t depth = 0;          // nearer is smaller; RGB565 frames use the top 16 bits
  uint32_t rgb = 0;            // 0xRRGGBB
};

enum class RasterStatus : uint8_t { kOk = 0, kBadConfig, kArenaTooSmall };

// Arena bytes `PointRaster::init` needs (8-byte aligned sections), or 0 for an
// invalid configuration (zero size, tiles outside 8..128 px).
size_t point_raster_bytes(const RasterConfig& config);

constexpr uint16_t rgb565(uint32_t rgb) {
  return static_cast<uint16_t>(((rgb >> 8) & 0xF800u) | ((rgb >> 5) & 0x07E0u) | ((rgb >> 3) & 0x001Fu));
}

class PointRaster {
 public:
  [[nodiscard]] RasterStatus init(const RasterConfig& config, void* arena, size_t bytes);

  // Starts a frame: forgets all points.
  void begin_frame();
  // Bins a point of `size_px` (1..3). Returns false when the frame's budget
  // is full — max_points points, or max_points * 5/4 tile entries (a point
  // straddling tile edges takes 2 or 4) — and the point is dropped; a point
  // entirely off screen is accepted and ignored.
  bool add(const ScreenPoint& p, int size_px);
  // Draws the binned points over `clear_rgb` into `frame` (height rows of
  // `stride` bytes, pixels in the configured format, little-endian RGB565).
  void draw(uint32_t clear_rgb, uint8_t* frame, size_t stride) const;

  uint32_t points() const { return count_; }

 private:
  struct Binned {
    uint16_t x0, y0;  // first covered pixel (clipped to the screen)
    uint32_t depth;
    uint32_t rgb_wh;  // 0xRRGGBB, covered width << 24, height << 28 (after clipping, 1..3)
  };
  template <class Word>
  void draw_tiles(uint32_t clear_rgb, uint8_t* frame, size_t stride) const;

  RasterConfig config_{};
  int tiles_x_ = 0, tiles_y_ = 0;
  Binned* points_ = nullptr;
  uint32_t* tile_start_ = nullptr;  // per tile, after draw's prefix sum
  uint32_t* tile_count_ = nullptr;
  uint32_t* tile_index_ = nullptr;  // point indices grouped by tile
  uint32_t* tile_fill_ = nullptr;
  void* tile_words_ = nullptr;      // one tile of depth+colour words
  uint32_t count_ = 0, bins_ = 0, bin_capacity_ = 0;
};

}  // namespace stipple
