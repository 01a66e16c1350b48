// stipple raster — the screen-space resolve. See resolve.h.
#include "raster/resolve.h"

namespace stipple {
namespace {

// 2^16 / n rounded, n = 1..9: (sum * r + 2^15) >> 16 is sum / n rounded for
// every sum a block of n 8-bit values can have.
constexpr uint32_t kReciprocal[10] = {0, 65536, 32768, 21845, 16384, 13107, 10923, 9362, 8192, 7282};

// A pixel in lanes, so that a 3 x 3 sum of nine is nine additions of one
// integer, and what the resolve needs of such a sum: its covered count and
// its mean colour. RGB888 frames: four 16-bit lanes of a 64-bit word —
// covered count, R, G, B (each below 9 x 255). RGB565 frames: the channels
// as they are stored, in one 32-bit word — count (4 bits), R (9), G (10),
// B (9), each below 9 times its largest value — which on a 32-bit handheld
// is one addition where the 64-bit word is two.
struct Lanes888 {
  using Word = uint64_t;
  static constexpr Word kCovered = Word{1} << 48;
  static constexpr int kBytes = 3;
  static Word of(const uint8_t* p) {
    return kCovered | (Word{p[0]} << 32) | (Word{p[1]} << 16) | p[2];
  }
  static uint32_t count(Word v) { return static_cast<uint32_t>(v >> 48); }
  // The mean colour of a sum of count(sum) pixels, as the frame stores it (0xRRGGBB).
  static uint32_t mean(Word sum) {
    const uint32_t r = kReciprocal[count(sum)];
    const uint32_t cr = static_cast<uint32_t>(sum >> 32) & 0xFFFFu, cg = static_cast<uint32_t>(sum >> 16) & 0xFFFFu,
                   cb = static_cast<uint32_t>(sum) & 0xFFFFu;
    return (((cr * r + 32768u) >> 16) << 16) | (((cg * r + 32768u) >> 16) << 8) | ((cb * r + 32768u) >> 16);
  }
  static Word of_mean(Word sum) {
    const uint32_t c = mean(sum);
    return kCovered | (Word{c >> 16} << 32) | (Word{(c >> 8) & 255u} << 16) | (c & 255u);
  }
  static void store(uint8_t* p, uint32_t c) {
    p[0] = static_cast<uint8_t>(c >> 16);
    p[1] = static_cast<uint8_t>(c >> 8);
    p[2] = static_cast<uint8_t>(c);
  }
  static uint32_t clear(uint32_t rgb) { return rgb & 0xFFFFFFu; }
};
struct Lanes565 {
  using Word = uint32_t;
  static constexpr Word kCovered = Word{1} << 28;
  static constexpr int kBytes = 2;
  static Word of(const uint8_t* p) {
    const uint32_t c = p[0] | uint32_t{p[1]} << 8;
    return kCovered | (c >> 11) << 19 | ((c >> 5) & 63u) << 9 | (c & 31u);
  }
  static uint32_t count(Word v) { return v >> 28; }
  // The mean of a sum of count(sum) pixels, as RGB565 (sums below 2^10, so
  // the products stay below 2^26).
  static uint32_t mean(Word sum) {
    const uint32_t r = kReciprocal[count(sum)];
    const uint32_t cr = (sum >> 19) & 511u, cg = (sum >> 9) & 1023u, cb = sum & 511u;
    return ((cr * r + 32768u) >> 16) << 11 | ((cg * r + 32768u) >> 16) << 5 | ((cb * r + 32768u) >> 16);
  }
  static Word of_mean(Word sum) {
    const uint32_t c = mean(sum);
    return kCovered | (c >> 11) << 19 | ((c >> 5) & 63u) << 9 | (c & 31u);
  }
  static void store(uint8_t* p, uint32_t c) {
    p[0] = static_cast<uint8_t>(c);
    p[1] = static_cast<uint8_t>(c >> 8);
  }
  static uint32_t clear(uint32_t rgb) { return rgb565(rgb); }
};

// The columns [lo, hi) of a row that can hold covered pixels; every lane
// outside is zero.
struct Span {
  uint32_t lo = 0, hi = 0;
};

template <class L>
void clear(typename L::Word* row, Span& s) {
  for (uint32_t x = s.lo; x < s.hi; ++x) row[x] = 0;
  s = Span{};
}

// A row as drawn, within the span of its coverage bits.
template <class L>
Span load_row(const uint8_t* in, const uint8_t* bits, uint16_t width, typename L::Word* out) {
  const uint32_t bytes = (width + 7u) / 8u;
  uint32_t first = 0, last = bytes;
  while (first < bytes && bits[first] == 0) ++first;
  if (first == bytes) return Span{};
  while (bits[last - 1] == 0) --last;
  const uint32_t lo = 8 * first, hi = 8 * last < width ? 8 * last : width;
  for (uint32_t x = lo; x < hi; ++x)
    out[x] = ((bits[x >> 3] >> (x & 7)) & 1u) ? L::of(in + L::kBytes * x) : 0;
  return Span{lo, hi};
}

// Step 1 for columns [lo, hi) of one row: `up`, `mid`, `down` as drawn
// (the empty row beyond the frame).
template <class L>
void fill_row(const typename L::Word* up, const typename L::Word* mid, const typename L::Word* down, uint32_t lo,
              uint32_t hi, uint16_t width, typename L::Word* out) {
  using W = typename L::Word;
  W left = lo > 0 ? up[lo - 1] + mid[lo - 1] + down[lo - 1] : 0, here = up[lo] + mid[lo] + down[lo];
  for (uint32_t x = lo; x < hi; ++x) {
    const W right = x + 1 < width ? up[x + 1] + mid[x + 1] + down[x + 1] : 0;
    if (mid[x] != 0) {
      out[x] = mid[x];
    } else {
      const W around = left + here + right;  // the centre is empty
      out[x] = L::count(around) >= 6 ? L::of_mean(around) : 0;
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
// isolated speck, and then takes the mean of its block's covered pixels.
// Pixels outside [lo, hi) are uncovered in `mid`, so the frame already
// holds the clear colour there.
template <class L>
void blend_row(const typename L::Word* up, const typename L::Word* mid, const typename L::Word* down,
               const typename L::Word* empty, uint32_t lo, uint32_t hi, uint16_t width, uint32_t clear, uint8_t* out) {
  using W = typename L::Word;
  const W* u = up ? up : empty;
  const W* d = down ? down : empty;
  const uint32_t rows = 1u + (up != nullptr) + (down != nullptr);
  W left = lo > 0 ? u[lo - 1] + mid[lo - 1] + d[lo - 1] : 0, here = u[lo] + mid[lo] + d[lo];
  for (uint32_t x = lo; x < hi; ++x) {
    const W right = x + 1 < width ? u[x + 1] + mid[x + 1] + d[x + 1] : 0;
    const W block = left + here + right;
    const uint32_t columns = 1u + (x > 0) + (x + 1 < width);
    // Kept: a pixel inside the surface (its whole block covered), or one of
    // an isolated speck (at most 3 covered neighbours): a node seen closer
    // than its points cover stays as dots instead of vanishing.
    const uint32_t n = L::count(block);
    const bool keep = mid[x] != 0 && (n == rows * columns || (rows * columns == 9 && n <= 4));
    L::store(out + L::kBytes * x, keep ? L::mean(block) : clear);
    left = here;
    here = right;
  }
}

template <class L>
void resolve(uint8_t* frame, size_t stride, uint16_t width, uint16_t height, const uint8_t* coverage, uint32_t clear_rgb,
             void* scratch) {
  using W = typename L::Word;
  W* rows = static_cast<W*>(scratch);
  W* drawn[3] = {rows, rows + width, rows + 2 * size_t{width}};
  W* filled[3] = {rows + 3 * size_t{width}, rows + 4 * size_t{width}, rows + 5 * size_t{width}};
  W* empty = rows + 6 * size_t{width};
  Span drawn_span[3], filled_span[3];
  for (int k = 0; k < 3; ++k) {
    drawn_span[k] = filled_span[k] = Span{0, width};
    clear<L>(drawn[k], drawn_span[k]);
    clear<L>(filled[k], filled_span[k]);
  }
  for (uint32_t x = 0; x < width; ++x) empty[x] = 0;
  const Span none;
  const size_t cov_stride = coverage_row_bytes(width);
  const uint32_t clear_word = L::clear(clear_rgb);
  // Row y is read at step y, filled at step y + 1 and written at step y + 2,
  // so the frame can be rewritten in place behind the ring. Only the columns
  // that can hold covered pixels are visited: a row's fill spans its and
  // its neighbours' drawn columns and one more each side; its blend spans
  // its filled columns.
  for (int32_t y = 0; y < int32_t{height} + 2; ++y) {
    if (y < height) {
      clear<L>(drawn[y % 3], drawn_span[y % 3]);
      drawn_span[y % 3] = load_row<L>(frame + size_t(y) * stride, coverage + size_t(y) * cov_stride, width, drawn[y % 3]);
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
      clear<L>(filled[f % 3], filled_span[f % 3]);
      if (lo < hi) {
        lo = lo > 0 ? lo - 1 : 0;
        hi = hi < width ? hi + 1 : width;
        fill_row<L>(f > 0 ? drawn[(f - 1) % 3] : empty, drawn[f % 3], f + 1 < height ? drawn[(f + 1) % 3] : empty, lo,
                    hi, width, filled[f % 3]);
        filled_span[f % 3] = Span{lo, hi};
      }
    }
    const int32_t b = y - 2;
    if (b >= 0 && filled_span[b % 3].lo < filled_span[b % 3].hi)
      blend_row<L>(b > 0 ? filled[(b - 1) % 3] : nullptr, filled[b % 3], b + 1 < height ? filled[(b + 1) % 3] : nullptr,
                   empty, filled_span[b % 3].lo, filled_span[b % 3].hi, width, clear_word, frame + size_t(b) * stride);
  }
}

}  // namespace

void resolve_frame(uint8_t* frame, size_t stride, PixelFormat format, uint16_t width, uint16_t height,
                   const uint8_t* coverage, uint32_t clear_rgb, void* scratch) {
  if (format == PixelFormat::kRgb565) resolve<Lanes565>(frame, stride, width, height, coverage, clear_rgb, scratch);
  else resolve<Lanes888>(frame, stride, width, height, coverage, clear_rgb, scratch);
}

}  // namespace stipple
