// Writes the stream fuzzer's seeds (tests/fuzz/seeds/sphere_stream.{bin,cobs})
// with core's own sender, so they follow the protocol as it is: the startup of
// the 600-point sphere fixture, a coarse cut of it (a few dozen nodes), an
// update-end, a finer cut's change (nodes and drops) and its update-end — as
// a socket carries them, and each frame COBS-framed as a serial line does.
// Regenerate after a deliberate protocol change:
//   make_stream_seed tests/data/sphere600_normals.spg tests/fuzz/seeds
#include <cstdio>
#include <string>
#include <vector>

#include "core/cobs.h"
#include "core/node_decoder.h"
#include "core/protocol.h"
#include "core/stream.h"
#include "core/view_cut.h"
#include "platform/file_io.h"

namespace {

using namespace stipple;

struct Link {
  std::vector<uint8_t> bytes, cobs;
  static bool sink(void* self, const uint8_t* frame, size_t size) {
    auto* l = static_cast<Link*>(self);
    l->bytes.insert(l->bytes.end(), frame, frame + size);
    std::vector<uint8_t> packet(size + size / 254 + 2);
    const size_t n = cobs_encode(frame, size, packet.data(), packet.size());
    l->cobs.insert(l->cobs.end(), packet.begin(), packet.begin() + static_cast<ptrdiff_t>(n));
    l->cobs.push_back(0);
    return true;
  }
};

Camera camera_at(const int32_t extent[3], uint32_t yaw) {
  OrbitView o;
  for (int a = 0; a < 3; ++a) o.target_mu[a] = extent[a] / 2;
  o.distance_mu = 3 << 24;
  o.yaw = yaw;
  o.pitch = 0x0E000000u;  // ~20 degrees
  o.fov = 0x18E38E39u;    // 35 degrees
  Camera c;
  if (!orbit_camera(o, 240, 320, &c)) std::fprintf(stderr, "make_stream_seed: the camera is out of range\n");
  return c;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: make_stream_seed MODEL.spg OUTPUT_DIR\n");
    return 2;
  }
  std::vector<uint8_t> file;
  std::string error;
  if (!read_file(argv[1], file, error)) return std::fprintf(stderr, "make_stream_seed: %s\n", error.c_str()), 1;
  SpgView view;
  if (!spg_parse(file.data(), file.size(), &view).ok()) return std::fprintf(stderr, "make_stream_seed: %s: not a valid .spg\n", argv[1]), 1;
  std::vector<uint32_t> decoder_storage(node_decoder_bytes(view.header) / 4 + 1);
  NodeDecoder decoder;
  std::vector<uint64_t> bounds_storage(CutBounds::bytes(view.header) / 8 + 1);
  CutBounds bounds;
  if (decoder.init(view, decoder_storage.data(), decoder_storage.size() * 4) != DecodeStatus::kOk ||
      bounds.init(view, decoder, bounds_storage.data(), bounds_storage.size() * 8) != CutStatus::kOk)
    return std::fprintf(stderr, "make_stream_seed: the model does not decode\n"), 1;
  std::vector<uint64_t> sender_storage(StreamSender::storage_bytes(view.header) / 8 + 1);
  StreamSender sender;
  if (!sender.init(view, bounds, sender_storage.data(), sender_storage.size() * 8))
    return std::fprintf(stderr, "make_stream_seed: the sender does not start\n"), 1;
  Link link;
  Hello hello;
  hello.cache_capacity = 64;  // a coarse cut: a few dozen nodes
  bool ok = sender.start(hello, Link::sink, &link);
  CameraUpdate u;
  u.camera = camera_at(decoder.extent_mu(), 0);
  ok = ok && sender.update(u, true, Link::sink, &link);
  u.sequence = 1;
  u.camera = camera_at(decoder.extent_mu(), 0x20000000u);  // 45 degrees on: nodes enter and leave
  ok = ok && sender.update(u, true, Link::sink, &link);
  if (!ok) return std::fprintf(stderr, "make_stream_seed: the sender refused\n"), 1;
  const std::string dir = argv[2];
  if (!write_file_atomic(dir + "/sphere_stream.bin", link.bytes, error) ||
      !write_file_atomic(dir + "/sphere_stream.cobs", link.cobs, error))
    return std::fprintf(stderr, "make_stream_seed: %s\n", error.c_str()), 1;
  std::printf("%s/sphere_stream.bin: %zu bytes; sphere_stream.cobs: %zu bytes\n", dir.c_str(), link.bytes.size(),
              link.cobs.size());
  return 0;
}
