// What decoding protocol 5's coded batches costs a client, beside protocol
// 4's compact ones: core only, so it builds for the host and for any target
// (tools/bench/coded_stream_cost.sh builds it both ways and counts an ARMv5
// run in qemu-user).
//
//   coded_stream_cost record MODEL.spg DIR   (host) writes DIR/coded.bin and
//       DIR/compact.bin: a 240x320 client's stream (60,000-node cache) — the
//       model, a cold start at yaw 30 and 12 orbit steps of 3 degrees
//   coded_stream_cost receive STREAM CAPACITY PASSES   (any target) feeds the
//       stream to a receiver over a node cache PASSES times; prints the nodes
//       and bytes of one pass
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "core/camera.h"
#include "core/node_decoder.h"
#include "core/spg_format.h"
#include "core/stream.h"
#include "core/view_cut.h"

namespace {

using namespace stipple;

std::vector<uint8_t> read_all(const char* path) {
  std::vector<uint8_t> bytes;
  std::FILE* f = std::fopen(path, "rb");
  if (f == nullptr) return bytes;
  uint8_t chunk[65536];
  for (size_t n; (n = std::fread(chunk, 1, sizeof chunk, f)) > 0;) bytes.insert(bytes.end(), chunk, chunk + n);
  std::fclose(f);
  return bytes;
}

bool write_all(const std::string& path, const std::vector<uint8_t>& bytes) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (f == nullptr) return false;
  const bool ok = std::fwrite(bytes.data(), 1, bytes.size(), f) == bytes.size();
  return std::fclose(f) == 0 && ok;
}

bool sink(void* self, const uint8_t* frame, size_t size) {
  auto* out = static_cast<std::vector<uint8_t>*>(self);
  out->insert(out->end(), frame, frame + size);
  return true;
}

int record(const char* model, const std::string& dir) {
  const std::vector<uint8_t> file = read_all(model);
  SpgView view;
  if (file.empty() || !spg_parse(file.data(), file.size(), &view).ok()) return std::fprintf(stderr, "%s: not a valid .spg\n", model), 1;
  std::vector<uint32_t> decoder_storage(node_decoder_bytes(view.header) / 4 + 1);
  NodeDecoder decoder;
  std::vector<uint64_t> bounds_storage(CutBounds::bytes(view.header) / 8 + 1);
  CutBounds bounds;
  if (decoder.init(view, decoder_storage.data(), decoder_storage.size() * 4) != DecodeStatus::kOk ||
      bounds.init(view, decoder, bounds_storage.data(), bounds_storage.size() * 8) != CutStatus::kOk)
    return std::fprintf(stderr, "%s: does not decode\n", model), 1;
  for (const bool coded : {true, false}) {
    std::vector<uint64_t> storage(StreamSender::storage_bytes(view.header) / 8 + 1);
    StreamSender sender;
    if (!sender.init(view, bounds, storage.data(), storage.size() * 8)) return std::fprintf(stderr, "no sender\n"), 1;
    std::vector<uint8_t> stream;
    Hello hello;
    hello.cache_capacity = 60000;
    if (coded) hello.attributes |= kWantCoded;
    if (!sender.start(hello, sink, &stream)) return std::fprintf(stderr, "no start\n"), 1;
    for (uint32_t step = 0; step <= 12; ++step) {
      OrbitView o;
      for (int a = 0; a < 3; ++a) o.target_mu[a] = decoder.extent_mu()[a] / 2;
      o.distance_mu = 3 << 24;
      o.yaw = 0x15555555u + step * 35791394u;  // 30 degrees, then 3-degree steps
      o.pitch = 0x0E38E38Eu;                    // 20 degrees
      CameraUpdate u;
      u.sequence = step;
      if (!orbit_camera(o, 240, 320, &u.camera) || !sender.update(u, true, sink, &stream))
        return std::fprintf(stderr, "update %u failed\n", step), 1;
    }
    const std::string path = dir + (coded ? "/coded.bin" : "/compact.bin");
    if (!write_all(path, stream)) return std::fprintf(stderr, "%s: cannot write\n", path.c_str()), 1;
    std::printf("%s: %zu bytes\n", path.c_str(), stream.size());
  }
  return 0;
}

int receive(const char* path, uint32_t capacity, int passes) {
  const std::vector<uint8_t> stream = read_all(path);
  if (stream.empty()) return std::fprintf(stderr, "%s: cannot read\n", path), 1;
  NodeCacheLimits limits;
  limits.node_capacity = capacity;
  std::vector<uint64_t> cache_storage(node_cache_bytes(limits) / 8 + 1);
  NodeCache cache;
  std::vector<uint8_t> reader(kMaxFrameBytes);
  std::vector<uint32_t> part(capacity);
  if (cache.init(limits, cache_storage.data(), cache_storage.size() * 8) != CacheStatus::kOk)
    return std::fprintf(stderr, "no cache\n"), 1;
  uint64_t nodes = 0;
  for (int pass = 0; pass < passes; ++pass) {
    StreamReceiver r;
    r.init(&cache, reader.data(), reader.size());
    r.use_part_storage(part.data(), capacity);
    if (r.receive(stream.data(), stream.size()) != ReceiveStatus::kOk)
      return std::fprintf(stderr, "%s: %s\n", path, receive_status_text(r.receive(nullptr, 0))), 1;
    nodes = r.nodes_received();
  }
  std::printf("%s: %llu nodes, %zu bytes a pass\n", path, static_cast<unsigned long long>(nodes), stream.size());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 4 && !std::strcmp(argv[1], "record")) return record(argv[2], argv[3]);
  if (argc == 5 && !std::strcmp(argv[1], "receive"))
    return receive(argv[2], static_cast<uint32_t>(std::strtoul(argv[3], nullptr, 10)), std::atoi(argv[4]));
  std::fprintf(stderr,
               "usage: coded_stream_cost record MODEL.spg DIR\n"
               "       coded_stream_cost receive STREAM CAPACITY PASSES\n");
  return argc == 2 && !std::strcmp(argv[1], "--help") ? 0 : 2;
}
