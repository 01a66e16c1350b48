// stipple core — bit packing of node records. See node_format.h.
//
// Fields are at most 16 bits wide and start at any bit, so a field spans at
// most 3 bytes: (bit & 7) + 16 <= 23 < 32. Each field is therefore one
// little-endian 32-bit window read from a zero-padded copy of the record,
// shifted and masked — no per-bit loop, no read past the record.
#include "core/node_format.h"

namespace stipple {
namespace {

constexpr int kPaddedBytes = kMaxRecordBytes + 4;

inline uint32_t window32(const uint8_t* p) {
  return static_cast<uint32_t>(p[0]) | (static_cast<uint32_t>(p[1]) << 8) | (static_cast<uint32_t>(p[2]) << 16) |
         (static_cast<uint32_t>(p[3]) << 24);
}

}  // namespace

void pack_record(const RecordLayout& layout, const NodeFields& fields, uint8_t* out) {
  uint8_t buf[kPaddedBytes] = {};
  int bit = 0;
  for (int f = 0; f < kFieldCount; ++f) {
    const int w = layout.bits[f];
    if (w == 0) continue;
    const uint32_t value = (static_cast<uint32_t>(fields.v[f]) & ((1u << w) - 1u)) << (bit & 7);
    uint8_t* p = buf + (bit >> 3);
    p[0] = static_cast<uint8_t>(p[0] | value);
    p[1] = static_cast<uint8_t>(p[1] | (value >> 8));
    p[2] = static_cast<uint8_t>(p[2] | (value >> 16));
    bit += w;
  }
  const int bytes = layout.record_bytes();
  for (int i = 0; i < bytes; ++i) out[i] = buf[i];
}

NodeFields unpack_record(const RecordLayout& layout, const uint8_t* in) {
  uint8_t buf[kPaddedBytes] = {};
  const int bytes = layout.record_bytes();
  for (int i = 0; i < bytes; ++i) buf[i] = in[i];
  NodeFields fields;
  int bit = 0;
  for (int f = 0; f < kFieldCount; ++f) {
    const int w = layout.bits[f];
    fields.v[f] = static_cast<uint16_t>((window32(buf + (bit >> 3)) >> (bit & 7)) & ((1u << w) - 1u));
    bit += w;
  }
  return fields;
}

bool fields_fit(const RecordLayout& layout, const NodeFields& fields) {
  for (int f = 0; f < kFieldCount; ++f) {
    if ((static_cast<uint32_t>(fields.v[f]) >> layout.bits[f]) != 0) return false;
  }
  return true;
}

}  // namespace stipple
