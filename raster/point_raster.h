// stipple raster — tile-based z-buffer point rasterizer.
//
// Points arrive in screen space: x, y in 1/16 pixel (Q4), a depth where
// smaller is nearer, and an RGB888 colour. `add` clips each point's square
// (1-3 px a side) to the screen and files it, already split at tile edges
// and in tile-local coordinates, into the bins of the tiles it touches: each
// tile owns a chain of fixed-size chunks taken from one pool, so binning is
// a single pass with no sort. `draw` walks the tiles, keeping one tile's
// depth+colour words hot, draws its bins and writes the finished tile out.
//
// Items a caller draws itself (the renderer's small nodes, whose points it
// generates inside the tile pass) are records of the caller's words kept in
// the same pool, from its bottom up while the bins' chunks are taken from
// its top down, each filed per tile by links in its last words and handed
// back, with the tile's words, to the caller's function in `draw`. An item
// spares the bins its points, so the pool lends the items what those points
// would have taken: `max_nodes` items always have room, and more as the
// items' points free it, while every point of the budget still has the
// bins' room it had without items (take_item).
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
#include <type_traits>

namespace stipple {

enum class PixelFormat : uint8_t { kRgb565, kRgb888 };

inline constexpr int bytes_per_pixel(PixelFormat f) { return f == PixelFormat::kRgb565 ? 2 : 3; }

inline constexpr int kDefaultTileLog2 = 6;  // 64 x 64 tiles (docs/fixed_point.md, "Speed")

struct RasterConfig {
  uint16_t width = 240, height = 320;
  uint8_t tile_log2 = kDefaultTileLog2;
  PixelFormat format = PixelFormat::kRgb565;
  uint32_t max_points = 1u << 16;  // points per frame; more are refused by add()
  // Items (the renderer's nodes) drawn by the caller's tile function inside
  // the tile pass: item_words words each (and kItemLinks links), max_nodes
  // of them always room for, more as their points spare the bins (take_item);
  // max_nodes 0: none.
  uint32_t max_nodes = 0;
  uint32_t item_words = 0;
  // Clear and write out tiles with AVX2 (PointRenderer sets it where the
  // CPU has it: raster/point_kernel_avx2.h). The same bytes either way.
  bool avx2 = false;
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
// The most items a frame can hold (PointRaster::take_item): the pool's
// bytes over an item's, 0 without items.
uint32_t point_raster_items(const RasterConfig& config);

constexpr uint16_t rgb565(uint32_t rgb) {
  return static_cast<uint16_t>(((rgb >> 8) & 0xF800u) | ((rgb >> 5) & 0x07E0u) | ((rgb >> 3) & 0x001Fu));
}
// 0xRRGGBB of an RGB565 value, by bit replication (rgb565 of it gives v back).
constexpr uint32_t rgb888_from_565(uint16_t v) {
  const uint32_t r = v >> 11, g = (v >> 5) & 63u, b = v & 31u;
  return (((r << 3) | (r >> 2)) << 16) | (((g << 2) | (g >> 4)) << 8) | ((b << 3) | (b >> 2));
}

// The tile words: depth above colour. RGB565 frames: 32-bit words, the
// depth's top 16 bits above the 565 colour; RGB888: 64-bit, 32 above 24.
template <class Word>
constexpr Word pack_word(uint32_t depth, uint32_t color);
template <>
constexpr uint32_t pack_word<uint32_t>(uint32_t depth, uint32_t color) {
  return (depth & 0xFFFF0000u) | (color & 0xFFFFu);
}
template <>
constexpr uint64_t pack_word<uint64_t>(uint32_t depth, uint32_t color) {
  return (static_cast<uint64_t>(depth) << 32) | (color & 0xFFFFFFu);
}
// Whether a tile word was drawn: its depth is not the clear word's (all ones).
template <class Word>
constexpr bool word_covered(Word w) {
  return sizeof(Word) == 8 ? (w >> 32) != 0xFFFFFFFFu : (w >> 16) != 0xFFFFu;
}
// The word with another colour (pack_word's), its depth kept.
template <class Word>
constexpr Word recolour_word(Word w, uint32_t color) {
  return pack_word<Word>(sizeof(Word) == 8 ? static_cast<uint32_t>(w >> 32) : static_cast<uint32_t>(w), color);
}

// Depth-tests word `w` into the pixels from `at` in a tile of rows `tile`
// words apart, `wh` = width | height << 4 (1..15 each): the one z-test the
// bins and the tile pass share (2 x 2 and 1 x 1, nearly every point, unrolled).
template <class Word>
inline void ztest_square(Word* at, int tile, uint32_t wh, Word w) {
  if (wh == 0x22u) {
    if (w < at[0]) at[0] = w;
    if (w < at[1]) at[1] = w;
    if (w < at[tile]) at[tile] = w;
    if (w < at[tile + 1]) at[tile + 1] = w;
  } else if (wh == 0x11u) {
    if (w < at[0]) at[0] = w;
  } else {
    const int width = static_cast<int>(wh & 15u), height = static_cast<int>(wh >> 4);
    for (int y = 0; y < height; ++y, at += tile)
      for (int x = 0; x < width; ++x)
        if (w < at[x]) at[x] = w;
  }
}

class PointRaster {
 public:
  [[nodiscard]] RasterStatus init(const RasterConfig& config, void* arena, size_t bytes);

