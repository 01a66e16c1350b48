// stipple core — `.spg` validation. The specification is docs/format.md; each
// check below names the rule it enforces there.
#include "core/spg_format.h"

namespace stipple {
namespace {

// CRC-32 (IEEE, reflected) sliced by four: v[0] is the byte-wise table,
// v[k][n] the CRC of byte n followed by k zero bytes, so four bytes are
// folded per step. Generated at compile time; lives in read-only data (4 KB).
struct CrcTable {
  uint32_t v[4][256];
};
constexpr CrcTable kCrcTable = [] {
  CrcTable t{};
  for (uint32_t n = 0; n < 256; ++n) {
    uint32_t c = n;
    for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
    t.v[0][n] = c;
  }
  for (uint32_t n = 0; n < 256; ++n)
    for (int k = 1; k < 4; ++k) t.v[k][n] = t.v[0][t.v[k - 1][n] & 0xFFu] ^ (t.v[k - 1][n] >> 8);
  return t;
}();

// IEEE-754 binary32 checks with integer code only.
constexpr bool f32_finite(uint32_t bits) { return (bits & 0x7F800000u) != 0x7F800000u; }
constexpr bool f32_negative(uint32_t bits) { return (bits & 0x80000000u) != 0 && (bits & 0x7FFFFFFFu) != 0; }
// Maps binary32 bits to an unsigned key ordered like the values they encode.
constexpr uint32_t f32_order_key(uint32_t bits) {
  return (bits & 0x80000000u) ? ~bits : (bits | 0x80000000u);
}

// A bounds-checked cursor over the input: reads fail instead of overrunning.
struct Cursor {
  const uint8_t* data;
  size_t size;
  size_t pos;
  size_t remaining() const { return size - pos; }
};

SpgResult fail(SpgError e, size_t offset) { return SpgResult{e, offset, 0}; }
// The file ends at `size`, short of the `needed` bytes its sections need.
SpgResult truncated(size_t size, uint64_t needed) { return SpgResult{SpgError::kTruncated, size, needed}; }

bool class_field_ok(int width, uint16_t count, bool present) {
  if (!present) return width == 0 && count == 0;
  return width >= 1 && count >= 1 && static_cast<uint32_t>(count) <= (1u << width);
}

}  // namespace

const char* spg_error_text(SpgError e) {
  switch (e) {
    case SpgError::kOk: return "ok";
    case SpgError::kTruncated: return "file is truncated";
    case SpgError::kBadMagic: return "not a .spg file (bad magic)";
    case SpgError::kBadVersion: return "unsupported format version";
    case SpgError::kBadFlags: return "unknown attribute flags (or a curvature sign without normals or before version 2)";
    case SpgError::kBadArity: return "tree arity must be 2 or 8";
    case SpgError::kBadLayout: return "invalid record bit layout";
    case SpgError::kBadCounts: return "node, leaf or point counts are inconsistent or too large for the file";
    case SpgError::kBadFloat: return "float32 field is NaN, infinite or negative";
    case SpgError::kBadBoundingBox: return "bounding box minimum exceeds maximum";
    case SpgError::kBadClassCount: return "class table size does not match its index width";
    case SpgError::kBadTree: return "tree topology is invalid";
    case SpgError::kBadLeafCount: return "leaf point counts are invalid";
    case SpgError::kBadDepth: return "tree depth does not match the header";
    case SpgError::kBadRecord: return "node record has a class index beyond its table or nonzero padding";
    case SpgError::kBadChecksum: return "CRC-32 mismatch (file corrupted)";
    case SpgError::kTrailingBytes: return "unexpected bytes after the CRC-32";
    case SpgError::kCodedRecords: return "version 3 (coded records) must be expanded before it is read";
    case SpgError::kBadCoded: return "coded records do not decode (version 3)";
  }
  return "unknown error";
}

const char* spg_axis_name(SpgAxis a) {
  static const char* const names[] = {"none", "+x", "-x", "+y", "-y", "+z", "-z"};
  return static_cast<uint8_t>(a) < kSpgAxisCount ? names[static_cast<uint8_t>(a)] : "?";
}

bool spg_parse_axis(const char* text, SpgAxis* out) {
  char sign = '+', axis = 0;
  if (text[0] != '\0' && text[1] == '\0') {
    axis = text[0];  // "x" means "+x"
  } else if ((text[0] == '+' || text[0] == '-') && text[1] != '\0' && text[2] == '\0') {
    sign = text[0];
    axis = text[1];
  }
  for (uint8_t i = 1; i < kSpgAxisCount; ++i) {
    const char* name = spg_axis_name(static_cast<SpgAxis>(i));
    if (name[0] == sign && name[1] == axis) {
      *out = static_cast<SpgAxis>(i);
      return true;
    }
  }
  return false;
}

uint32_t crc32(const uint8_t* data, size_t size) { return crc32_extend(0, data, size); }

uint32_t crc32_extend(uint32_t crc, const uint8_t* data, size_t size) {
  const auto& t = kCrcTable.v;
  uint32_t c = crc ^ 0xFFFFFFFFu;
  size_t i = 0;
  for (; i + 4 <= size; i += 4) {
    c ^= uint32_t{data[i]} | uint32_t{data[i + 1]} << 8 | uint32_t{data[i + 2]} << 16 | uint32_t{data[i + 3]} << 24;
    c = t[3][c & 0xFFu] ^ t[2][(c >> 8) & 0xFFu] ^ t[1][(c >> 16) & 0xFFu] ^ t[0][c >> 24];
  }
  for (; i < size; ++i) c = t[0][(c ^ data[i]) & 0xFFu] ^ (c >> 8);
  return c ^ 0xFFFFFFFFu;
}

uint32_t spg_child_count(const SpgView& view, uint32_t node) {
  if (view.header.tree_arity == 2) return ((view.topology[node >> 3] >> (node & 7)) & 1u) ? 2u : 0u;
  return (view.topology[node >> 1] >> ((node & 1) * 4)) & 0xFu;
}

void spg_node_points(const SpgView& view, uint8_t* out, size_t stride) {
  const uint32_t n = view.header.node_count;
  const uint8_t* at = view.leaf_counts;
  for (uint32_t i = 0; i < n; ++i) {
    uint32_t v = 0;
    if (at != nullptr && spg_child_count(view, i) == 0) {
      for (int shift = 0;; shift += 7) {  // validated by spg_parse: at most 5 bytes
        const uint8_t byte = *at++;
        v |= static_cast<uint32_t>(byte & 0x7Fu) << shift;
        if ((byte & 0x80u) == 0) break;
      }
    }
    out[size_t{i} * stride] = static_cast<uint8_t>(v < 255 ? v : 255);
  }
  if (at == nullptr) return;
  // Bottom up: the children of the k-th internal node follow those of the
  // (k-1)-th, so walking back, each internal node's children end where the
  // next one's begin.
  uint32_t end = n;
  for (uint32_t i = n; i-- > 0;) {
    const uint32_t k = spg_child_count(view, i);
    if (k == 0) continue;
    uint32_t sum = 0;
    for (uint32_t c = end - k; c < end; ++c) sum += out[size_t{c} * stride];
    end -= k;
    out[size_t{i} * stride] = static_cast<uint8_t>(sum < 255 ? sum : 255);
  }
}

SpgResult spg_check_class_values(uint16_t version, const uint8_t* values, size_t bytes) {
  if (spg_class_value_bytes(version) == 4)
    for (size_t i = 0; i + 4 <= bytes; i += 4) {
      const uint32_t bits = load_u32le(values + i);
      if (!f32_finite(bits) || f32_negative(bits)) return fail(SpgError::kBadFloat, i);
    }
  return SpgResult{};
}

namespace {

// §1 fixed header and §2 class tables: the startup message. With
// `whole_file`, the counts must also fit the bytes after the header.
SpgResult parse_startup(const uint8_t* data, size_t size, bool whole_file, SpgView& view, Cursor& in, bool tables = true,
                        bool coded = false) {
  SpgHeader& h = view.header;

  // §1 fixed header.
  if (size < 4) return truncated(size, kSpgFixedHeaderBytes);
  for (int i = 0; i < 4; ++i)
    if (data[spg_offset::kMagic + i] != kSpgMagic[i]) return fail(SpgError::kBadMagic, spg_offset::kMagic);
  if (size < kSpgFixedHeaderBytes) return truncated(size, kSpgFixedHeaderBytes);
  using namespace spg_offset;
  h.version = load_u16le(data + kVersion);
  if (h.version == kSpgCodedVersion && !coded)
    return fail(whole_file ? SpgError::kCodedRecords : SpgError::kBadVersion, kVersion);
  if (h.version < kSpgOldestVersion || h.version > (coded ? kSpgCodedVersion : kSpgVersion))
    return fail(SpgError::kBadVersion, kVersion);
  const size_t header_bytes = spg_fixed_header_bytes(h.version);
  if (size < header_bytes) return truncated(size, header_bytes);
  h.flags = load_u16le(data + kFlags);
  if ((h.flags & ~kAttrKnownMask) != 0) return fail(SpgError::kBadFlags, kFlags);
  // A curvature sign needs normals and the 16-bit class codes.
  if ((h.flags & kAttrCurvatureSign) && (!(h.flags & kAttrNormals) || h.version == 1))
    return fail(SpgError::kBadFlags, kFlags);
  h.tree_arity = data[kArity];
  if (h.tree_arity != 2 && h.tree_arity != 8) return fail(SpgError::kBadArity, kArity);
  if (data[spg_offset::kFieldCount] != stipple::kFieldCount) return fail(SpgError::kBadLayout, spg_offset::kFieldCount);
  for (int f = 0; f < stipple::kFieldCount; ++f) {
    h.layout.bits[f] = data[kFieldBits + f];
    if (h.layout.bits[f] > kMaxFieldBits) return fail(SpgError::kBadLayout, kFieldBits + static_cast<size_t>(f));
  }
  const bool normals = h.has_normals();
  const bool color = h.has_color();
  for (int f = 0; f < stipple::kFieldCount; ++f) {
    const bool normal_field = f >= static_cast<int>(Field::kFnTheta) && f <= static_cast<int>(Field::kSigmaN);
    const bool color_field = f >= static_cast<int>(Field::kColorR);
    const bool present = normal_field ? normals : color_field ? color : true;
    if (present != (h.layout.bits[f] != 0)) return fail(SpgError::kBadLayout, kFieldBits + static_cast<size_t>(f));
  }
  if (h.layout.record_bytes() > kMaxRecordBytes) return fail(SpgError::kBadLayout, kFieldBits);
  h.node_count = load_u32le(data + kNodeCount);
  h.leaf_count = load_u32le(data + kLeafCount);
  h.point_count = load_u32le(data + kPointCount);
  h.depth = load_u16le(data + kDepth);
  if (h.node_count == 0) return fail(SpgError::kBadCounts, kNodeCount);
  if (h.leaf_count == 0 || h.leaf_count > h.node_count) return fail(SpgError::kBadCounts, kLeafCount);
  if (h.point_count < h.leaf_count) return fail(SpgError::kBadCounts, kPointCount);
  // View hint: two axis codes below kSpgAxisCount, the other bits zero.
  const uint16_t hint = load_u16le(data + kViewHint);
  if ((hint & 7u) >= kSpgAxisCount || ((hint >> 3) & 7u) >= kSpgAxisCount || (hint >> 7) != 0)
    return fail(SpgError::kBadLayout, kViewHint);
  h.view_hint.sensor_at_origin = (hint >> 6) & 1u;
  h.view_hint.up = static_cast<SpgAxis>(hint & 7u);
  h.view_hint.sensor_side = static_cast<SpgAxis>((hint >> 3) & 7u);
  // Every node needs a record and every leaf at least one LEB128 byte: bound
  // the counts by the file size before anything is sized from them.
  // (Version 3: a topology bit a node, the coded section's two counts.)
  const uint64_t min_body = h.version == kSpgCodedVersion
                                ? static_cast<uint64_t>(h.node_count) / 8 + h.leaf_count + 12
                                : static_cast<uint64_t>(h.node_count) * h.layout.record_bytes() + h.leaf_count + 4;
  if (whole_file && min_body > size - header_bytes) return truncated(size, header_bytes + min_body);
  for (int i = 0; i < 6; ++i) {
    h.bbox_bits[i] = load_u32le(data + kBboxMin + 4 * i);
    if (!f32_finite(h.bbox_bits[i])) return fail(SpgError::kBadFloat, kBboxMin + 4 * static_cast<size_t>(i));
  }
  for (int a = 0; a < 3; ++a)
    if (f32_order_key(h.bbox_bits[a]) > f32_order_key(h.bbox_bits[3 + a]))
      return fail(SpgError::kBadBoundingBox, kBboxMin + 4 * static_cast<size_t>(a));
  for (int c = 0; c < 3; ++c) h.class_count[c] = load_u16le(data + kClassCounts + 2 * c);
  if (!class_field_ok(h.layout.width(Field::kSigmaP), h.class_count[0], true)) return fail(SpgError::kBadClassCount, kClassCounts);
  if (!class_field_ok(h.layout.width(Field::kSigmaN), h.class_count[1], normals)) return fail(SpgError::kBadClassCount, kClassCounts + 2);
  if (!class_field_ok(h.layout.width(Field::kSigmaC), h.class_count[2], color)) return fail(SpgError::kBadClassCount, kClassCounts + 4);
  if (load_u16le(data + kReserved) != 0) return fail(SpgError::kBadLayout, kReserved);
  // Version 2's origin: three finite float64.
  for (int a = 0; a < 3 && h.version >= 2; ++a) {
    const uint64_t bits = uint64_t{load_u32le(data + kOrigin + 8 * a)} | uint64_t{load_u32le(data + kOrigin + 8 * a + 4)} << 32;
    if (((bits >> 52) & 0x7FFu) == 0x7FFu) return fail(SpgError::kBadFloat, kOrigin + 8 * static_cast<size_t>(a));
    h.origin_bits[a] = bits;
  }
  in.pos = header_bytes;
  if (!tables) return SpgResult{};

  // §2 class tables: non-negative finite float32 (version 1) or 16-bit
  // codes, every one of which is a valid value (version 2).
  const size_t value_bytes = spg_class_value_bytes(h.version);
  const size_t table_bytes = spg_startup_bytes(h.version, h.class_count) - header_bytes;
  if (in.remaining() < table_bytes) return truncated(size, uint64_t{in.pos} + table_bytes);
  view.sigma_p = data + in.pos;
  view.sigma_n = view.sigma_p + 3 * value_bytes * h.class_count[0];
  view.sigma_c = view.sigma_n + 2 * value_bytes * h.class_count[1];
  if (const SpgResult r = spg_check_class_values(h.version, data + in.pos, table_bytes); !r.ok())
    return fail(r.error, in.pos + r.offset);
  in.pos += table_bytes;

  return SpgResult{};
}

}  // namespace

SpgResult spg_parse_startup(const uint8_t* data, size_t size, SpgView* out, size_t* startup_bytes) {
  Cursor in{data, size, 0};
  SpgView view;
  const SpgResult r = parse_startup(data, size, false, view, in);
  if (!r.ok()) return r;
  *out = view;
  *startup_bytes = in.pos;
  return r;
}

SpgResult spg_parse_header(const uint8_t* data, size_t size, SpgHeader* out, size_t* header_bytes) {
  Cursor in{data, size, 0};
  SpgView view;
  const SpgResult r = parse_startup(data, size, false, view, in, false);
  if (!r.ok()) return r;
  *out = view.header;
  *header_bytes = in.pos;
  return r;
}

namespace {

SpgResult parse_file(const uint8_t* data, size_t size, SpgView* out, SpgCodedParts* coded) {
  Cursor in{data, size, 0};
  SpgView view;
  const SpgResult startup = parse_startup(data, size, true, view, in, true, coded != nullptr);
  if (!startup.ok()) return startup;
  const SpgHeader& h = view.header;
  const bool normals = h.has_normals(), color = h.has_color();

  // §3 topology: BFS order, siblings adjacent, children after their parent.
  const uint32_t bits_per_node = h.tree_arity == 2 ? 1u : 4u;
  // At most node_count / 2 + 1 bytes, below the record bytes already bounded
  // by the file size: fits size_t on 32-bit targets too.
  view.topology_bytes = static_cast<size_t>((static_cast<uint64_t>(h.node_count) * bits_per_node + 7) / 8);
  if (in.remaining() < view.topology_bytes) return truncated(size, uint64_t{in.pos} + view.topology_bytes);
  view.topology = data + in.pos;
  {
    uint32_t next_child = 1, leaves = 0, level_end = 1, depth = 0;
    for (uint32_t i = 0; i < h.node_count; ++i) {
      const size_t at = in.pos + static_cast<size_t>((static_cast<uint64_t>(i) * bits_per_node) / 8);
      if (i > 0 && i >= next_child) return fail(SpgError::kBadTree, at);  // orphan node
      if (i == level_end) {
        level_end = next_child;
        ++depth;
      }
      uint32_t c;
      if (h.tree_arity == 2) {
        c = ((view.topology[i >> 3] >> (i & 7)) & 1u) ? 2u : 0u;
      } else {
        c = (view.topology[i >> 1] >> ((i & 1) * 4)) & 0xFu;
        if (c > 8) return fail(SpgError::kBadTree, at);
      }
      if (c == 0) ++leaves;
      if (c > h.node_count - next_child) return fail(SpgError::kBadTree, at);
      next_child += c;
    }
    if (next_child != h.node_count) return fail(SpgError::kBadTree, in.pos);
    const uint64_t used_bits = static_cast<uint64_t>(h.node_count) * bits_per_node;
    if (used_bits % 8 != 0 && (view.topology[view.topology_bytes - 1] >> (used_bits % 8)) != 0)
      return fail(SpgError::kBadTree, in.pos + view.topology_bytes - 1);
    if (leaves != h.leaf_count) return fail(SpgError::kBadCounts, spg_offset::kLeafCount);
    if (depth != h.depth) return fail(SpgError::kBadDepth, spg_offset::kDepth);
  }
  in.pos += view.topology_bytes;

  // §4 leaf point counts: canonical LEB128, each in [1, 2^32), summing to point_count.
  view.leaf_counts = data + in.pos;
  {
    uint64_t sum = 0;
    for (uint32_t leaf = 0; leaf < h.leaf_count; ++leaf) {
      const size_t start = in.pos;
      uint64_t value = 0;
      for (int shift = 0;; shift += 7) {
        if (in.remaining() == 0) return truncated(size, uint64_t{in.pos} + 1);
        if (shift > 28) return fail(SpgError::kBadLeafCount, start);
        const uint8_t byte = data[in.pos++];
        value |= static_cast<uint64_t>(byte & 0x7Fu) << shift;
        if ((byte & 0x80u) == 0) {
          if (byte == 0 && shift > 0) return fail(SpgError::kBadLeafCount, start);  // overlong
          break;
        }
      }
      if (value == 0 || value > 0xFFFFFFFFu) return fail(SpgError::kBadLeafCount, start);
      sum += value;
      if (sum > h.point_count) return fail(SpgError::kBadLeafCount, start);
    }
    if (sum != h.point_count) return fail(SpgError::kBadLeafCount, in.pos);
  }
  view.leaf_counts_bytes = static_cast<size_t>(in.pos - static_cast<size_t>(view.leaf_counts - data));

  view.record_bytes = static_cast<size_t>(h.layout.record_bytes());
  if (h.version == kSpgCodedVersion) {
    // §5, version 3: u32 the code tables' bytes, the tables, u32 the
    // batches, each u32 its bytes (at least 8: a count and a state) and
    // its payload. What they hold, spg_expand checks.
    SpgCodedParts parts;
    parts.records_offset = in.pos;
    const auto length = [&](size_t* n) {
      if (in.remaining() < 4) return truncated(size, uint64_t{in.pos} + 4);
      *n = load_u32le(data + in.pos);
      in.pos += 4;
      return SpgResult{};
    };
    if (const SpgResult r = length(&parts.tables_bytes); !r.ok()) return r;
    if (in.remaining() < parts.tables_bytes) return truncated(size, uint64_t{in.pos} + parts.tables_bytes);
    parts.tables = data + in.pos;
    in.pos += parts.tables_bytes;
    const size_t batches_at = in.pos;
    size_t batches = 0;
    if (const SpgResult r = length(&batches); !r.ok()) return r;
    if (batches == 0 || batches > h.node_count) return fail(SpgError::kBadCoded, batches_at);
    for (size_t b = 0; b < batches; ++b) {
      const size_t at = in.pos;
      size_t bytes = 0;
      if (const SpgResult r = length(&bytes); !r.ok()) return r;
      if (bytes < 8) return fail(SpgError::kBadCoded, at);
      if (in.remaining() < bytes) return truncated(size, uint64_t{in.pos} + bytes);
      in.pos += bytes;
    }
    parts.batches = data + batches_at;
    parts.batches_bytes = in.pos - batches_at;
    parts.batch_count = static_cast<uint32_t>(batches);
    *coded = parts;
  } else {
    // §5 records: class indices inside their tables, padding bits zero.
    const uint64_t records_size = static_cast<uint64_t>(h.node_count) * view.record_bytes;
    if (in.remaining() < records_size) return truncated(size, uint64_t{in.pos} + records_size);
    view.records = data + in.pos;
    {
      const int pad_bits = static_cast<int>(view.record_bytes * 8) - h.layout.total_bits();
      for (uint32_t i = 0; i < h.node_count; ++i) {
        const uint8_t* rec = view.records + static_cast<size_t>(i) * view.record_bytes;
        const NodeFields f = unpack_record(h.layout, rec);
        if (f[Field::kSigmaP] >= h.class_count[0] || (normals && f[Field::kSigmaN] >= h.class_count[1]) ||
            (color && f[Field::kSigmaC] >= h.class_count[2]))
          return fail(SpgError::kBadRecord, in.pos + static_cast<size_t>(i) * view.record_bytes);
        if (pad_bits > 0 && (rec[view.record_bytes - 1] >> (8 - pad_bits)) != 0)
          return fail(SpgError::kBadRecord, in.pos + static_cast<size_t>(i) * view.record_bytes);
      }
    }
    in.pos += static_cast<size_t>(records_size);
  }

  // §6 CRC-32 of everything before it, then end of file.
  if (in.remaining() < 4) return truncated(size, uint64_t{in.pos} + 4);
  if (in.remaining() > 4) return fail(SpgError::kTrailingBytes, in.pos + 4);
  if (load_u32le(data + in.pos) != crc32(data, in.pos)) return fail(SpgError::kBadChecksum, in.pos);

  *out = view;
  return SpgResult{};
}

}  // namespace

SpgResult spg_parse(const uint8_t* data, size_t size, SpgView* out) { return parse_file(data, size, out, nullptr); }

SpgResult spg_parse_coded(const uint8_t* data, size_t size, SpgView* out, SpgCodedParts* parts) {
  SpgView view;
  SpgCodedParts coded;
  const SpgResult r = parse_file(data, size, &view, &coded);
  if (!r.ok()) return r;
  if (view.header.version != kSpgCodedVersion) return fail(SpgError::kBadVersion, spg_offset::kVersion);
  *out = view;
  *parts = coded;
  return r;
}

}  // namespace stipple
