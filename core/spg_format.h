// stipple core — the `.spg` container: startup header, class tables, tree
// topology, leaf point counts, packed node records, CRC-32 trailer.
// The byte-level specification, with every check listed here, is docs/format.md.
//
// `spg_parse` validates a whole file held in memory and returns views into it.
// It is safe on untrusted input: every length is checked against the bytes
// that remain before it is used, no read goes past `size`, nothing is
// allocated, nothing is thrown, and no floating point is used (float32 fields
// are returned as raw IEEE-754 bit patterns and checked for finiteness with
// integer code). On failure it reports an error code and the byte offset of
// the offending field; the host builds a message from `spg_error_text`.
#pragma once

#include <cstddef>
#include <cstdint>

#include "core/node_format.h"

namespace stipple {

inline constexpr uint8_t kSpgMagic[4] = {'S', 'T', 'P', 'G'};
// The version written; the reader also takes every version from
// kSpgOldestVersion. Version 1 stores the class tables as float32, version 2
// as 16-bit codes (docs/format.md §2) and adds an origin to the fixed header
// (§1: the bounding box is stored relative to it, so a survey's coordinates
// 1e7 from the origin keep their millimetres in the float32 box).
inline constexpr uint16_t kSpgVersion = 2;
inline constexpr uint16_t kSpgOldestVersion = 1;
// Version 3 is version 2 with the records entropy-coded, each child
// against its parent (docs/format.md §5, "Coded records"): a file to store
// and carry, read by expanding it into the version 2 image it stands for
// (core/spg_coded.h). spg_parse refuses it (kCodedRecords); no stream
// carries it.
inline constexpr uint16_t kSpgCodedVersion = 3;
inline constexpr size_t kSpgFixedHeaderBytes = 76;    // version 1's fixed header, the start of every version's
inline constexpr size_t kSpgOriginBytes = 24;         // version 2: 3 x float64 after it
inline size_t spg_fixed_header_bytes(uint16_t version) {
  return version == 1 ? kSpgFixedHeaderBytes : kSpgFixedHeaderBytes + kSpgOriginBytes;
}

// Byte offsets of the fixed header's fields (docs/format.md §1): the reader,
// the writer (core/spg_writer.h) and every tool use these names.
namespace spg_offset {
inline constexpr size_t kMagic = 0;          // 4 bytes "STPG"
inline constexpr size_t kVersion = 4;        // u16
inline constexpr size_t kFlags = 6;          // u16: kAttrNormals | kAttrColor
inline constexpr size_t kArity = 8;          // u8: 2 or 8
inline constexpr size_t kFieldCount = 9;     // u8: kFieldCount
inline constexpr size_t kFieldBits = 10;     // kFieldCount x u8
inline constexpr size_t kNodeCount = 28;     // u32
inline constexpr size_t kLeafCount = 32;     // u32
inline constexpr size_t kPointCount = 36;    // u32
inline constexpr size_t kDepth = 40;         // u16
inline constexpr size_t kViewHint = 42;      // u16: up axis and sensor side (SpgViewHint)
inline constexpr size_t kBboxMin = 44;       // 3 x float32
inline constexpr size_t kBboxMax = 56;       // 3 x float32
inline constexpr size_t kClassCounts = 68;   // 3 x u16: sigma_p, sigma_n, sigma_c
inline constexpr size_t kReserved = 74;      // u16, 0
static_assert(kReserved + 2 == kSpgFixedHeaderBytes);
inline constexpr size_t kOrigin = 76;        // version 2: 3 x float64, what the box is relative to
}  // namespace spg_offset

// An axis direction as the view hint stores it in 3 bits: 0 none, then
// +x, -x, +y, -y, +z, -z.
enum class SpgAxis : uint8_t { kNone = 0, kPosX, kNegX, kPosY, kNegY, kPosZ, kNegZ };
inline constexpr uint8_t kSpgAxisCount = 7;

// "+x", "-z", ...; "none" for kNone. The parser takes "+x" .. "-z" and a
// bare "x" for "+x"; false (out untouched) for anything else.
const char* spg_axis_name(SpgAxis a);
// An axis's coordinate (x 0, y 1, z 2; -1 for kNone) and whether it runs
// towards the coordinate's negative side.
inline int spg_axis_index(SpgAxis a) { return a == SpgAxis::kNone ? -1 : (static_cast<int>(a) - 1) / 2; }
inline bool spg_axis_negative(SpgAxis a) { return a != SpgAxis::kNone && (static_cast<int>(a) - 1) % 2 == 1; }
[[nodiscard]] bool spg_parse_axis(const char* text, SpgAxis* out);

// How the scan wants to be seen (docs/format.md §1, offset 42): which way is
// up, the side the sensor saw it from (the default view looks from there),
// or that the sensor stood inside the scan at the origin (the default view
// looks out from there). All none in files without a hint: the viewer chooses.
struct SpgViewHint {
  SpgAxis up = SpgAxis::kNone;
  SpgAxis sensor_side = SpgAxis::kNone;
  bool sensor_at_origin = false;
  uint16_t encode() const {
    return static_cast<uint16_t>(static_cast<uint16_t>(up) | (static_cast<uint16_t>(sensor_side) << 3) |
                                 (sensor_at_origin ? 1u << 6 : 0u));
  }
};

// Bytes of one class table value: a float32 in version 1, a 16-bit code
// from version 2.
inline size_t spg_class_value_bytes(uint16_t version) { return version == 1 ? 4 : 2; }
// Values a class of table 0 (sigma_p: 3), 1 (sigma_n: 2) or 2 (sigma_c: 3) holds.
inline uint32_t spg_class_values(int table) { return table == 1 ? 2 : 3; }

// The startup message, defined once: the fixed header and the class tables
// (§1-§2), the prefix a client needs before any node record. Its length for
// a header's version and class counts.
inline size_t spg_startup_bytes(uint16_t version, const uint16_t class_count[3]) {
  return spg_fixed_header_bytes(version) + spg_class_value_bytes(version) * (3 * size_t{class_count[0]} + 2 * size_t{class_count[1]} +
                                                                   3 * size_t{class_count[2]});
}

// Version 2's class codes (docs/format.md §2), decoded without floating
// point. sigma_p is a 16-bit floating-point code relative to the box's largest
// extent E: exponent e = code >> 11, mantissa m = code & 2047, value
// E (2048 + m) 2^(e - 42) for e >= 1 and E m 2^-41 for e = 0 (so E 2^-41
// steps near zero, 12 significant bits above, at most about 2 E).
// sigma_n (radians) and sigma_c (colour, 0..1) are Q12: value = code / 4096;
// with kAttrCurvatureSign the sigma_n codes are two's complement (a negative
// value a concave turn, its magnitude the spread), read by spg_sigma_n_q12.
// The sigma_p value in units of E / 2^unit_bits, rounded half up (unit_bits
// <= 30, so the result stays below 2^32).
inline uint32_t spg_sigma_p_code_units(uint16_t code, int unit_bits) {
  const uint32_t e = code >> 11u, m = code & 2047u;
  const uint32_t mant = e == 0 ? m : 2048u + m;
  const int shift = (e == 0 ? 41 : 42 - static_cast<int>(e)) - unit_bits;  // value = mant 2^-shift units
  if (shift <= 0) return mant << -shift;
  if (shift > 31) return 0;
  return static_cast<uint32_t>((uint64_t{mant} + (uint64_t{1} << (shift - 1))) >> shift);
}

// A sigma_n code as Q12 radians: unsigned, or with the header's curvature
// sign two's complement. spg_sigma_n_magnitude: its spread, whatever the sign.
inline int32_t spg_sigma_n_q12(uint16_t code, bool curvature_sign) {
  return curvature_sign && code >= 0x8000u ? static_cast<int32_t>(code) - 0x10000 : static_cast<int32_t>(code);
}
inline uint16_t spg_sigma_n_magnitude(uint16_t code, bool curvature_sign) {
  const int32_t v = spg_sigma_n_q12(code, curvature_sign);
  return static_cast<uint16_t>(v < 0 ? -v : v);
}

enum class SpgError : uint8_t {
  kOk = 0,
  kTruncated,          // the file ends inside a section
  kBadMagic,           // not "STPG"
  kBadVersion,         // a version this reader does not know
  kBadFlags,           // unknown attribute bits
  kBadArity,           // tree arity not 2 or 8
  kBadLayout,          // a field width out of range or inconsistent with flags
  kBadCounts,          // node/leaf/point counts inconsistent or too large for the file
  kBadFloat,           // a float32 field is NaN, infinite or negative where it must not be
  kBadBoundingBox,     // min > max on some axis
  kBadClassCount,      // a class table larger than its index width allows, or empty
  kBadTree,            // a child count out of range or the children do not fit
  kBadLeafCount,       // a leaf point count of 0, over 32 bits or not summing to point_count
  kBadDepth,           // the tree's depth differs from the header's
  kBadRecord,          // a record's class index is beyond its class table
  kBadChecksum,        // CRC-32 mismatch
  kTrailingBytes,      // bytes after the CRC-32
  kCodedRecords,       // a version 3 file (coded records) where its expansion is wanted (spg_expand)
  kBadCoded,           // version 3: coded records whose framing, tables or batches do not decode
};

// A short, static, English description of an error code (no allocation).
const char* spg_error_text(SpgError e);

struct SpgHeader {
  uint16_t version = 0;
  uint16_t flags = 0;        // kAttrNormals | kAttrColor | kAttrCurvatureSign
  uint8_t tree_arity = 0;    // 2: binary 2-means tree, 8: octree
  RecordLayout layout;
  uint32_t node_count = 0;
  uint32_t leaf_count = 0;
  uint32_t point_count = 0;  // original points the tree was built from
  uint16_t depth = 0;        // deepest level; the root is level 0
  SpgViewHint view_hint;     // up axis and sensor side, or none
  uint32_t bbox_bits[6] = {};  // float32 bit patterns: min x y z, max x y z, relative to the origin
  uint64_t origin_bits[3] = {};  // float64 bit patterns (version 2; zero, the origin, in version 1)
  uint16_t class_count[3] = {};  // sigma_p, sigma_n, sigma_c