  // Starts a frame: forgets all points.
  void begin_frame();
  // Bins a point of `size_px` (1..3). Returns false when the frame's budget
  // is full — max_points points, or the chunk pool (sized for max_points
  // * 5/4 entries — a point straddling tile edges takes 2 or 4 — plus one
  // partial chunk per tile, beside the items') — and the point is dropped;
  // a point entirely off screen is accepted and ignored.
  [[gnu::always_inline]] bool add(const ScreenPoint& p, int size_px) {
    if (count_ >= config_.max_points || free_chunk_ < floor_ + 4) return false;
    const int s = size_px < 1 ? 1 : size_px > 3 ? 3 : size_px;
    // First covered pixel: floor(x - (s - 1) / 2) with x in Q4; arithmetic shift floors.
    int32_t x0 = (p.x_q4 - (s - 1) * 8) >> 4, y0 = (p.y_q4 - (s - 1) * 8) >> 4;
    int32_t x1 = x0 + s, y1 = y0 + s;  // exclusive
    if (x1 <= 0 || y1 <= 0 || x0 >= config_.width || y0 >= config_.height) return true;  // off screen
    const int sh = config_.tile_log2, mask = (1 << sh) - 1;
    ++count_;
    // Fast path: inside the screen and one tile.
    if (x0 >= 0 && y0 >= 0 && x1 <= config_.width && y1 <= config_.height && (x0 & mask) + s <= mask + 1 &&
        (y0 & mask) + s <= mask + 1) {
      push((y0 >> sh) * tiles_x_ + (x0 >> sh), p.depth, p.rgb, static_cast<uint32_t>(s | s << 4),
           static_cast<uint32_t>(((y0 & mask) << sh) | (x0 & mask)));
      return true;
    }
    split(x0, y0, x1, y1, p.depth, p.rgb);
    return true;
  }
  // Items: the caller's records, items() of them this frame, item i's words
  // at item_words(i) (config.item_words long; kItemLinks more follow, the
  // raster's). An item is filed in at most 2 x 2 tiles.
  static constexpr int kItemLinks = 4;
  uint32_t items() const { return item_count_; }
  uint32_t* item_words(uint32_t item) { return items_ + size_t{item} * item_stride_; }
  // Whether item items() for `points` points drawn in the tile pass has
  // room, and taking it, its points counted against the frame's budget.
  // The items may cover max_nodes items' bytes plus the bins' share (5/4
  // entries, in whole chunks) of the points of the items before, never a
  // chunk in use.
  bool item_room(uint32_t points) const {
    const uint32_t end = item_end_ + item_bytes_;
    return points <= config_.max_points - count_ && end <= item_allow_ && end <= free_chunk_ * chunk_bytes_;
  }
  // take_item where item_room said yes.
  void take_item(uint32_t points) {
    count_ += points;
    ++item_count_;
    grow_items(item_bytes_, points);
  }
  // Files item `item` in `tile`'s list as its filing `slot` (0..3: each
  // tile of the item's once).
  void file_item(uint32_t item, int slot, uint32_t tile) {
    const uint32_t link = item * item_stride_ + config_.item_words + static_cast<uint32_t>(slot);
    items_[link] = tile_items_[tile];
    tile_items_[tile] = link;
  }
  // Files item `item` in tile `tile` and, where `wide` and `tall` say, the
  // tiles to its right and below; took_items takes such items, written and
  // filed where room_for said there is room, `n` of them, with `points`.
  void file_item_in_tiles(uint32_t item, uint32_t tile, bool wide, bool tall) {
    int slot = 0;
    file_item(item, slot++, tile);
    if (wide) file_item(item, slot++, tile + 1);
    if (tall) file_item(item, slot++, tile + static_cast<uint32_t>(tiles_x_));
    if (wide && tall) file_item(item, slot, tile + static_cast<uint32_t>(tiles_x_) + 1);
  }
  void took_items(uint32_t n, uint32_t points) {
    item_count_ += n;
    count_ += points;
    grow_items(n * item_bytes_, points);
  }
  // Whether `items` more items (written before they are taken) and `points`
  // more points, each filed as items or binned however they straddle tiles
  // (at most 4 entries each), surely fit the budget and the pool.
  bool room_for(uint32_t items, uint32_t points) const {
    const uint64_t end = item_end_ + uint64_t{items} * item_bytes_;
    return points <= config_.max_points - count_ && (items == 0 || end <= item_allow_) &&
           (end + chunk_bytes_ - 1) / chunk_bytes_ + 4 + (uint64_t{4} * points >> kChunkLog2) +
                   2 * static_cast<uint64_t>(tiles_x_ * tiles_y_) <= free_chunk_;
  }
  static constexpr uint32_t kNoLink = 0xFFFFFFFFu;
  // A tile's filed items: first link, then next_link(link) until kNoLink.
  // A link is the index of the word, counted from item_words(0), that
  // holds the next: item_of(link) is link / (item_words + kItemLinks).
  uint32_t first_link(uint32_t tile) const { return tile_items_[tile]; }
  uint32_t next_link(uint32_t link) const { return items_[link]; }
  uint32_t item_of(uint32_t link) const { return link / item_stride_; }
  // The most items a frame can hold (point_raster_items).
  uint32_t item_capacity() const { return item_capacity_; }

