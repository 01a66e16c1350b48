// stipple core — writing a `.spg` file (docs/format.md), the reader's twin.
//
// The caller owns every buffer: `spg_write_bound` says how many bytes a file
// with a given header can take, `spg_write` writes it into `out` and returns
// the bytes written. Nothing is allocated or thrown and no floating point is
// used (the bounding box is float32 bit patterns, the class tables float32
// bit patterns or 16-bit codes). The
// writer checks what it is given as the reader would — counts, topology,
// leaf counts, class indices — so it never writes a file `spg_parse`
// refuses; it returns a status instead.
//
//   SpgContent c{header, tables, child_counts, leaf_points, records};
//   std::vector<uint8_t> out(spg_write_bound(c.header));
//   size_t n = 0;
//   if (spg_write(c, out.data(), out.size(), &n) == SpgWriteStatus::kOk) out.resize(n);
//
// `spg_write_startup` writes only the startup message (§1-§2, the prefix of
// the file; its length is spg_startup_bytes): what a server sends a client
// before any node record.
#pragma once

#include <cstddef>
#include <cstdint>

#include "core/spg_format.h"

namespace stipple {

enum class SpgWriteStatus : uint8_t {
  kOk = 0,
  kOutputTooSmall,  // `capacity` below what this content needs
  kBadHeader,       // a field the reader would refuse (version, flags, layout, counts, box, class counts, hint)
  kBadTree,         // child counts that do not form the header's tree (or its depth, leaf count)
  kBadLeafCount,    // a leaf's point count of 0, or the sum differs from point_count
  kBadRecord,       // a class index beyond its table, or nonzero padding bits
};

const char* spg_write_status_text(SpgWriteStatus s);

// The class tables as the header's version stores them — float32 bit
// patterns in version 1, 16-bit codes (docs/format.md §2; a value above
// 0xFFFF is kBadHeader) from version 2: class_count[0] x 3 for sigma_p
// (sigma1 >= sigma2 >= sigma3), class_count[1] x 2 for sigma_n,
// class_count[2] x 3 for sigma_c. Null where the count is 0.
struct SpgClassTables {
  const uint32_t* sigma_p = nullptr;
  const uint32_t* sigma_n = nullptr;
  const uint32_t* sigma_c = nullptr;
};

struct SpgContent {
  SpgHeader header;             // version, flags, arity, layout, counts, depth, hint, box bits, class counts
  SpgClassTables classes;
  const uint8_t* child_counts = nullptr;  // node_count entries, breadth-first: 0 or 2 (arity 2), 0..8 (arity 8)
  const uint32_t* leaf_points = nullptr;  // leaf_count original point counts, breadth-first
  const uint8_t* records = nullptr;       // node_count x header.layout.record_bytes(), packed (core/node_format.h)
};

// The most bytes a file with this header takes (every leaf count in 5
// LEB128 bytes); 0 when the header's counts cannot form a file. The
// actual size is at most this.
size_t spg_write_bound(const SpgHeader& header);

// Writes the whole file into out[0 .. capacity) and sets *written.
[[nodiscard]] SpgWriteStatus spg_write(const SpgContent& content, uint8_t* out, size_t capacity, size_t* written);

// Writes the startup message (fixed header and class tables) into
// out[0 .. capacity); spg_startup_bytes(header.version, header.class_count) bytes.
[[nodiscard]] SpgWriteStatus spg_write_startup(const SpgHeader& header, const SpgClassTables& classes, uint8_t* out,
                                               size_t capacity, size_t* written);

// The same from class tables as they lie in a file of the header's version
// (little-endian bytes, e.g. an SpgView's): what a server sends without
// converting them.
[[nodiscard]] SpgWriteStatus spg_write_startup_le(const SpgHeader& header, const uint8_t* sigma_p, const uint8_t* sigma_n,
                                                  const uint8_t* sigma_c, uint8_t* out, size_t capacity, size_t* written);

// A leaf's point count as §4 stores it (LEB128, at most 5 bytes) at out;
// returns the bytes written.
inline size_t store_leb128(uint8_t* out, uint32_t v) {
  size_t n = 0;
  do {
    const uint8_t byte = v & 0x7F;
    v >>= 7;
    out[n++] = static_cast<uint8_t>(byte | (v ? 0x80 : 0));
  } while (v);
  return n;
}

// The bytes store_leb128 writes for v.
inline size_t leb128_bytes(uint32_t v) {
  size_t n = 1;
  while (v >>= 7) ++n;
  return n;
}

inline void store_u16le(uint8_t* p, uint16_t v) {
  p[0] = static_cast<uint8_t>(v);
  p[1] = static_cast<uint8_t>(v >> 8);
}
inline void store_u32le(uint8_t* p, uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<uint8_t>(v >> (8 * i));
}

}  // namespace stipple
