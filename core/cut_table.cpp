// stipple core — the cut table file. See cut_table.h and docs/format.md.
#include "core/cut_table.h"

#include "core/spg_writer.h"

namespace stipple {

namespace {

constexpr uint8_t kMagic[8] = {'S', 'P', 'G', 'C', 'U', 'T', '\r', '\n'};
constexpr size_t kBoundBytes = 36;

uint64_t load_u64le(const uint8_t* p) { return uint64_t{load_u32le(p)} | (uint64_t{load_u32le(p + 4)} << 32); }

}  // namespace

const char* cut_table_error_text(CutTableError e) {
  switch (e) {
    case CutTableError::kOk: return "ok";
    case CutTableError::kTruncated: return "truncated";
    case CutTableError::kBadMagic: return "not a cut table (bad magic)";
    case CutTableError::kBadVersion: return "a cut table version this build does not read";
    case CutTableError::kOtherModel: return "made from another model (its size, CRC-32 or node count differ)";
    case CutTableError::kOtherCones: return "made for another cone rule (--leaf-cone)";
    case CutTableError::kBadChecksum: return "CRC-32 mismatch";
    case CutTableError::kBadNode: return "a node's bounds do not fit the model";
    case CutTableError::kTrailingBytes: return "bytes after the last node";
  }
  return "unknown error";
}

ModelTag model_tag(const uint8_t* file, size_t size) {
  ModelTag t;
  t.bytes = size;
  t.crc = size >= 4 ? load_u32le(file + size - 4) : 0;
  return t;
}

size_t cut_table_bytes(uint32_t node_count) { return kCutTableHeaderBytes + kBoundBytes * size_t{node_count}; }

void cut_table_header(const ModelTag& tag, const ConeRule& cones, const CutBounds& bounds,
                      uint8_t out[kCutTableHeaderBytes]) {
  for (size_t i = 0; i < kCutTableHeaderBytes; ++i) out[i] = 0;
  for (size_t i = 0; i < sizeof kMagic; ++i) out[i] = kMagic[i];
  store_u16le(out + 8, kCutTableVersion);
  store_u16le(out + 10, kBoundBytes);
  store_u32le(out + 12, bounds.node_count());
  store_u32le(out + 16, static_cast<uint32_t>(tag.bytes));
  store_u32le(out + 20, static_cast<uint32_t>(tag.bytes >> 32));
  store_u32le(out + 24, tag.crc);
  store_u16le(out + 28, cones.gamma_q8);
  store_u16le(out + 30, cones.leaf_gamma_q8);
  out[32] = bounds.normals() ? 1 : 0;
  store_u32le(out + 60, crc32(static_cast<const uint8_t*>(bounds.table()), kBoundBytes * size_t{bounds.node_count()}));
}

CutTableResult cut_table_attach(const uint8_t* data, size_t size, const SpgView& view, const ModelTag& tag,
                                const ConeRule& cones, CutBounds* out) {
  CutTableResult r;
  *out = CutBounds{};  // unattached unless the table is accepted
  const auto fail = [&](CutTableError e) {
    r.error = e;
    return r;
  };
  if (size < kCutTableHeaderBytes) return fail(CutTableError::kTruncated);
  for (size_t i = 0; i < sizeof kMagic; ++i)
    if (data[i] != kMagic[i]) return fail(CutTableError::kBadMagic);
  if (load_u16le(data + 8) != kCutTableVersion || load_u16le(data + 10) != kBoundBytes)
    return fail(CutTableError::kBadVersion);
  for (size_t i = 33; i < 60; ++i)
    if (data[i] != 0) return fail(CutTableError::kBadVersion);  // reserved: a later version's
  const uint32_t n = load_u32le(data + 12);
  if (n != view.header.node_count || load_u64le(data + 16) != tag.bytes ||
      load_u32le(data + 24) != tag.crc)
    return fail(CutTableError::kOtherModel);
  const bool normals = data[32] != 0;
  if (data[32] > 1 || normals != view.header.has_normals()) return fail(CutTableError::kOtherModel);
  // Without normals no cone is kept: any rule's table is the same.
  if (normals && (load_u16le(data + 28) != cones.gamma_q8 || load_u16le(data + 30) != cones.leaf_gamma_q8))
    return fail(CutTableError::kOtherCones);
  const size_t nodes = kBoundBytes * size_t{n};
  if (size - kCutTableHeaderBytes < nodes) return fail(CutTableError::kTruncated);
  if (size - kCutTableHeaderBytes > nodes) return fail(CutTableError::kTrailingBytes);
  if (crc32(data + kCutTableHeaderBytes, nodes) != load_u32le(data + 60)) return fail(CutTableError::kBadChecksum);
  const CutStatus s = out->attach(view, data + kCutTableHeaderBytes, nodes, &r.node, &r.field);
  if (s != CutStatus::kOk) return fail(CutTableError::kBadNode);
  return r;
}

}  // namespace stipple