  // Called once per tile during draw, after its binned points, with the
  // tile's depth+colour words (2^tile_log2 a row; uint32_t for RGB565,
  // uint64_t for RGB888: pack_word's) for its filed items to be drawn into.
  using TileFn = void (*)(void* context, uint32_t tile, int px0, int py0, void* words);

  // Draws the binned points over `clear_rgb` into `frame` (height rows of
  // `stride` bytes, pixels in the configured format, little-endian RGB565).
  // With `coverage`, also writes which pixels a point covered: one bit a
  // pixel, LSB first, rows of (width + 7) / 8 bytes (raster/resolve.h).
  // `tile_fn` is called for the tiles that hold items, or with
  // `every_tile` for every tile (the renderer's close-ups, which span many).
  void draw(uint32_t clear_rgb, uint8_t* frame, size_t stride, uint8_t* coverage = nullptr, TileFn tile_fn = nullptr,
            void* context = nullptr, bool every_tile = false) const;

  uint32_t points() const { return count_; }
  // Bytes of one binned square: 8 for RGB565 frames, 12 for RGB888.
  static size_t entry_bytes(PixelFormat format);
  const RasterConfig& config() const { return config_; }
  int tiles_x() const { return tiles_x_; }

 private:
  static constexpr uint32_t kChunkLog2 = 6;  // 64 entries a chunk
  // A binned square: its tile word, its covered width | height << 4 (1..3
  // each, within the tile) and its first pixel, (y << tile_log2) + x within
  // the tile. RGB565 frames keep the 32-bit word itself (8 bytes an entry),
  // RGB888 frames the depth and the colour (12).
  struct Entry565 {
    uint32_t word;
    uint32_t offset_wh;  // offset | wh << 24
    uint32_t tile_word() const { return word; }
    uint32_t wh() const { return offset_wh >> 24; }
    uint32_t offset() const { return offset_wh & 0xFFFFFFu; }
  };
  struct Entry888 {
    uint32_t depth;
    uint32_t color_wh;  // colour | wh << 24
    uint32_t offset_;
    uint64_t tile_word() const { return pack_word<uint64_t>(depth, color_wh); }
    uint32_t wh() const { return color_wh >> 24; }
    uint32_t offset() const { return offset_; }
  };
  template <class Word>
  using EntryOf = typename std::conditional<sizeof(Word) == 4, Entry565, Entry888>::type;
  // Files a square of colour `rgb` (0xRRGGBB) in `tile`'s bins as the frame format's entry.
  void push(uint32_t tile, uint32_t depth, uint32_t rgb, uint32_t wh, uint32_t offset) {
    const uint32_t fill = tile_fill_[tile];
    if ((fill & ((1u << kChunkLog2) - 1)) == 0) {  // the tile's chunk is full (or it has none)
      const uint32_t c = --free_chunk_;
      if (fill == 0) tile_head_[tile] = c;
      else chunk_next_[tile_tail_[tile]] = c;
      tile_tail_[tile] = c;
    }
    const uint32_t at = (tile_tail_[tile] << kChunkLog2) + (fill & ((1u << kChunkLog2) - 1));
    if (config_.format == PixelFormat::kRgb565)
      static_cast<Entry565*>(entries_)[at] = Entry565{pack_word<uint32_t>(depth, rgb565(rgb)), offset | wh << 24};
    else
      static_cast<Entry888*>(entries_)[at] = Entry888{depth, (rgb & 0xFFFFFFu) | wh << 24, offset};
    tile_fill_[tile] = fill + 1;
  }
  void split(int32_t x0, int32_t y0, int32_t x1, int32_t y1, uint32_t depth, uint32_t rgb);
  // Items of `bytes` and `points` more: the items' end, the chunks they
  // reach into and the bytes they may reach.
  void grow_items(uint32_t bytes, uint32_t points) {
    item_end_ += bytes;
    while (floor_ * chunk_bytes_ < item_end_) ++floor_;
    item_points_ += points;
    item_allow_ = dedicated_bytes_ + ((item_points_ + item_points_ / 4) >> kChunkLog2) * chunk_bytes_;
  }
  template <class Word>
  void draw_tiles(uint32_t clear_rgb, uint8_t* frame, size_t stride, uint8_t* coverage, TileFn tile_fn,
                  void* context, bool every_tile) const;

