// Fuzz harness: the serial line's receiving end, as the server runs it for a
// serial client — the COBS deframer with the server's buffer, each packet
// read as one frame at the sequence its header claims — and the deframer
// alone with a small buffer, where most packets overflow. Checked: a packet
// never exceeds its buffer, a dropped one is counted, and after a zero byte
// the deframer starts clean (the bytes after it decode as they would alone).
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/cobs.h"
#include "core/protocol.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace stipple;
  static std::vector<uint8_t> big(4096 + 16), small(32), reader_storage(4096), again(4096 + 16);
  CobsDeframer d;
  d.init(big.data(), big.size());
  FrameReader reader;
  reader.init(reader_storage.data(), reader_storage.size());
  uint32_t packets = 0;
  size_t last_zero = size;
  for (size_t i = 0; i < size; ++i) {
    const uint32_t dropped = d.dropped();
    const CobsStatus s = d.push(data[i]);
    if (data[i] == 0 && last_zero == size) last_zero = i;
    if (s == CobsStatus::kDropped && d.dropped() != dropped + 1) __builtin_trap();
    if (s != CobsStatus::kPacket) continue;
    ++packets;
    if (d.packet_bytes() > big.size()) __builtin_trap();
    if (d.packet_bytes() < kFrameHeaderBytes) continue;
    reader.reset();
    reader.expect(load_u16le(d.packet() + 2));
    reader.feed(d.packet(), d.packet_bytes());
    Frame f;
    if (reader.next(&f) == FrameStatus::kOk && f.payload_bytes > d.packet_bytes()) __builtin_trap();
  }
  // Resynchronisation: from the first zero on, a fresh deframer sees the same packets.
  if (last_zero < size) {
    CobsDeframer a, b;
    a.init(again.data(), again.size());
    b.init(big.data(), big.size());
    for (size_t i = 0; i < size; ++i) {
      const CobsStatus sb = b.push(data[i]);
      if (i <= last_zero) continue;
      const CobsStatus sa = a.push(data[i]);
      if (sa != sb) __builtin_trap();
      if (sa == CobsStatus::kPacket &&
          (a.packet_bytes() != b.packet_bytes() || !std::equal(a.packet(), a.packet() + a.packet_bytes(), b.packet())))
        __builtin_trap();
    }
  }
  // A small buffer: overflows are dropped, never written past.
  CobsDeframer tiny;
  tiny.init(small.data(), small.size());
  for (size_t i = 0; i < size; ++i)
    if (tiny.push(data[i]) == CobsStatus::kPacket && tiny.packet_bytes() > small.size()) __builtin_trap();
  (void)packets;
  return 0;
}
