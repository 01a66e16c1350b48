// stipple load — many orbiting clients against a server: what it sustains.
//
// Each client is a TCP connection that says hello and then sends a camera
// update of its own orbit at a fixed rate, whatever came back; it reads the
// stream (frames are checked for their length and CRC, not applied: no
// cache, no renderer, so one process plays a thousand viewers) and times
// each update-end against the camera it answers. The server answers only a
// client's latest camera, so a server that falls behind shows as cameras
// not answered, and as latency.
#include <poll.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "core/protocol.h"
#include "platform/file_io.h"
#include "platform/tcp/tcp_transport.h"
#include "tools/cli/cli.h"
#include "tools/embedded/model_file.h"
#include "tools/embedded/render_options.h"

namespace stipple {
namespace {

const char kLoadHelp[] =
    "usage: stipple load HOST:PORT MODEL.spg [--clients N] [--rate HZ] [--seconds S] [--step DEG]\n"
    "                    [--size WxH] [--cache N] [--no-coding] [--json]\n"
    "\n"
    "Plays N viewers of a running `stipple serve` of MODEL.spg (the same file:\n"
    "its extent places the cameras): each connects, says hello and sends a camera\n"
    "of its own orbit about the model every 1/HZ seconds, STEP degrees on from the\n"
    "last, for S seconds, reading what comes back. Prints how many cameras were\n"
    "answered (the server answers a client's latest camera only: one it skipped\n"
    "was superseded before it got to it), the latency from a camera to its\n"
    "update-end (p50, p99, largest) and the bytes received.\n"
    "\n"
    "  --clients N    viewers at once (default 100)\n"
    "  --rate HZ      camera updates a second, each (default 30)\n"
    "  --seconds S    how long (default 10)\n"
    "  --step DEG     orbit step between a viewer's cameras (default 3)\n"
    "  --size WxH     the viewers' screen (default 240x320)\n"
    "  --cache N      the node capacity they declare (default 30000)\n"
    "  --no-coding    viewers asking for protocol 4's compact batches (default:\n"
    "                 entropy-coded ones, as every stipple client does)\n"
    "  --json         one JSON object instead of the text\n";

using Clock = std::chrono::steady_clock;

struct Viewer {
  std::unique_ptr<TcpTransport> link;
  int fd = -1;
  uint16_t sequence = 0;  // the next frame's
  uint32_t camera = 0;    // cameras sent
  double yaw = 0;
  Clock::time_point sent_at[64];  // by camera sequence, modulo 64
  std::vector<uint8_t> in;        // bytes of the frame being read
  std::vector<uint8_t> out;       // bytes not yet written
  size_t out_at = 0;
  bool gone = false;
};

}  // namespace

int cmd_load(int argc, char** argv) {
  cli::Args args(argc, argv, 2);
  if (args.flag("--help") || args.flag("-h")) {
    std::fputs(kLoadHelp, stdout);
    return 0;
  }
  std::string v, error;
  unsigned long long clients = 100, rate = 30, seconds = 10, cache = 30000;
  double step = 3;
  if (args.value("--clients", v) && (!cli::parse_uint(v, 100000, clients) || clients == 0))
    return cli::fail("load: --clients: expected 1..100000, got '" + v + "'");
  if (args.value("--rate", v) && (!cli::parse_uint(v, 1000, rate) || rate == 0))
    return cli::fail("load: --rate: expected 1..1000 updates a second, got '" + v + "'");
  if (args.value("--seconds", v) && (!cli::parse_uint(v, 86400, seconds) || seconds == 0))
    return cli::fail("load: --seconds: expected 1..86400, got '" + v + "'");
  if (args.value("--cache", v) && (!cli::parse_uint(v, 1u << 30, cache) || cache == 0))
    return cli::fail("load: --cache: expected a node count, got '" + v + "'");
  if (args.value("--step", v)) {
    char* end = nullptr;
    step = std::strtod(v.c_str(), &end);
    if (end == v.c_str() || *end != '\0' || !(step >= 0 && step <= 180))
      return cli::fail("load: --step: expected 0..180 degrees, got '" + v + "'");
  }
  unsigned width = 240, height = 320;
  if (args.value("--size", v) && (std::sscanf(v.c_str(), "%ux%u", &width, &height) != 2 || width == 0 || height == 0 ||
                                  width > 4096 || height > 4096))
    return cli::fail("load: --size: expected WxH up to 4096x4096, got '" + v + "'");
  const bool json = args.flag("--json");
  const bool coded = !args.flag("--no-coding");
  const std::vector<std::string> files = args.positionals();
  if (args.bad()) return cli::fail("load: " + args.error());
  if (!args.unknown_option().empty()) return cli::fail("load: " + args.unknown_option_message());
  if (files.size() != 2) return cli::fail("load: expected HOST:PORT and the served MODEL.spg (see stipple load --help)");
  std::string host;
  uint16_t port = 0;
  if (!parse_host_port(files[0], "127.0.0.1", host, port, error)) return cli::fail("load: " + error);
  std::vector<uint8_t> file;
  if (!read_spg_file(files[1], file, error)) return cli::fail("load: " + error);
  SpgView view;
  const SpgResult parsed = spg_parse(file.data(), file.size(), &view);
  if (!parsed.ok()) return cli::fail("load: " + spg_error_message(files[1], parsed, file.data(), file.size()));
  std::vector<uint8_t> decoder_storage(node_decoder_bytes(view.header));
  NodeDecoder decoder;
  if (decoder.init(view, decoder_storage.data(), decoder_storage.size()) != DecodeStatus::kOk)
    return cli::fail("load: " + files[1] + ": the angle fields are wider than the decoder supports");
  const ViewSpec base = resolve_view(ViewSpec{}, view.header, decoder.extent_mu());

  // Connect everyone, hello first.
  std::vector<Viewer> viewers(clients);
  Hello hello;
  hello.width = static_cast<uint16_t>(width);
  hello.height = static_cast<uint16_t>(height);
  hello.cache_capacity = static_cast<uint32_t>(cache);
  if (coded) hello.attributes |= kWantCoded;
  const auto queue = [](Viewer& c, MessageType type, const uint8_t* payload, size_t size) {
    uint8_t frame[kFrameHeaderBytes + kCameraUpdateBytes + kFrameTrailerBytes];
    const size_t n = write_frame(type, c.sequence++, payload, size, frame, sizeof frame);
    c.out.insert(c.out.end(), frame, frame + n);
  };
  for (size_t k = 0; k < viewers.size(); ++k) {
    Viewer& c = viewers[k];
    if (!tcp_connect(host, port, 5000, &c.fd, error))
      return cli::fail("load: viewer " + std::to_string(k + 1) + ": " + error);
    c.link = std::make_unique<TcpTransport>(c.fd, files[0]);
    c.yaw = base.yaw + 360.0 * static_cast<double>(k) / static_cast<double>(clients);
    uint8_t payload[kHelloBytes];
    write_hello(hello, payload);
    queue(c, MessageType::kHello, payload, kHelloBytes);
  }

  std::vector<double> latencies;
  uint64_t sent = 0, answered = 0, bytes = 0, frames = 0, closed = 0, refused = 0;
  const auto period = std::chrono::nanoseconds(1000000000ull / rate);
  const Clock::time_point start = Clock::now(), stop = start + std::chrono::seconds(seconds);
  Clock::time_point next = start;
  std::vector<pollfd> fds(viewers.size());
  std::vector<uint8_t> buf(1 << 16);
  while (Clock::now() < stop + std::chrono::milliseconds(500)) {
    const Clock::time_point now = Clock::now();
    if (now >= next && now < stop) {  // every viewer's next camera
      for (Viewer& c : viewers) {
        if (c.gone) continue;
        ViewSpec s = base;
        s.yaw = c.yaw + step * static_cast<double>(c.camera);
        CameraUpdate u;
        u.sequence = c.camera;
        if (!orbit_camera(orbit_view(decoder.extent_mu(), s), hello.width, hello.height, &u.camera))
          return cli::fail("load: an orbit camera is out of range");
        uint8_t payload[kCameraUpdateBytes];
        write_camera_update(u, payload);
        queue(c, MessageType::kCamera, payload, kCameraUpdateBytes);
        c.sent_at[c.camera % 64] = now;
        ++c.camera;
        ++sent;
      }
      next += period;
    }
    for (size_t k = 0; k < viewers.size(); ++k)
      fds[k] = {viewers[k].gone ? -1 : viewers[k].fd,
                static_cast<short>(POLLIN | (viewers[k].out_at < viewers[k].out.size() ? POLLOUT : 0)), 0};
    const auto wait = std::chrono::duration_cast<std::chrono::milliseconds>(next - Clock::now()).count();
    poll(fds.data(), static_cast<nfds_t>(fds.size()), static_cast<int>(std::clamp<long long>(wait, 0, 20)));
    for (size_t k = 0; k < viewers.size(); ++k) {
      Viewer& c = viewers[k];
      if (c.gone) continue;
      while (c.out_at < c.out.size()) {
        size_t moved = 0;
        const TransportStatus s = c.link->write(c.out.data() + c.out_at, c.out.size() - c.out_at, &moved);
        c.out_at += moved;
        if (s != TransportStatus::kOk || moved == 0) break;
      }
      if (c.out_at == c.out.size()) c.out.clear(), c.out_at = 0;
      if (!(fds[k].revents & (POLLIN | POLLHUP | POLLERR))) continue;
      for (;;) {
        size_t got = 0;
        const TransportStatus s = c.link->read(buf.data(), buf.size(), &got);
        if (s == TransportStatus::kClosed || s == TransportStatus::kError) {
          c.gone = true;
          ++closed;
          break;
        }
        if (s != TransportStatus::kOk || got == 0) break;
        bytes += got;
        // Whole frames: header, payload, CRC; update-ends timed.
        c.in.insert(c.in.end(), buf.data(), buf.data() + got);
        size_t at = 0;
        const Clock::time_point t = Clock::now();
        while (c.in.size() - at >= kFrameHeaderBytes) {
          const uint8_t* f = c.in.data() + at;
          const size_t n = kFrameHeaderBytes + load_u32le(f + 4) + kFrameTrailerBytes;
          if (n > kMaxFrameBytes) return cli::fail("load: viewer " + std::to_string(k + 1) + ": an oversized frame");
          if (c.in.size() - at < n) break;
          if (load_u32le(f + n - 4) != crc32(f, n - 4))
            return cli::fail("load: viewer " + std::to_string(k + 1) + ": a frame failed its CRC");
          ++frames;
          if (f[0] == static_cast<uint8_t>(MessageType::kClose)) ++refused;
          if (f[0] == static_cast<uint8_t>(MessageType::kUpdateEnd) && n - kFrameHeaderBytes - kFrameTrailerBytes >= 4) {
            const uint32_t answered_camera = load_u32le(f + kFrameHeaderBytes);
            if (answered_camera < c.camera && c.camera - answered_camera <= 64) {
              ++answered;
              latencies.push_back(std::chrono::duration<double, std::milli>(t - c.sent_at[answered_camera % 64]).count());
            }
          }
          at += n;
        }
        c.in.erase(c.in.begin(), c.in.begin() + static_cast<long>(at));
      }
    }
  }
  std::sort(latencies.begin(), latencies.end());
  const auto pct = [&](double p) {
    return latencies.empty() ? 0.0 : latencies[std::min(latencies.size() - 1, static_cast<size_t>(p * static_cast<double>(latencies.size())))];
  };
  const double share = sent ? static_cast<double>(answered) / static_cast<double>(sent) : 0;
  if (json) {
    cli::Json j;
    j.integer("clients", static_cast<long long>(clients))
        .integer("rate_hz", static_cast<long long>(rate))
        .integer("seconds", static_cast<long long>(seconds))
        .integer("cameras_sent", static_cast<long long>(sent))
        .integer("cameras_answered", static_cast<long long>(answered))
        .num("answered_share", share)
        .num("latency_p50_ms", pct(0.5))
        .num("latency_p99_ms", pct(0.99))
        .num("latency_max_ms", latencies.empty() ? 0.0 : latencies.back())
        .integer("bytes_received", static_cast<long long>(bytes))
        .integer("clients_closed", static_cast<long long>(closed))
        .integer("close_frames", static_cast<long long>(refused));
    std::printf("%s\n", j.done().c_str());
  } else {
    std::printf("%llu viewers at %llu Hz for %llu s: %llu cameras sent, %llu answered (%.1f %%); latency p50 %.1f ms, "
                "p99 %.1f ms, largest %.1f ms; %.1f MB received; %llu closed by the server\n",
                clients, rate, seconds, static_cast<unsigned long long>(sent), static_cast<unsigned long long>(answered),
                100 * share, pct(0.5), pct(0.99), latencies.empty() ? 0.0 : latencies.back(),
                static_cast<double>(bytes) / 1e6, static_cast<unsigned long long>(closed));
  }
  return 0;
}

}  // namespace stipple