  RasterConfig config_{};
  int tiles_x_ = 0, tiles_y_ = 0;
  // The pool: chunk_count_ chunks of 64 Entry565 or Entry888, taken from
  // the top (free_chunk_: the lowest in use), the items from the bottom
  // (floor_: the chunks they reach into).
  void* entries_ = nullptr;
  uint32_t* items_ = nullptr;      // the pool as words: item i at i * item_stride_
  uint32_t* chunk_next_ = nullptr; // per chunk
  uint32_t* tile_head_ = nullptr;  // per tile: first and last chunk, entries
  uint32_t* tile_tail_ = nullptr;
  uint32_t* tile_fill_ = nullptr;
  void* tile_words_ = nullptr;     // one tile of depth+colour words
  uint32_t* tile_items_ = nullptr; // per tile: its last filed item's link
  uint32_t count_ = 0, free_chunk_ = 0, chunk_count_ = 0, floor_ = 0;
  // The pool is at most 2 GiB, and the points at most 2^26: every byte
  // count below, and item_points_ * 5/4, fits 32 bits.
  uint32_t item_count_ = 0, item_points_ = 0, item_end_ = 0, item_allow_ = 0;
  uint32_t item_stride_ = 0, item_capacity_ = 0, item_bytes_ = 0, chunk_bytes_ = 0;
  uint32_t dedicated_bytes_ = 0;  // max_nodes items' chunks
};

}  // namespace stipple