  bool has_normals() const { return (flags & kAttrNormals) != 0; }
  bool has_color() const { return (flags & kAttrColor) != 0; }
  bool has_curvature_sign() const { return (flags & kAttrCurvatureSign) != 0; }
};

// Whether a reader with header `reader` (a stream's reduced header) gets a
// file's sigma_n codes as their magnitudes: the file has the sign, it not.
inline bool spg_sigma_n_unsigned_for(const SpgHeader& file, const SpgHeader& reader) {
  return file.has_curvature_sign() && !reader.has_curvature_sign();
}

// A class's bit where a bit set holds every class of a header's tables, one
// table after another (which classes a stream has sent, or a cache holds).
inline size_t spg_class_bit(const SpgHeader& h, int table, uint32_t index) {
  return (table > 0 ? size_t{h.class_count[0]} : 0) + (table > 1 ? size_t{h.class_count[1]} : 0) + index;
}

// Views into a validated file. Pointers refer to the caller's buffer.
struct SpgView {
  SpgHeader header;
  // Class tables, little-endian: float32 in version 1, 16-bit codes from
  // version 2 (spg_class_value_bytes(header.version) each).
  const uint8_t* sigma_p = nullptr;  // class_count[0] x 3 (sigma1 >= sigma2 >= sigma3)
  const uint8_t* sigma_n = nullptr;  // class_count[1] x 2
  const uint8_t* sigma_c = nullptr;  // class_count[2] x 3
  const uint8_t* topology = nullptr; // child counts, BFS order (1 bit/node for arity 2, 4 bits for 8)
  size_t topology_bytes = 0;
  const uint8_t* leaf_counts = nullptr;  // LEB128 point count per leaf, BFS order
  size_t leaf_counts_bytes = 0;
  const uint8_t* records = nullptr;  // node_count x record_bytes
  size_t record_bytes = 0;
};

struct SpgResult {
  SpgError error = SpgError::kOk;
  size_t offset = 0;  // byte offset of the offending field (valid when error != kOk)
  // kTruncated: the bytes the file needs at least — the sections read so far
  // and, for a whole file, the minimum the header's counts need (so a count
  // a file cannot hold reads as a file cut short of that size).
  uint64_t needed = 0;
  bool ok() const { return error == SpgError::kOk; }
};

// Validates `data[0 .. size)` as a complete `.spg` file and fills `out`.
// Checks every rule of docs/format.md, including the class index of every record.
[[nodiscard]] SpgResult spg_parse(const uint8_t* data, size_t size, SpgView* out);

// A version 3 file's coded records (docs/format.md §5): the code tables
// and the batches, each u32-length-prefixed in the file.
struct SpgCodedParts {
  const uint8_t* tables = nullptr;
  size_t tables_bytes = 0;
  const uint8_t* batches = nullptr;  // u32 count, then each batch: u32 bytes, payload
  size_t batches_bytes = 0;
  uint32_t batch_count = 0;
  size_t records_offset = 0;  // where the coded section, and a version 2 image's records, begin
};
// Validates a version 3 file as spg_parse validates every other version —
// all but the records, which only their decoding checks (spg_expand) — and
// finds its coded parts. `out->records` is null.
[[nodiscard]] SpgResult spg_parse_coded(const uint8_t* data, size_t size, SpgView* out, SpgCodedParts* parts);

// Validates only the startup message — the fixed header and class tables
// that begin a `.spg` file (docs/format.md §1-§2) — from `data[0 .. size)`.
// Fills the header and class table views of `out` (no topology, counts or
// records) and the startup message's length. Used by clients, which receive
// the startup message first and node records afterwards.
[[nodiscard]] SpgResult spg_parse_startup(const uint8_t* data, size_t size, SpgView* out, size_t* startup_bytes);

// The fixed header alone (§1, every rule of it), for a stream that sends the
// class tables in pieces (docs/protocol.md, version 4): *header_bytes is its
// length.
[[nodiscard]] SpgResult spg_parse_header(const uint8_t* data, size_t size, SpgHeader* out, size_t* header_bytes);
// Class table values of a header's version (§2): version 1's float32 must
// be finite and non-negative (every version 2 code is a value). The offset
// of a bad one is relative to `values`.
[[nodiscard]] SpgResult spg_check_class_values(uint16_t version, const uint8_t* values, size_t bytes);

// Children of node `i` of a validated view: number of children.
uint32_t spg_child_count(const SpgView& view, uint32_t node);

// The original points under every node of a validated view (its leaves'
// counts from §4, summed), saturated at 255 — what a client caps a node's
// drawn points by — into out[i * stride], breadth-first. No storage besides
// `out`; all zero when the view has no leaf counts (spg_parse_startup's).
void spg_node_points(const SpgView& view, uint8_t* out, size_t stride);

// Little-endian readers shared by the parser and its users.
inline uint16_t load_u16le(const uint8_t* p) { return static_cast<uint16_t>(p[0] | (p[1] << 8)); }
inline uint32_t load_u32le(const uint8_t* p) {
  return static_cast<uint32_t>(p[0]) | (static_cast<uint32_t>(p[1]) << 8) |
         (static_cast<uint32_t>(p[2]) << 16) | (static_cast<uint32_t>(p[3]) << 24);
}
// A little-endian base-128 (LEB128) u32 from *at: at most 5 bytes, below
// 2^32; advances *at past it. False when it runs past `end` or does not fit.
inline bool load_leb128(const uint8_t** at, const uint8_t* end, uint32_t* v) {
  uint32_t value = 0;
  for (int shift = 0; shift < 35; shift += 7) {
    if (*at >= end) return false;
    const uint8_t b = *(*at)++;
    if (shift == 28 && b > 15) return false;
    value |= uint32_t{b & 0x7Fu} << shift;
    if (!(b & 0x80)) {
      *v = value;
      return true;
    }
  }
  return false;
}

// CRC-32 (ISO-HDLC, the zlib/PNG polynomial 0xEDB88320).
uint32_t crc32(const uint8_t* data, size_t size);
// The CRC-32 of a file's bytes so far (`crc`, 0 for none) extended by
// data[0 .. size): crc32(a + b) == crc32_extend(crc32(a), b), as zlib's
// crc32() — for files written or checked in pieces.
uint32_t crc32_extend(uint32_t crc, const uint8_t* data, size_t size);

}  // namespace stipple
