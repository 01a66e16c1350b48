// stipple core — COBS byte stuffing. See cobs.h.
#include "core/cobs.h"

namespace stipple {

size_t cobs_encode(const uint8_t* data, size_t size, uint8_t* out, size_t capacity) {
  if (capacity < cobs_bound(size)) return 0;
  size_t code_at = 0, at = 1;
  uint8_t code = 1;
  for (size_t i = 0; i < size; ++i) {
    if (data[i] == 0) {
      out[code_at] = code;
      code_at = at++;
      code = 1;
      continue;
    }
    out[at++] = data[i];
    if (++code == 0xFF) {  // a full block of 254 non-zero bytes
      out[code_at] = code;
      code_at = at++;
      code = 1;
    }
  }
  out[code_at] = code;
  out[at++] = 0;
  return at;
}

size_t cobs_decode(const uint8_t* data, size_t size, uint8_t* out) {
  size_t in = 0, at = 0;
  while (in < size) {
    const uint8_t code = data[in++];
    if (code == 0 || in + code - 1 > size) return SIZE_MAX;
    for (uint8_t k = 1; k < code; ++k) {
      if (data[in] == 0) return SIZE_MAX;
      out[at++] = data[in++];
    }
    if (code != 0xFF && in < size) out[at++] = 0;
  }
  return at;
}

void CobsDeframer::init(uint8_t* storage, size_t bytes) {
  buffer_ = storage;
  capacity_ = bytes;
  used_ = packet_bytes_ = 0;
  overflow_ = false;
  dropped_ = 0;
}

CobsStatus CobsDeframer::push(uint8_t byte) {
  if (byte != 0) {
    if (used_ < capacity_) buffer_[used_++] = byte;
    else overflow_ = true;
    return CobsStatus::kNone;
  }
  const size_t n = used_;
  const bool overflow = overflow_;
  used_ = 0;
  overflow_ = false;
  if (n == 0 && !overflow) return CobsStatus::kNone;  // an empty packet: idle line
  const size_t decoded = overflow ? SIZE_MAX : cobs_decode(buffer_, n, buffer_);
  if (decoded == SIZE_MAX) {
    ++dropped_;
    return CobsStatus::kDropped;
  }
  packet_bytes_ = decoded;
  return CobsStatus::kPacket;
}

}  // namespace stipple
