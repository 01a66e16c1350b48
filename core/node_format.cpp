// stipple core — bit packing of node records. See node_format.h.
#include "core/node_format.h"

namespace stipple {

void pack_record(const RecordLayout& layout, const NodeFields& fields, uint8_t* out) {
  const int bytes = layout.record_bytes();
  for (int i = 0; i < bytes; ++i) out[i] = 0;
  int bit = 0;
  for (int f = 0; f < kFieldCount; ++f) {
    const int w = layout.bits[f];
    const uint32_t value = fields.v[f] & ((1u << w) - 1u);
    for (int k = 0; k < w; ++k, ++bit) {
      if ((value >> k) & 1u) out[bit >> 3] = static_cast<uint8_t>(out[bit >> 3] | (1u << (bit & 7)));
    }
  }
}

NodeFields unpack_record(const RecordLayout& layout, const uint8_t* in) {
  NodeFields fields;
  int bit = 0;
  for (int f = 0; f < kFieldCount; ++f) {
    const int w = layout.bits[f];
    uint32_t value = 0;
    for (int k = 0; k < w; ++k, ++bit) value |= static_cast<uint32_t>((in[bit >> 3] >> (bit & 7)) & 1u) << k;
    fields.v[f] = static_cast<uint16_t>(value);
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
