// Fuzz harness: the client end of a serial line (tools/embedded/remote.h
// with Options::serial) — COBS deframing, whole-frame checks, go-back-N
// resends, a restarted stream, the startup re-sizing the client — fed the
// input as what the line delivers, in pieces whose sizes the input's first
// bytes choose; what the client writes (hello, resends, acks, cameras) goes
// nowhere. It connects, then asks for one view. Checked: no crash, no
// hang (the waits are bounded by the input: an exhausted line reads as
// closed), and a client that converged draws a frame.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "platform/transport.h"
#include "tools/embedded/remote.h"

namespace {

// The line: the input in pieces, then closed; writes are taken and dropped.
class Line final : public stipple::Transport {
 public:
  Line(const uint8_t* data, size_t size) : data_(data), size_(size) {}
  stipple::TransportStatus read(uint8_t* out, size_t capacity, size_t* moved) override {
    *moved = 0;
    if (at_ >= size_) return stipple::TransportStatus::kClosed;
    const size_t piece = std::min({capacity, size_ - at_, size_t{1} + size_t{data_[at_] % 128u}});
    std::copy(data_ + at_, data_ + at_ + piece, out);
    at_ += piece;
    *moved = piece;
    return stipple::TransportStatus::kOk;
  }
  stipple::TransportStatus write(const uint8_t*, size_t size, size_t* moved) override {
    *moved = size;
    return stipple::TransportStatus::kOk;
  }
  void close() override {}
  const char* last_error() const override { return ""; }

 private:
  const uint8_t* data_;
  size_t size_, at_ = 0;
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace stipple;
  Line line(data, size);
  ClientConfig config;
  config.raster = RasterConfig{64, 48, 5, PixelFormat::kRgb565, 4096};
  config.node_capacity = 256;
  config.samples = 64;
  RemoteModel remote;
  RemoteModel::Options o;
  o.serial = true;
  o.pump = [](void*) { return true; };
  o.timeout_ms = 200;
  o.silence_ms = 1000000;  // silences come from the input running out, not the clock
  std::string error;
  if (!remote.connect(line, config, o, error)) return 0;
  OrbitView orbit;
  for (int a = 0; a < 3; ++a) orbit.target_mu[a] = remote.client().decoder().extent_mu()[a] / 2;
  Camera camera;
  if (!orbit_camera(orbit, 64, 48, &camera)) return 0;
  const int32_t window[4] = {0, 0, 0, 0};
  if (!remote.view(camera, 32, window, error)) return 0;
  std::vector<uint8_t> frame(64 * 48 * 2);
  if (!remote.render(camera, frame.data(), 128, nullptr, error)) __builtin_trap();
  return 0;
}
