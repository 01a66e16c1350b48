// stipple raster — the screen-space resolve. See resolve.h.
#include "raster/resolve.h"

namespace stipple {
namespace {

// A pixel as four 16-bit lanes — covered count, R, G, B — so a 3 x 3 sum of
// nine is nine additions (each lane stays below 9 x 255).
using Lanes = uint64_t;
constexpr Lanes kCovered = Lanes{1} << 48;

constexpr Lanes lanes_of(uint32_t rgb) {
  return kCovered | (Lanes{(rgb >> 16) & 255u} << 32) | (Lanes{(rgb >> 8) & 255u} << 16) | (rgb & 255u);
}
constexpr uint32_t count_of(Lanes v) { return static_cast<uint32_t>(v >> 48); }

// 2^16 / n rounded, n = 1..9: (sum * r + 2^15) >> 16 is sum / n rounded for
// every sum a block of n 8-bit values can have.
constexpr uint32_t kReciprocal[10] = {0, 65536, 32768, 21845, 16384, 13107, 10923, 9362, 8192, 7282};

// The mean colour of a sum of `count_of(sum)` pixels, as 0xRRGGBB.
inline uint32_t mean_rgb(Lanes sum) {
  const uint32_t r = kReciprocal[count_of(sum)];
  const uint32_t cr = static_cast<uint32_t>(sum >> 32) & 0xFFFFu, cg = static_cast<uint32_t>(sum >> 16) & 0xFFFFu,
                 cb = static_cast<uint32_t>(sum) & 0xFFFFu;
  return (((cr * r + 32768u) >> 16) << 16) | (((cg * r + 32768u) >> 16) << 8) | ((cb * r + 32768u) >> 16);
}

// The columns [lo, hi) of a row that can hold covered pixels; every lane
// outside is zero.
struct Span {
  uint32_t lo = 0, hi = 0;
};

void clear(Lanes* row, Span& s) {
  for (uint32_t x = s.lo; x < s.hi; ++x) row[x] = 0;
  s = Span{};
}

// A row as drawn, within the span of its coverage bits.
Span load_row(const uint8_t* in, const uint8_t* bits, PixelFormat format, uint16_t width, Lanes* out) {
  const uint32_t bytes = (width + 7u) / 8u;
  uint32_t first = 0, last = bytes;
  while (first < bytes && bits[first] == 0) ++first;
  if (first == bytes) return Span{};
  while (bits[last - 1] == 0) --last;
  const uint32_t lo = 8 * first, hi = 8 * last < width ? 8 * last : width;
  for (uint32_t x = lo; x < hi; ++x) {
    if (((bits[x >> 3] >> (x & 7)) & 1u) == 0) {
      out[x] = 0;
      continue;
    }
    const uint32_t rgb = format == PixelFormat::kRgb565
                             ? rgb888_from_565(static_cast<uint16_t>(in[2 * x] | (in[2 * x + 1] << 8)))
                             : (uint32_t{in[3 * x]} << 16) | (uint32_t{in[3 * x + 1]} << 8) | in[3 * x + 2];
    out[x] = lanes_of(rgb);
  }
  return Span{lo, hi};
}

// Step 1 for columns [lo, hi) of one row: `up`, `mid`, `down` as drawn
// (the empty row beyond the frame).
void fill_row(const Lanes* up, const Lanes* mid, const Lanes* down, uint32_t lo, uint32_t hi, uint16_t width, Lanes* out) {
  Lanes left = lo > 0 ? up[lo - 1] + mid[lo - 1] + down[lo - 1] : 0, here = up[lo] + mid[lo] + down[lo];
  for (uint32_t x = lo; x < hi; ++x) {
    const Lanes right = x + 1 < width ? up[x + 1] + mid[x + 1] + down[x + 1] : 0;
    if (mid[x] != 0) {
      out[x] = mid[x];
    } else {
      const Lanes around = left + here + right;  // the centre is empty
      out[x] = count_of(around) >= 6 ? lanes_of(mean_rgb(around)) : 0;
    }
    left = here;
    here = right;
  }
}

// Steps 2 and 3 for columns [lo, hi) of one row, from the filled rows; `up`
// or `down` is null at the frame's top or bottom. A pixel is kept when every
// pixel of its 3 x 3 block inside the frame is covered — the covered count
// of the block equals the block's size there (9 inside, 6 on an edge, 4 in
// a corner: beyond the frame counts as covered) — or when it is part of an
// isolated speck, and then takes the mean of its block's covered pixels. Pixels outside [lo, hi) are uncovered in `mid`, so the frame already
// holds the clear colour there.
void blend_row(const Lanes* up, const Lanes* mid, const Lanes* down, const Lanes* empty, PixelFormat format,
               uint32_t lo, uint32_t hi, uint16_t width, uint32_t clear_rgb, uint8_t* out) {
  const Lanes* u = up ? up : empty;
  const Lanes* d = down ? down : empty;
  const uint32_t rows = 1u + (up != nullptr) + (down != nullptr);
  const uint16_t clear565 = rgb565(clear_rgb);
  Lanes left = lo > 0 ? u[lo - 1] + mid[lo - 1] + d[lo - 1] : 0, here = u[lo] + mid[lo] + d[lo];
  for (uint32_t x = lo; x < hi; ++x) {
    const Lanes right = x + 1 < width ? u[x + 1] + mid[x + 1] + d[x + 1] : 0;
    const Lanes block = left + here + right;
    const uint32_t columns = 1u + (x > 0) + (x + 1 < width);
    // Kept: a pixel inside the surface (its whole block covered), or one of
    // an isolated speck (at most 3 covered neighbours): a node seen closer
    // than its points cover stays as dots instead of vanishing.
    const uint32_t n = count_of(block);
    const bool keep = mid[x] != 0 && (n == rows * columns || (rows * columns == 9 && n <= 4));
    if (format == PixelFormat::kRgb565) {
      const uint16_t v = keep ? rgb565(mean_rgb(block)) : clear565;
      out[2 * x] = static_cast<uint8_t>(v);
      out[2 * x + 1] = static_cast<uint8_t>(v >> 8);
    } else {
      const uint32_t rgb = keep ? mean_rgb(block) : clear_rgb;
      out[3 * x] = static_cast<uint8_t>(rgb >> 16);
      out[3 * x + 1] = static_cast<uint8_t>(rgb >> 8);
      out[3 * x + 2] = static_cast<uint8_t>(rgb);
    }
    left = here;
    here = right;
  }
}

}  // namespace

void resolve_frame(uint8_t* frame, size_t stride, PixelFormat format, uint16_t width, uint16_t height,
                   const uint8_t* coverage, uint32_t clear_rgb, void* scratch) {
  Lanes* rows = static_cast<Lanes*>(scratch);
  Lanes* drawn[3] = {rows, rows + width, rows + 2 * size_t{width}};
  Lanes* filled[3] = {rows + 3 * size_t{width}, rows + 4 * size_t{width}, rows + 5 * size_t{width}};
  Lanes* empty = rows + 6 * size_t{width};
  Span drawn_span[3], filled_span[3];
  for (int k = 0; k < 3; ++k) {
    drawn_span[k] = filled_span[k] = Span{0, width};
    clear(drawn[k], drawn_span[k]);
    clear(filled[k], filled_span[k]);
  }
  for (uint32_t x = 0; x < width; ++x) empty[x] = 0;
  const Span none;
  const size_t cov_stride = coverage_row_bytes(width);
  // Row y is read at step y, filled at step y + 1 and written at step y + 2,
  // so the frame can be rewritten in place behind the ring. Only the columns
  // that can hold covered pixels are visited: a row's fill spans its and
  // its neighbours' drawn columns and one more each side; its blend spans
  // its filled columns.
  for (int32_t y = 0; y < int32_t{height} + 2; ++y) {
    if (y < height) {
      clear(drawn[y % 3], drawn_span[y % 3]);
      drawn_span[y % 3] = load_row(frame + size_t(y) * stride, coverage + size_t(y) * cov_stride, format, width, drawn[y % 3]);
    }
    const int32_t f = y - 1;
    if (f >= 0 && f < height) {
      const Span& a = f > 0 ? drawn_span[(f - 1) % 3] : none;
      const Span& b = drawn_span[f % 3];
      const Span& c = f + 1 < height ? drawn_span[(f + 1) % 3] : none;
      uint32_t lo = width, hi = 0;
      const Span* spans[3] = {&a, &b, &c};
      for (const Span* s : spans)
        if (s->lo < s->hi) {
          lo = s->lo < lo ? s->lo : lo;
          hi = s->hi > hi ? s->hi : hi;
        }
      clear(filled[f % 3], filled_span[f % 3]);
      if (lo < hi) {
        lo = lo > 0 ? lo - 1 : 0;
        hi = hi < width ? hi + 1 : width;
        fill_row(f > 0 ? drawn[(f - 1) % 3] : empty, drawn[f % 3], f + 1 < height ? drawn[(f + 1) % 3] : empty, lo, hi,
                 width, filled[f % 3]);
        filled_span[f % 3] = Span{lo, hi};
      }
    }
    const int32_t b = y - 2;
    if (b >= 0 && filled_span[b % 3].lo < filled_span[b % 3].hi)
      blend_row(b > 0 ? filled[(b - 1) % 3] : nullptr, filled[b % 3], b + 1 < height ? filled[(b + 1) % 3] : nullptr,
                empty, format, filled_span[b % 3].lo, filled_span[b % 3].hi, width, clear_rgb, frame + size_t(b) * stride);
  }
}

}  // namespace stipple
