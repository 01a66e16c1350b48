// stipple raster — tile-based z-buffer point rasterizer. See point_raster.h.
#include "raster/point_raster.h"

namespace stipple {
namespace {

constexpr size_t align8(size_t n) { return (n + 7) & ~size_t{7}; }

struct Layout {
  size_t points, tile_start, tile_count, tile_fill, tile_index, tile_words, total;
};

// Tile-index entries: one per point plus a quarter for points on tile edges
// (a point of s <= 3 px straddles an edge of a 2^k-pixel tile with
// probability about 2 (s - 1) / 2^k; at 32 px and s = 2, 6 %).
uint32_t tile_entries(const RasterConfig& c) { return c.max_points + c.max_points / 4 + 3; }

bool valid(const RasterConfig& c) {
  return c.width > 0 && c.height > 0 && c.tile_log2 >= 3 && c.tile_log2 <= 7 && c.max_points > 0 &&
         c.max_points <= (1u << 26);
}

Layout layout_of(const RasterConfig& c, size_t binned_size) {
  const size_t tile = size_t{1} << c.tile_log2;
  const size_t tiles = ((c.width + tile - 1) >> c.tile_log2) * ((c.height + tile - 1) >> c.tile_log2);
  const size_t word = c.format == PixelFormat::kRgb565 ? 4 : 8;
  Layout l{};
  size_t at = 0;
  l.points = at;
  at += align8(binned_size * c.max_points);
  l.tile_start = at;
  at += align8(4 * tiles);
  l.tile_count = at;
  at += align8(4 * tiles);
  l.tile_fill = at;
  at += align8(4 * tiles);
  l.tile_index = at;
  at += align8(4 * size_t{tile_entries(c)});
  l.tile_words = at;
  at += align8(word * tile * tile);
  l.total = at;
  return l;
}

template <class Word>
constexpr Word pack(uint32_t depth, uint32_t rgb);
template <>
constexpr uint32_t pack<uint32_t>(uint32_t depth, uint32_t rgb) {
  return (depth & 0xFFFF0000u) | rgb565(rgb);
}
template <>
constexpr uint64_t pack<uint64_t>(uint32_t depth, uint32_t rgb) {
  return (static_cast<uint64_t>(depth) << 32) | (rgb & 0xFFFFFFu);
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

}  // namespace

size_t point_raster_bytes(const RasterConfig& config) {
  return valid(config) ? layout_of(config, sizeof(uint32_t) * 3).total : 0;
}

RasterStatus PointRaster::init(const RasterConfig& config, void* arena, size_t bytes) {
  static_assert(sizeof(Binned) == 12, "Binned is sized into point_raster_bytes");
  if (!valid(config)) return RasterStatus::kBadConfig;
  const Layout l = layout_of(config, sizeof(Binned));
  if (bytes < l.total) return RasterStatus::kArenaTooSmall;
  config_ = config;
  tiles_x_ = (config.width + (1 << config.tile_log2) - 1) >> config.tile_log2;
  tiles_y_ = (config.height + (1 << config.tile_log2) - 1) >> config.tile_log2;
  uint8_t* base = static_cast<uint8_t*>(arena);
  points_ = reinterpret_cast<Binned*>(base + l.points);
  tile_start_ = reinterpret_cast<uint32_t*>(base + l.tile_start);
  tile_count_ = reinterpret_cast<uint32_t*>(base + l.tile_count);
  tile_fill_ = reinterpret_cast<uint32_t*>(base + l.tile_fill);
  tile_index_ = reinterpret_cast<uint32_t*>(base + l.tile_index);
  tile_words_ = base + l.tile_words;
  bin_capacity_ = tile_entries(config);
  begin_frame();
  return RasterStatus::kOk;
}

void PointRaster::begin_frame() {
  count_ = 0;
  bins_ = 0;
  for (int t = 0; t < tiles_x_ * tiles_y_; ++t) tile_count_[t] = 0;
}

bool PointRaster::add(const ScreenPoint& p, int size_px) {
  if (count_ >= config_.max_points) return false;
  const int s = size_px < 1 ? 1 : size_px > 3 ? 3 : size_px;
  // First covered pixel: floor(x - (s - 1) / 2) with x in Q4; arithmetic shift floors.
  int32_t x0 = (p.x_q4 - (s - 1) * 8) >> 4, y0 = (p.y_q4 - (s - 1) * 8) >> 4;
  int32_t x1 = x0 + s, y1 = y0 + s;  // exclusive
  if (x1 <= 0 || y1 <= 0 || x0 >= config_.width || y0 >= config_.height) return true;  // off screen
  if (x0 < 0) x0 = 0;
  if (y0 < 0) y0 = 0;
  if (x1 > config_.width) x1 = config_.width;
  if (y1 > config_.height) y1 = config_.height;
  const int sh = config_.tile_log2;
  const int tx0 = x0 >> sh, tx1 = (x1 - 1) >> sh, ty0 = y0 >> sh, ty1 = (y1 - 1) >> sh;
  const uint32_t entries = static_cast<uint32_t>((tx1 - tx0 + 1) * (ty1 - ty0 + 1));
  if (bins_ + entries > bin_capacity_) return false;
  points_[count_++] = Binned{static_cast<uint16_t>(x0), static_cast<uint16_t>(y0), p.depth,
                             (p.rgb & 0xFFFFFFu) | static_cast<uint32_t>(x1 - x0) << 24 | static_cast<uint32_t>(y1 - y0) << 28};
  for (int ty = ty0; ty <= ty1; ++ty)
    for (int tx = tx0; tx <= tx1; ++tx) ++tile_count_[ty * tiles_x_ + tx];
  bins_ += entries;
  return true;
}

void PointRaster::draw(uint32_t clear_rgb, uint8_t* frame, size_t stride) const {
  if (config_.format == PixelFormat::kRgb565) draw_tiles<uint32_t>(clear_rgb, frame, stride);
  else draw_tiles<uint64_t>(clear_rgb, frame, stride);
}

template <class Word>
void PointRaster::draw_tiles(uint32_t clear_rgb, uint8_t* frame, size_t stride) const {
  const int tiles = tiles_x_ * tiles_y_;
  const int sh = config_.tile_log2, tile = 1 << sh;
  // Group point indices by tile (counting sort; order within a tile is the
  // insertion order, though the packed-word minimum makes order irrelevant).
  uint32_t at = 0;
  for (int t = 0; t < tiles; ++t) {
    tile_start_[t] = at;
    tile_fill_[t] = at;
    at += tile_count_[t];
  }
  for (uint32_t i = 0; i < count_; ++i) {
    const Binned& b = points_[i];
    const int w = static_cast<int>((b.rgb_wh >> 24) & 15u), h = static_cast<int>(b.rgb_wh >> 28);
    for (int ty = b.y0 >> sh; ty <= (b.y0 + h - 1) >> sh; ++ty)
      for (int tx = b.x0 >> sh; tx <= (b.x0 + w - 1) >> sh; ++tx) tile_index_[tile_fill_[ty * tiles_x_ + tx]++] = i;
  }
  Word* words = static_cast<Word*>(tile_words_);
  const Word clear = pack<Word>(0xFFFFFFFFu, clear_rgb);
  const int bpp = bytes_per_pixel(config_.format);
  for (int ty = 0; ty < tiles_y_; ++ty) {
    for (int tx = 0; tx < tiles_x_; ++tx) {
      const int t = ty * tiles_x_ + tx;
      const int px0 = tx << sh, py0 = ty << sh;
      const int pw = (px0 + tile > config_.width ? config_.width - px0 : tile);
      const int ph = (py0 + tile > config_.height ? config_.height - py0 : tile);
      for (int i = 0; i < tile * tile; ++i) words[i] = clear;
      for (uint32_t k = tile_start_[t]; k < tile_start_[t] + tile_count_[t]; ++k) {
        const Binned& b = points_[tile_index_[k]];
        const Word w = pack<Word>(b.depth, b.rgb_wh & 0xFFFFFFu);
        const int bw = static_cast<int>((b.rgb_wh >> 24) & 15u), bh = static_cast<int>(b.rgb_wh >> 28);
        // Only the pixels of this tile: each pixel belongs to exactly one tile.
        const int xa = b.x0 > px0 ? b.x0 : px0, xb = b.x0 + bw < px0 + pw ? b.x0 + bw : px0 + pw;
        const int ya = b.y0 > py0 ? b.y0 : py0, yb = b.y0 + bh < py0 + ph ? b.y0 + bh : py0 + ph;
        for (int y = ya; y < yb; ++y) {
          Word* row = words + ((y - py0) << sh);
          for (int x = xa; x < xb; ++x)
            if (w < row[x - px0]) row[x - px0] = w;
        }
      }
      for (int y = 0; y < ph; ++y) {
        uint8_t* out = frame + static_cast<size_t>(py0 + y) * stride + static_cast<size_t>(px0) * bpp;
        const Word* row = words + (y << sh);
        for (int x = 0; x < pw; ++x, out += bpp) store(out, row[x]);
      }
    }
  }
}

}  // namespace stipple
