// Fuzz harness: the client end of the node stream — the frame reader and
// StreamReceiver applying frames to a node cache — over any bytes a socket
// can carry, and the same bytes as a serial line: through the COBS deframer,
// each packet a frame. Must never crash, overrun or hang; every fault must
// leave the cache usable (it is reloaded by the next valid startup).
// Seed: tests/fuzz/seeds/bunny_stream.bin, a recorded stream (startup, the
// cold cut of the default view, one update-end).
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/cobs.h"
#include "core/node_cache.h"
#include "core/protocol.h"
#include "core/stream.h"

namespace {

struct Harness {
  std::vector<uint64_t> cache_storage;
  stipple::NodeCache cache;
  std::vector<uint8_t> reader_storage = std::vector<uint8_t>(stipple::kMaxFrameBytes);
  std::vector<uint8_t> cobs_storage = std::vector<uint8_t>(stipple::kMaxFrameBytes + 64);
  std::vector<uint32_t> part_storage = std::vector<uint32_t>(512);  // coded batches (protocol 5)
  Harness() {
    stipple::NodeCacheLimits l;
    l.node_capacity = 512;
    cache_storage.resize(stipple::node_cache_bytes(l) / 8 + 1);
    (void)cache.init(l, cache_storage.data(), cache_storage.size() * 8);
  }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static Harness h;
  // As a socket stream, in pieces of a size the input chooses.
  stipple::StreamReceiver r;
  r.init(&h.cache, h.reader_storage.data(), h.reader_storage.size());
  r.use_part_storage(h.part_storage.data(), static_cast<uint32_t>(h.part_storage.size()));
  const size_t piece = size > 0 ? 1 + data[0] % 97 : 1;
  for (size_t at = 0; at < size; at += piece) {
    const size_t n = size - at < piece ? size - at : piece;
    if (r.receive(data + at, n) != stipple::ReceiveStatus::kOk) break;
  }
  (void)h.cache.has(stipple::NodeId{0});
  // As a serial line: packets between zeros, each checked as a frame.
  stipple::CobsDeframer d;
  d.init(h.cobs_storage.data(), h.cobs_storage.size());
  stipple::FrameReader reader;
  for (size_t i = 0; i < size; ++i) {
    if (d.push(data[i]) != stipple::CobsStatus::kPacket) continue;
    reader.init(h.reader_storage.data(), h.reader_storage.size());
    reader.feed(d.packet(), d.packet_bytes());
    stipple::Frame f;
    while (reader.next(&f) == stipple::FrameStatus::kOk) {
      stipple::NodeBatch b;
      (void)stipple::parse_nodes(f.payload, f.payload_bytes, 13, 100000, &b);
    }
  }
  return 0;
}
