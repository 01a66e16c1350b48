// stipple server — timing over an emulated link. See link_timing.h.
#include "tools/server/link_timing.h"

#include <algorithm>

#include "core/protocol.h"
#include "core/stream.h"
#include "tools/embedded/remote.h"
#include "tools/server/server.h"

namespace stipple {

bool time_over_link(const std::vector<uint8_t>& file, const LinkProfile& down, const LinkProfile& up,
                    const ClientConfig& config, const std::vector<Camera>& cameras, LinkTiming& out, std::string& error,
                    bool coded) {
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
  std::vector<uint32_t> part_storage(config.node_capacity);
  receiver.use_part_storage(part_storage.data(), config.node_capacity);
  uint16_t sequence = 0;
  const auto send = [&](MessageType type, const uint8_t* payload, size_t size) {
    const size_t n = write_frame(type, sequence++, payload, size, frame.data(), frame.size());
    for (size_t at = 0; at < n;) {
      size_t moved = 0;
      (void)pipe.client().write(frame.data() + at, n - at, &moved);
      at += moved;
    }
  };
  // What the client draws, every 50 ms of link time until the first view
  // converges: the pixels it covers (anything but the black background).
  const RasterConfig& r = config.raster;
  const size_t pixel_bytes = r.format == PixelFormat::kRgb565 ? 2 : 3;
  const size_t stride = r.width * pixel_bytes;
  std::vector<uint8_t> image(stride * r.height);
  std::vector<std::vector<bool>> drawn;
  bool sampling = true;
  uint64_t next_sample_us = 0;
  const auto covered = [&] {
    std::vector<bool> mask(size_t{r.width} * r.height, false);
    if (client.node_count() > 0 && client.render(cameras[0], image.data(), stride) == ClientStatus::kOk)
      for (size_t i = 0; i < mask.size(); ++i)
        for (size_t b = 0; b < pixel_bytes; ++b) mask[i] = mask[i] || image[i * pixel_bytes + b] != 0;
    return mask;
  };
  // Runs the loop in 100 us steps of simulated time until `done`.
  const auto run_until = [&](auto done, double limit_s) {
    uint8_t buf[4096];
    while (!done()) {
      if (sampling && pipe.now_us() >= next_sample_us) {
        drawn.push_back(covered());
        next_sample_us += 50000;
      }
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
  Hello hello = hello_for(config);
  if (!coded) hello.attributes = static_cast<uint8_t>(hello.attributes & ~kWantCoded);
  write_hello(hello, payload);
  send(MessageType::kHello, payload, kHelloBytes);
  CameraUpdate u;
  u.camera = cameras[0];
  write_camera_update(u, payload);
  send(MessageType::kCamera, payload, kCameraUpdateBytes);
  if (!run_until([&] { return client.node_count() > 0; }, 3600)) return error = "no node arrived", false;
  out.first_image_s = static_cast<double>(pipe.now_us()) / 1e6;
  if (!run_until([&] { return receiver.converged(0); }, 3600)) return error = "the first view did not converge", false;
  out.converged_s = static_cast<double>(pipe.now_us()) / 1e6;
  out.converged_bytes = receiver.bytes_received();
  sampling = false;
  {
    const std::vector<bool> whole = covered();
    const auto share = [&](const std::vector<bool>& m) {
      size_t both = 0, all = 0;
      for (size_t i = 0; i < whole.size(); ++i) {
        all += whole[i];
        both += whole[i] && m[i];
      }
      return all == 0 ? 1.0 : static_cast<double>(both) / static_cast<double>(all);
    };
    out.coverage.clear();
    for (const std::vector<bool>& m : drawn) out.coverage.push_back(share(m));
    const auto whole_enough = std::find_if(out.coverage.begin(), out.coverage.end(), [](double c) { return c >= 0.9; });
    out.silhouette_s = whole_enough == out.coverage.end() ? out.converged_s
                                                          : 0.05 * static_cast<double>(whole_enough - out.coverage.begin());
  }
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
  out.orbit_step_bytes = cameras.size() > 1 ? static_cast<double>(receiver.bytes_received() - out.converged_bytes) /
                                                  static_cast<double>(cameras.size() - 1)
                                            : 0;
  out.bytes_down = receiver.bytes_received();
  out.cut_nodes = client.node_count();
  return true;
}

}  // namespace stipple
