// stipple core — `.spg` writer. See spg_writer.h and docs/format.md.
#include "core/spg_writer.h"

namespace stipple {
namespace {

void write_fixed_header(const SpgHeader& h, uint8_t* out) {
  using namespace spg_offset;
  for (int i = 0; i < 4; ++i) out[kMagic + i] = kSpgMagic[i];
  store_u16le(out + kVersion, h.version);
  store_u16le(out + kFlags, h.flags);
  out[kArity] = h.tree_arity;
  out[spg_offset::kFieldCount] = static_cast<uint8_t>(stipple::kFieldCount);
  for (int f = 0; f < stipple::kFieldCount; ++f) out[kFieldBits + f] = h.layout.bits[f];
  store_u32le(out + kNodeCount, h.node_count);
  store_u32le(out + kLeafCount, h.leaf_count);
  store_u32le(out + kPointCount, h.point_count);
  store_u16le(out + kDepth, h.depth);
  store_u16le(out + kViewHint, h.view_hint.encode());
  for (int i = 0; i < 6; ++i) store_u32le(out + kBboxMin + 4 * i, h.bbox_bits[i]);
  for (int c = 0; c < 3; ++c) store_u16le(out + kClassCounts + 2 * c, h.class_count[c]);
  store_u16le(out + kReserved, 0);
  if (h.version >= 2)
    for (int a = 0; a < 3; ++a) {
      store_u32le(out + kOrigin + 8 * a, static_cast<uint32_t>(h.origin_bits[a]));
      store_u32le(out + kOrigin + 8 * a + 4, static_cast<uint32_t>(h.origin_bits[a] >> 32));
    }
}

// False when a version-2 code does not fit its 16 bits.
bool write_startup(const SpgHeader& h, const SpgClassTables& t, uint8_t* out) {
  write_fixed_header(h, out);
  uint8_t* at = out + spg_fixed_header_bytes(h.version);
  const uint32_t* tables[3] = {t.sigma_p, t.sigma_n, t.sigma_c};
  const size_t per_class[3] = {3, 2, 3};
  const bool floats = spg_class_value_bytes(h.version) == 4;
  for (int c = 0; c < 3; ++c)
    for (size_t i = 0; i < per_class[c] * h.class_count[c]; ++i) {
      if (floats) {
        store_u32le(at, tables[c][i]);
        at += 4;
      } else {
        if (tables[c][i] > 0xFFFFu) return false;
        store_u16le(at, static_cast<uint16_t>(tables[c][i]));
        at += 2;
      }
    }
  return true;
}

SpgWriteStatus status_of(SpgError e) {
  switch (e) {
    case SpgError::kOk: return SpgWriteStatus::kOk;
    case SpgError::kBadTree:
    case SpgError::kBadDepth: return SpgWriteStatus::kBadTree;
    case SpgError::kBadLeafCount: return SpgWriteStatus::kBadLeafCount;
    case SpgError::kBadRecord: return SpgWriteStatus::kBadRecord;
    default: return SpgWriteStatus::kBadHeader;
  }
}

}  // namespace

const char* spg_write_status_text(SpgWriteStatus s) {
  switch (s) {
    case SpgWriteStatus::kOk: return "ok";
    case SpgWriteStatus::kOutputTooSmall: return "output buffer smaller than the file";
    case SpgWriteStatus::kBadHeader: return "header has a field the format does not allow";
    case SpgWriteStatus::kBadTree: return "child counts do not form the header's tree";
    case SpgWriteStatus::kBadLeafCount: return "leaf point counts are 0 or do not sum to the point count";
    case SpgWriteStatus::kBadRecord: return "node record has a class index beyond its table or nonzero padding";
  }
  return "unknown status";
}

size_t spg_write_bound(const SpgHeader& h) {
  if (h.node_count == 0 || h.leaf_count == 0 || h.leaf_count > h.node_count) return 0;
  const uint64_t bits_per_node = h.tree_arity == 8 ? 4 : 1;
  const uint64_t bytes = spg_startup_bytes(h.version, h.class_count) + (uint64_t{h.node_count} * bits_per_node + 7) / 8 +
                         5 * uint64_t{h.leaf_count} + uint64_t{h.node_count} * static_cast<uint64_t>(h.layout.record_bytes()) + 4;
  return bytes > static_cast<uint64_t>(SIZE_MAX) ? 0 : static_cast<size_t>(bytes);
}

SpgWriteStatus spg_write_startup(const SpgHeader& h, const SpgClassTables& classes, uint8_t* out, size_t capacity,
                                 size_t* written) {
  if (h.version < kSpgOldestVersion || h.version > kSpgVersion) return SpgWriteStatus::kBadHeader;
  const size_t n = spg_startup_bytes(h.version, h.class_count);
  if (capacity < n) return SpgWriteStatus::kOutputTooSmall;
  for (int c = 0; c < 3; ++c) {
    const uint32_t* table = c == 0 ? classes.sigma_p : c == 1 ? classes.sigma_n : classes.sigma_c;
    if (h.class_count[c] > 0 && table == nullptr) return SpgWriteStatus::kBadHeader;
  }
  if (!write_startup(h, classes, out)) return SpgWriteStatus::kBadHeader;
  SpgView view;
  size_t used = 0;
  const SpgResult r = spg_parse_startup(out, n, &view, &used);
  if (!r.ok()) return status_of(r.error);
  *written = n;
  return SpgWriteStatus::kOk;
}

SpgWriteStatus spg_write_startup_le(const SpgHeader& h, const uint8_t* sigma_p, const uint8_t* sigma_n,
                                    const uint8_t* sigma_c, uint8_t* out, size_t capacity, size_t* written) {
  if (h.version < kSpgOldestVersion || h.version > kSpgVersion) return SpgWriteStatus::kBadHeader;
  const size_t n = spg_startup_bytes(h.version, h.class_count);
  if (capacity < n) return SpgWriteStatus::kOutputTooSmall;
  const uint8_t* tables[3] = {sigma_p, sigma_n, sigma_c};
  for (int c = 0; c < 3; ++c)
    if (h.class_count[c] > 0 && tables[c] == nullptr) return SpgWriteStatus::kBadHeader;
  write_fixed_header(h, out);
  uint8_t* at = out + spg_fixed_header_bytes(h.version);
  const size_t b = spg_class_value_bytes(h.version), per_class[3] = {3 * b, 2 * b, 3 * b};
  for (int c = 0; c < 3; ++c)
    for (size_t i = 0; i < per_class[c] * h.class_count[c]; ++i) *at++ = tables[c][i];
  SpgView view;
  size_t used = 0;
  const SpgResult r = spg_parse_startup(out, n, &view, &used);
  if (!r.ok()) return status_of(r.error);
  *written = n;
  return SpgWriteStatus::kOk;
}

SpgWriteStatus spg_write(const SpgContent& c, uint8_t* out, size_t capacity, size_t* written) {
  const SpgHeader& h = c.header;
  const size_t bound = spg_write_bound(h);
  if (bound == 0 || h.version < kSpgOldestVersion || h.version > kSpgVersion || c.child_counts == nullptr || c.leaf_points == nullptr || c.records == nullptr)
    return SpgWriteStatus::kBadHeader;
  // Representable child counts, and exactly leaf_count leaves (leaf_points
  // is read for each of them).
  uint32_t leaves = 0;
  for (uint32_t i = 0; i < h.node_count; ++i) {
    const uint8_t k = c.child_counts[i];
    if (h.tree_arity == 2 ? (k != 0 && k != 2) : k > 8) return SpgWriteStatus::kBadTree;
    leaves += k == 0;
  }
  if (leaves != h.leaf_count) return SpgWriteStatus::kBadTree;
  // Exact size: LEB128 lengths are known now.
  size_t leb_bytes = 0;
  for (uint32_t i = 0; i < h.leaf_count; ++i) leb_bytes += leb128_bytes(c.leaf_points[i]);
  const size_t table_bytes = spg_startup_bytes(h.version, h.class_count) - spg_fixed_header_bytes(h.version);
  const size_t topology_bytes = static_cast<size_t>((uint64_t{h.node_count} * (h.tree_arity == 8 ? 4 : 1) + 7) / 8);
  const size_t record_bytes = static_cast<size_t>(h.layout.record_bytes());
  const size_t size = spg_fixed_header_bytes(h.version) + table_bytes + topology_bytes + leb_bytes + size_t{h.node_count} * record_bytes + 4;
  if (capacity < size) return SpgWriteStatus::kOutputTooSmall;

  size_t startup = 0;
  const SpgWriteStatus s = spg_write_startup(h, c.classes, out, capacity, &startup);
  // The startup alone cannot judge counts that need the rest of the file.
  if (s != SpgWriteStatus::kOk) return s;
  uint8_t* at = out + startup;
  // §3 topology, LSB first.
  for (size_t i = 0; i < topology_bytes; ++i) at[i] = 0;
  for (uint32_t i = 0; i < h.node_count; ++i) {
    const uint32_t k = c.child_counts[i];
    if (h.tree_arity == 8) at[i >> 1] = static_cast<uint8_t>(at[i >> 1] | (k << ((i & 1) * 4)));
    else if (k) at[i >> 3] = static_cast<uint8_t>(at[i >> 3] | (1u << (i & 7)));
  }
  at += topology_bytes;
  // §4 leaf point counts, LEB128.
  for (uint32_t i = 0; i < h.leaf_count; ++i) at += store_leb128(at, c.leaf_points[i]);
  // §5 records, §6 CRC-32.
  for (size_t i = 0; i < size_t{h.node_count} * record_bytes; ++i) *at++ = c.records[i];
  store_u32le(at, crc32(out, static_cast<size_t>(at - out)));
  at += 4;
  // The reader's checks, on the bytes written: never a file it refuses.
  SpgView view;
  const SpgResult r = spg_parse(out, size, &view);
  if (!r.ok()) return status_of(r.error);
  *written = static_cast<size_t>(at - out);
  return SpgWriteStatus::kOk;
}

}  // namespace stipple
