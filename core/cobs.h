// stipple core — byte stuffing for the serial line: Consistent Overhead Byte
// Stuffing (Cheshire and Baker, "Consistent Overhead Byte Stuffing", IEEE/ACM
// Transactions on Networking 7(2), 1999). An encoded packet has no zero
// byte; a zero ends it. A receiver that loses bytes or sees noise drops at
// most the packet it is in and resynchronises at the next zero.
//
// Integer-only, allocation-free: the encoder writes into a caller buffer
// (cobs_bound says how large), the deframer collects into caller storage.
#pragma once

#include <cstddef>
#include <cstdint>

namespace stipple {

// The most bytes cobs_encode writes for `size` input bytes, the final zero included.
constexpr size_t cobs_bound(size_t size) { return size + size / 254 + 2; }

// Encodes data[0 .. size) and appends the zero delimiter; returns the bytes
// written, or 0 when `capacity` is below cobs_bound(size).
size_t cobs_encode(const uint8_t* data, size_t size, uint8_t* out, size_t capacity);

// Decodes one packet (without its zero) in place or into `out` (which may be
// `data`); returns the decoded length, or SIZE_MAX when the packet is not
// valid COBS (a code byte pointing past its end, or a zero inside).
size_t cobs_decode(const uint8_t* data, size_t size, uint8_t* out);

enum class CobsStatus : uint8_t { kNone, kPacket, kDropped };

// Splits a byte stream into decoded packets. Bytes of a packet longer than
// the storage, or not valid COBS, are dropped up to the next zero and
// counted.
class CobsDeframer {
 public:
  void init(uint8_t* storage, size_t bytes);
  // Takes one byte. kPacket: packet() / packet_bytes() hold a decoded packet
  // until the next call; kDropped: a bad packet ended here.
  CobsStatus push(uint8_t byte);
  const uint8_t* packet() const { return buffer_; }
  size_t packet_bytes() const { return packet_bytes_; }
  uint32_t dropped() const { return dropped_; }

 private:
  uint8_t* buffer_ = nullptr;
  size_t capacity_ = 0, used_ = 0, packet_bytes_ = 0;
  bool overflow_ = false;
  uint32_t dropped_ = 0;
};

}  // namespace stipple
