// stipple server — timing over an emulated link. See link_timing.h.
#include "tools/server/link_timing.h"

#include "core/protocol.h"
#include "core/stream.h"
#include "tools/embedded/remote.h"
#include "tools/server/server.h"

namespace stipple {

bool time_over_link(const std::vector<uint8_t>& file, const LinkProfile& down, const LinkProfile& up,
                    const ClientConfig& config, const std::vector<Camera>& cameras, LinkTiming& out, std::string& error) {
  Server server;
  if (!server.init(file, "model", ServerOptions{}, error)) return false;
  ShapedPipe pipe(down, up);
  server.add_client(std::make_unique<TransportRef>(pipe.server()), -1, "shaped");
  std::vector<uint64_t> arena(client_arena_bytes(config) / 8 + 1);
  Client client;
  if (client.init(config, arena.data(), arena.size() * 8) != ClientStatus::kOk) return error = "client setup failed", false;
  std::vector<uint8_t> reader_storage(kMaxFrameBytes), frame(kMaxFrameBytes);
  StreamReceiver receiver;
  receiver.init(&client.cache(), reader_storage.data(), reader_storage.size());
  uint16_t sequence = 0;
  const auto send = [&](MessageType type, const uint8_t* payload, size_t size) {
    const size_t n = write_frame(type, sequence++, payload, size, frame.data(), frame.size());
    for (size_t at = 0; at < n;) {
      size_t moved = 0;
      (void)pipe.client().write(frame.data() + at, n - at, &moved);
      at += moved;
    }
  };
  // Runs the loop in 100 us steps of simulated time until `done`.
  const auto run_until = [&](auto done, double limit_s) {
    uint8_t buf[4096];
    while (!done()) {
      server.step(0);
      size_t got = 0;
      while (pipe.client().read(buf, sizeof buf, &got) == TransportStatus::kOk && got > 0)
        if (receiver.receive(buf, got) != ReceiveStatus::kOk) return false;
      if (done()) break;
      pipe.advance(100);
      if (static_cast<double>(pipe.now_us()) > limit_s * 1e6) return false;
    }
    return true;
  };
  uint8_t payload[kCameraUpdateBytes];
  write_hello(hello_for(config), payload);
  send(MessageType::kHello, payload, kHelloBytes);
  CameraUpdate u;
  u.camera = cameras[0];
  write_camera_update(u, payload);
  send(MessageType::kCamera, payload, kCameraUpdateBytes);
  if (!run_until([&] { return client.node_count() > 0; }, 3600)) return error = "no node arrived", false;
  out.first_image_s = static_cast<double>(pipe.now_us()) / 1e6;
  if (!run_until([&] { return receiver.converged(0); }, 3600)) return error = "the first view did not converge", false;
  out.converged_s = static_cast<double>(pipe.now_us()) / 1e6;
  double steps = 0;
  for (uint32_t k = 1; k < cameras.size(); ++k) {
    const uint64_t start = pipe.now_us();
    u.sequence = k;
    u.camera = cameras[k];
    write_camera_update(u, payload);
    send(MessageType::kCamera, payload, kCameraUpdateBytes);
    if (!run_until([&] { return receiver.converged(k); }, 3600)) return error = "an orbit view did not converge", false;
    steps += static_cast<double>(pipe.now_us() - start) / 1e6;
  }
  out.orbit_step_s = cameras.size() > 1 ? steps / static_cast<double>(cameras.size() - 1) : 0;
  out.bytes_down = receiver.bytes_received();
  out.cut_nodes = client.node_count();
  return true;
}

}  // namespace stipple
