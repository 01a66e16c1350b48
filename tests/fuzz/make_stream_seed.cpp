// Writes the stream fuzzer's seeds (tests/fuzz/seeds/sphere_stream.{bin,cobs})
// with core's own sender, so they follow the protocol as it is: the startup of
// the 600-point sphere fixture, a coarse cut of it (a few dozen nodes), an
// update-end, a finer cut's change (nodes and drops) and its update-end — as
// a socket carries them, and each frame COBS-framed as a serial line does;
// and the server fuzzer's seeds (client_stream.{bin,cobs}): what a client
// sends — a hello, two cameras, an ack, a resend, a keep-alive, a close.
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
  hello.attributes |= kWantCoded;  // protocol 5: code tables and coded batches
  bool ok = sender.start(hello, Link::sink, &link);
  CameraUpdate u;
  u.camera = camera_at(decoder.extent_mu(), 0);
  ok = ok && sender.update(u, true, Link::sink, &link);
  u.sequence = 1;
  u.camera = camera_at(decoder.extent_mu(), 0x20000000u);  // 45 degrees on: nodes enter and leave
  ok = ok && sender.update(u, true, Link::sink, &link);
  if (!ok) return std::fprintf(stderr, "make_stream_seed: the sender refused\n"), 1;
  // The client's side of the same conversation.
  Link up;
  std::vector<uint8_t> frame(kMaxFrameBytes);
  uint16_t sequence = 0;
  const auto say = [&](MessageType type, const uint8_t* payload, size_t bytes) {
    const size_t n = write_frame(type, sequence++, payload, bytes, frame.data(), frame.size());
    Link::sink(&up, frame.data(), n);
  };
  uint8_t payload[kCameraUpdateBytes];
  write_hello(hello, payload);
  say(MessageType::kHello, payload, kHelloBytes);
  u.sequence = 0;
  u.camera = camera_at(decoder.extent_mu(), 0);
  write_camera_update(u, payload);
  say(MessageType::kCamera, payload, kCameraUpdateBytes);
  write_sequence(3, payload);
  say(MessageType::kAck, payload, kSequenceBytes);
  write_sequence(2, payload);
  say(MessageType::kResend, payload, kSequenceBytes);
  u.sequence = 1;
  u.camera = camera_at(decoder.extent_mu(), 0x20000000u);
  write_camera_update(u, payload);
  say(MessageType::kCamera, payload, kCameraUpdateBytes);
  say(MessageType::kKeepAlive, nullptr, 0);
  write_fault(Fault{}, payload);
  say(MessageType::kClose, payload, kFaultBytes);
  const std::string dir = argv[2];
  if (!write_file_atomic(dir + "/sphere_stream.bin", link.bytes, error) ||
      !write_file_atomic(dir + "/sphere_stream.cobs", link.cobs, error) ||
      !write_file_atomic(dir + "/client_stream.bin", up.bytes, error) ||
      !write_file_atomic(dir + "/client_stream.cobs", up.cobs, error))
    return std::fprintf(stderr, "make_stream_seed: %s\n", error.c_str()), 1;
  std::printf("%s/sphere_stream.bin: %zu bytes; sphere_stream.cobs: %zu bytes\n", dir.c_str(), link.bytes.size(),
              link.cobs.size());
  return 0;
}
