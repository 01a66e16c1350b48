// stipple raster — tile-based z-buffer point rasterizer. See point_raster.h.
#include "raster/point_raster.h"

#include <cstring>

#include "core/arena.h"
#include "raster/point_kernel_avx2.h"

namespace stipple {
namespace {

constexpr uint32_t kChunk = 64;

struct Layout {
  size_t entries, chunk_next, tile_head, tile_tail, tile_fill, tile_words, tile_items, total;
  uint32_t chunks, dedicated;  // chunks in the pool; of them, max_nodes items'
};

bool valid(const RasterConfig& c) {
  return c.width > 0 && c.height > 0 && c.tile_log2 >= 3 && c.tile_log2 <= 7 && c.max_points > 0 &&
         c.max_points <= (1u << 26) && c.max_nodes <= (1u << 26) && c.item_words <= 256 &&
         (c.max_nodes == 0 || c.item_words > 0);
}

uint32_t tile_count(const RasterConfig& c) {
  const uint32_t tile = 1u << c.tile_log2;
  return ((c.width + tile - 1) >> c.tile_log2) * ((c.height + tile - 1) >> c.tile_log2);
}

size_t item_bytes(const RasterConfig& c) { return size_t{4} * (c.item_words + PointRaster::kItemLinks); }

// Entries: one per binned point plus a quarter for points on tile edges (a point of
// s <= 3 px straddles an edge of a 2^k-pixel tile with probability about
// 2 (s - 1) / 2^k: 6 % at 32 px and s = 2), in chunks of 64, plus one
// partial chunk per tile and the 4 that `add` keeps in reserve; then
// max_nodes items in whole chunks.
Layout layout_of(const RasterConfig& c, size_t entry_size) {
  const size_t tiles = tile_count(c);
  const size_t word = c.format == PixelFormat::kRgb565 ? 4 : 8;
  const uint64_t entries = uint64_t{c.max_points} + c.max_points / 4;
  const uint64_t chunk_bytes = entry_size * kChunk;
  const uint64_t dedicated = (uint64_t{c.max_nodes} * item_bytes(c) + chunk_bytes - 1) / chunk_bytes;
  const uint64_t chunks = (entries + kChunk - 1) / kChunk + tiles + 4 + dedicated;
  Layout l{};
  if (chunks * chunk_bytes > (uint64_t{1} << 31)) return l;  // a pool beyond 2 GiB: entries and items index in 32 bits
  l.dedicated = static_cast<uint32_t>(dedicated);
  l.chunks = static_cast<uint32_t>(chunks);
  size_t at = 0;
  l.entries = at;
  at += align8(entry_size * kChunk * l.chunks);
  l.chunk_next = at;
  at += align8(4 * size_t{l.chunks});
  l.tile_head = at;
  at += align8(4 * tiles);
  l.tile_tail = at;
  at += align8(4 * tiles);
  l.tile_fill = at;
  at += align8(4 * tiles);
  l.tile_words = at;
  at += align8(word << (2 * c.tile_log2));
  l.tile_items = at;
  at += c.max_nodes ? align8(4 * tiles) : 0;
  l.total = at;
  return l;
}

// The items the whole pool would hold (none without max_nodes): what
// point_raster_items reports and PointRaster::init keeps.
uint32_t items_in(const RasterConfig& c, const Layout& l, size_t entry_size) {
  return c.max_nodes ? static_cast<uint32_t>(uint64_t{l.chunks} * entry_size * kChunk / item_bytes(c)) : 0;
}

void store(uint8_t* p, uint32_t word) {  // RGB565, little-endian
  p[0] = static_cast<uint8_t>(word);
  p[1] = static_cast<uint8_t>(word >> 8);
}
void store(uint8_t* p, uint64_t word) {  // RGB888
  p[0] = static_cast<uint8_t>(word >> 16);
  p[1] = static_cast<uint8_t>(word >> 8);
  p[2] = static_cast<uint8_t>(word);
}

// A row of tile words as pixels. RGB565: two pixels a 32-bit store where
// the row is so aligned (a 32-bit handheld's frame buffer), the same bytes.
void store_row(const uint32_t* row, int pixels, uint8_t* out) {
  int x = 0;
  if ((reinterpret_cast<uintptr_t>(out) & 1) != 0) {  // a frame at an odd address: a pixel at a time
    for (; x < pixels; ++x, out += 2) store(out, row[x]);
    return;
  }
  if ((reinterpret_cast<uintptr_t>(out) & 3) != 0 && pixels > 0) store(out, row[x++]), out += 2;
  // Four pixels a pass, then two, then one: the loop's count and branch
  // once for two stores (on ARMv5 3.5 instructions a pixel, not 4.5).
  const auto two = [](const uint32_t* p) { return (p[0] & 0xFFFFu) | p[1] << 16; };  // little-endian: the first pixel's bytes first
  const uint32_t* p = row + x;
  for (const uint32_t* end = p + ((pixels - x) & ~3); p != end; p += 4, out += 8) {
    const uint32_t pair[2] = {two(p), two(p + 2)};
    std::memcpy(__builtin_assume_aligned(out, 4), pair, 8);
  }
  x = static_cast<int>(p - row);
  if (x + 2 <= pixels) {  // fewer than four left: at most one pair
    const uint32_t pair = two(row + x);
    std::memcpy(__builtin_assume_aligned(out, 4), &pair, 4);
    x += 2, out += 4;
  }
  if (x < pixels) store(out, row[x]);
}
void store_row(const uint64_t* row, int pixels, uint8_t* out) {
  for (int x = 0; x < pixels; ++x, out += 3) store(out, row[x]);
}

// A tile's words set to `clear`, 8 a pass (a tile's count, 2^(2 tile_log2)
// with tile_log2 >= 3, is a multiple of 64): on ARMv5 11 instructions for
// 8 words, where a word a pass took 4 a word.
template <class Word>
void fill_words(Word* words, int count, Word clear) {
  for (Word *w = words, *end = words + count; w != end; w += 8) {
    w[0] = clear, w[1] = clear, w[2] = clear, w[3] = clear;
    w[4] = clear, w[5] = clear, w[6] = clear, w[7] = clear;
  }
}

}  // namespace

size_t PointRaster::entry_bytes(PixelFormat format) {
  return format == PixelFormat::kRgb565 ? sizeof(Entry565) : sizeof(Entry888);
}

size_t point_raster_bytes(const RasterConfig& config) {
  return valid(config) ? layout_of(config, PointRaster::entry_bytes(config.format)).total : 0;
}

uint32_t point_raster_items(const RasterConfig& config) {
  if (!valid(config)) return 0;
  const size_t entry = PointRaster::entry_bytes(config.format);
  return items_in(config, layout_of(config, entry), entry);
}

RasterStatus PointRaster::init(const RasterConfig& config, void* arena, size_t bytes) {
  static_assert(sizeof(Entry565) == 8 && sizeof(Entry888) == 12, "entries are sized into point_raster_bytes");
  if (!valid(config)) return RasterStatus::kBadConfig;
  const Layout l = layout_of(config, entry_bytes(config.format));
  if (l.total == 0) return RasterStatus::kBadConfig;
  if (bytes < l.total) return RasterStatus::kArenaTooSmall;
  config_ = config;
  tiles_x_ = (config.width + (1 << config.tile_log2) - 1) >> config.tile_log2;
  tiles_y_ = (config.height + (1 << config.tile_log2) - 1) >> config.tile_log2;
  uint8_t* base = static_cast<uint8_t*>(arena);
  entries_ = base + l.entries;
  items_ = reinterpret_cast<uint32_t*>(base + l.entries);
  chunk_next_ = reinterpret_cast<uint32_t*>(base + l.chunk_next);
  tile_head_ = reinterpret_cast<uint32_t*>(base + l.tile_head);
  tile_tail_ = reinterpret_cast<uint32_t*>(base + l.tile_tail);
  tile_fill_ = reinterpret_cast<uint32_t*>(base + l.tile_fill);
  tile_words_ = base + l.tile_words;
  tile_items_ = config.max_nodes ? reinterpret_cast<uint32_t*>(base + l.tile_items) : nullptr;
  chunk_count_ = l.chunks;
  chunk_bytes_ = static_cast<uint32_t>(entry_bytes(config.format) * kChunk);
  item_bytes_ = static_cast<uint32_t>(item_bytes(config));
  item_stride_ = config.item_words + kItemLinks;
  dedicated_bytes_ = l.dedicated * chunk_bytes_;  // 0 without items
  item_capacity_ = items_in(config, l, entry_bytes(config.format));
  begin_frame();
  return RasterStatus::kOk;
}

void PointRaster::begin_frame() {
  count_ = 0;
  free_chunk_ = chunk_count_;
  floor_ = 0;
  item_count_ = 0;
  item_points_ = 0;
  item_end_ = 0;
  item_allow_ = dedicated_bytes_;
  for (int t = 0; t < tiles_x_ * tiles_y_; ++t) tile_fill_[t] = 0;
  if (tile_items_)
    for (int t = 0; t < tiles_x_ * tiles_y_; ++t) tile_items_[t] = kNoLink;
}

// A point on tile edges or the screen's: clipped to the screen, then one
// entry per tile it touches, clipped to that tile.
void PointRaster::split(int32_t x0, int32_t y0, int32_t x1, int32_t y1, uint32_t depth, uint32_t rgb) {
  if (x0 < 0) x0 = 0;
  if (y0 < 0) y0 = 0;
  if (x1 > config_.width) x1 = config_.width;
  if (y1 > config_.height) y1 = config_.height;
  const int sh = config_.tile_log2;
  for (int ty = y0 >> sh; ty <= (y1 - 1) >> sh; ++ty) {
    const int ya = y0 > (ty << sh) ? y0 : ty << sh, yb = y1 < ((ty + 1) << sh) ? y1 : (ty + 1) << sh;
    for (int tx = x0 >> sh; tx <= (x1 - 1) >> sh; ++tx) {
      const int xa = x0 > (tx << sh) ? x0 : tx << sh, xb = x1 < ((tx + 1) << sh) ? x1 : (tx + 1) << sh;
      push(static_cast<uint32_t>(ty * tiles_x_ + tx), depth, rgb, static_cast<uint32_t>((xb - xa) | (yb - ya) << 4),
           static_cast<uint32_t>(((ya - (ty << sh)) << sh) | (xa - (tx << sh))));
    }
  }
}

void PointRaster::draw(uint32_t clear_rgb, uint8_t* frame, size_t stride, uint8_t* coverage, TileFn tile_fn,
                       void* context, bool every_tile) const {
  if (config_.format == PixelFormat::kRgb565)
    draw_tiles<uint32_t>(rgb565(clear_rgb), frame, stride, coverage, tile_fn, context, every_tile);
  else
    draw_tiles<uint64_t>(clear_rgb & 0xFFFFFFu, frame, stride, coverage, tile_fn, context, every_tile);
}

template <class Word>
void PointRaster::draw_tiles(uint32_t clear_color, uint8_t* frame, size_t stride, uint8_t* coverage, TileFn tile_fn,
                             void* context, bool every_tile) const {
  const int sh = config_.tile_log2, tile = 1 << sh;
  Word* words = static_cast<Word*>(tile_words_);
  const Word clear = pack_word<Word>(0xFFFFFFFFu, clear_color);
  const int bpp = bytes_per_pixel(config_.format);
  const bool wide = avx2::kBuilt && config_.avx2;
  for (int ty = 0; ty < tiles_y_; ++ty) {
    for (int tx = 0; tx < tiles_x_; ++tx) {
      const int t = ty * tiles_x_ + tx;
      const int px0 = tx << sh, py0 = ty << sh;
      const int pw = (px0 + tile > config_.width ? config_.width - px0 : tile);
      const int ph = (py0 + tile > config_.height ? config_.height - py0 : tile);
      const bool items = (tile_items_ != nullptr && tile_items_[t] != kNoLink) || every_tile;
      if (tile_fill_[t] == 0 && !(items && tile_fn != nullptr)) {
        // Nothing drawn here: every row the clear colour (one row of clear
        // words written out), no coverage.
        for (int x = 0; x < pw; ++x) words[x] = clear;
        for (int y = 0; y < ph; ++y) {
          uint8_t* out = frame + static_cast<size_t>(py0 + y) * stride + static_cast<size_t>(px0) * bpp;
          if constexpr (avx2::kBuilt) {
            if (wide) avx2::store_row(words, pw, out);
          }
          if (!wide) store_row(words, pw, out);
        }
        if (coverage != nullptr) {
          const size_t row_bytes = (size_t{config_.width} + 7) / 8;
          for (int y = 0; y < ph; ++y)
            for (int x = 0; x < pw; x += 8) coverage[static_cast<size_t>(py0 + y) * row_bytes + ((px0 + x) >> 3)] = 0;
        }
        continue;
      }
      if constexpr (avx2::kBuilt) {
        if (wide) avx2::clear_words(words, size_t{1} << (2 * sh), clear);
      }
      if (!wide) fill_words(words, tile * tile, clear);
      const uint32_t fill = tile_fill_[t];
      uint32_t chunk = tile_head_[t];
      for (uint32_t k = 0; k < fill; ++k) {
        if (k != 0 && (k & (kChunk - 1)) == 0) chunk = chunk_next_[chunk];
        const EntryOf<Word>& e = static_cast<const EntryOf<Word>*>(entries_)[(chunk << kChunkLog2) + (k & (kChunk - 1))];
        ztest_square(words + e.offset(), tile, e.wh(), static_cast<Word>(e.tile_word()));
      }
      if (items && tile_fn != nullptr) tile_fn(context, static_cast<uint32_t>(t), px0, py0, words);
      for (int y = 0; y < ph; ++y) {
        uint8_t* out = frame + static_cast<size_t>(py0 + y) * stride + static_cast<size_t>(px0) * bpp;
        const Word* row = words + (y << sh);
        if constexpr (avx2::kBuilt) {
          if (wide) avx2::store_row(row, pw, out);
        }
        if (!wide) store_row(row, pw, out);
      }
      if (coverage != nullptr) {
        // Covered: the depth is not the clear word's (all ones). Tiles are
        // at least 8 px, so a tile's row starts on a whole byte.
        const size_t row_bytes = (size_t{config_.width} + 7) / 8;
        for (int y = 0; y < ph; ++y) {
          uint8_t* bits = coverage + static_cast<size_t>(py0 + y) * row_bytes + (px0 >> 3);
          const Word* row = words + (y << sh);
          for (int x = 0; x < pw; x += 8) {
            uint32_t b = 0;
            if (fill != 0 || items)  // a tile without points covers nothing
              for (int k = 0; k < 8 && x + k < pw; ++k) b |= static_cast<uint32_t>(word_covered(row[x + k])) << k;
            bits[x >> 3] = static_cast<uint8_t>(b);
          }
        }
      }
    }
  }
}

}  // namespace stipple
