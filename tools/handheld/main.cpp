// stipple-handheld — the handheld client program: reads a .spg, takes a
// view-dependent cut for the camera, runs the fixed-point client over one arena and
// shows the frame on a Linux framebuffer or writes it as PPM. Builds for
// every target in toolchains/; its frames are the same bytes everywhere
// (`--crc` prints their CRC-32, which the golden-image tests check).
#include <algorithm>
#include <cstdio>
#include <exception>
#include <memory>
#include <new>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include <malloc.h>

#include "platform/fbdev/fbdev_display.h"
#include "platform/file_io.h"
#include "platform/null/null_display.h"
#include "platform/progress.h"
#include "platform/serial/serial_transport.h"
#include "platform/tcp/tcp_transport.h"
#include "tools/embedded/remote.h"
#include "tools/embedded/embedded.h"
#include "tools/embedded/model_file.h"
#include "tools/embedded/render_options.h"

namespace {

const char kUsage[] =
    "usage: stipple-handheld MODEL.spg [options]\n"
    "       stipple-handheld --connect HOST:PORT | --serial DEV [options]\n"
    "\n"
    "The handheld client: fixed point, one arena, no heap after start-up. Draws\n"
    "the view-dependent cut of MODEL.spg for an orbit camera (the same options and\n"
    "the same pixels as `stipple render`).\n"
    "\n";
const char kUsageOutput[] =
    "program:\n"
    "  --connect HOST:PORT    receive the nodes from `stipple serve` (no MODEL.spg):\n"
    "                         the server cuts for this view, the client draws\n"
    "  --serial DEV           the same over a serial line (`stipple serve --serial`)\n"
    "  --baud N               its rate (default 115200)\n"
    "  --frames N             draw N frames (timing; default 1)\n"
    "  -o FRAME.ppm           write the frame (headless)\n"
    "  --fbdev DEVICE         show the frame on a framebuffer (e.g. /dev/fb0)\n"
    "  --crc                  print the CRC-32 of the frame's RGB888 bytes\n"
    "  --memory               print the memory the run holds: the client's arena,\n"
    "                         the frame, the model file, and the heap in use while\n"
    "                         drawing (glibc's mallinfo2)\n";

int fail(const std::string& message) {
  std::fprintf(stderr, "stipple-handheld: %s\n", message.c_str());
  return 1;
}

// Bytes the C library's allocator has handed out and not taken back.
size_t heap_in_use() {
  const struct mallinfo2 m = mallinfo2();
  return m.uordblks + m.hblkhd;
}

}  // namespace

namespace {

int run(int argc, char** argv) {
  using namespace stipple;
  cli::Args args(argc, argv, 1);
  if (args.flag("--help") || args.flag("-h")) {
    std::fputs(kUsage, stdout);
    std::fputs(kRenderOptionsHelp, stdout);
    std::fputs(kUsageOutput, stdout);
    return 0;
  }
  RenderOptions o;
  std::string output, fbdev, error, v;
  if (!parse_render_options(args, o, error)) return fail(error);
  if (!o.tile_nodes_given) o.config.tile_nodes = kHandheldTileNodes;  // the PDA's arena (raster/client.h)
  if (!o.lanes_given) o.config.lanes = PointLanes::kBaseline;          // the PDA's lanes, and no x86 node tables
  if (o.config.ewa) {
    // EWA's splats and a tile's sums do not fit the device's 2 MiB arena.
    ClientConfig points = o.config;
    points.ewa = false;
    const size_t with = client_arena_bytes(o.config), without = client_arena_bytes(points);
    return fail("--splat ewa: the handheld draws points; EWA's splats (one for each of " +
                cli::with_commas(o.config.node_capacity) + " nodes) and a tile's sums take " +
                cli::with_commas(with - without) + " bytes of arena more, " + cli::with_commas(with) +
                " in all against the device's 2 MiB (docs/fixed_point.md \"EWA\"; the emulator and stipple render draw it)");
  }
  const bool crc = args.flag("--crc"), memory = args.flag("--memory");
  unsigned long long frames = 1;
  if (args.value("--frames", v) && (!cli::parse_uint(v, 100000, frames) || frames == 0))
    return fail("--frames: expected 1..100000, got '" + v + "'");
  if (!args.value("-o", output)) args.value("--output", output);
  args.value("--fbdev", fbdev);
  std::string connect, serial_dev;
  const bool over_serial = args.value("--serial", serial_dev);
  unsigned long long baud = 115200;
  if (args.value("--baud", v) && !cli::parse_uint(v, 4000000, baud)) return fail("--baud: expected a rate, got '" + v + "'");
  const bool remote = args.value("--connect", connect) || over_serial;
  if (over_serial) connect = serial_dev;
  const std::vector<std::string> files = args.positionals();
  if (args.bad()) return fail(args.error());
  if (!args.unknown_option().empty()) return fail(args.unknown_option_message() + " (see --help)");
  if (files.size() != (remote ? 0u : 1u)) return fail(remote ? "--connect takes no .spg file" : "expected one .spg file (see --help)");
  const std::string model = remote ? connect : files[0];
  ClientConfig& config = o.config;
  const bool sized = o.sized;

  // The framebuffer first: a missing device fails before any work, and its
  // size is the frame's unless --size says otherwise.
  FbdevDisplay fb;
  if (!fbdev.empty()) {
    if (!fb.open(fbdev, error)) return fail(error);
    if (!sized) {
      config.raster.width = fb.width();
      config.raster.height = fb.height();
    }
  }

  ModelFile local;
  size_t file_bytes = 0;
  FixedRender frame;
  if (remote) {
    // The nodes come over the wire: the server cuts, this client draws.
    std::unique_ptr<Transport> link;
    RemoteModel server;
    RemoteModel::Options ro;
    ro.coded = o.coded;
    if (over_serial) {
      auto line = std::make_unique<SerialTransport>();
      if (!line->open(serial_dev, static_cast<uint32_t>(baud), error)) return fail("--serial " + error);
      ro.fd = line->fd();
      ro.serial = true;
      link = std::move(line);
    } else {
      std::string host;
      uint16_t port = 0;
      int fd = -1;
      if (!parse_host_port(connect, "127.0.0.1", host, port, error) || !tcp_connect(host, port, 5000, &fd, error))
        return fail("--connect " + error);
      link = std::make_unique<TcpTransport>(fd, connect);
      ro.fd = fd;
    }
    if (!server.connect(*link, config, ro, error)) return fail(model + ": " + error);
    const int32_t* extent = server.client().decoder().extent_mu();
    Camera camera;
    if (!orbit_camera(orbit_view(extent, resolve_view(o.view, server.header(), extent)), config.raster.width,
                      config.raster.height, &camera))
      return fail("--camera: the view is out of the camera's range");
    if (!server.view(camera, o.rule.max_size_q4, o.rule.window, error)) return fail(model + ": " + error);
    const size_t row = static_cast<size_t>(config.raster.width) * bytes_per_pixel(config.raster.format);
    frame.frame.assign(row * config.raster.height, 0);
    for (unsigned long long f = 0; f < frames; ++f) {
      const double start = monotonic_seconds();
      if (!server.render(camera, frame.frame.data(), row, &frame.stats, error)) return fail(model + ": " + error);
      frame.frame_seconds.push_back(monotonic_seconds() - start);
    }
    frame.heap_bytes = memory ? heap_in_use() : 0;
    server.close();
    frame.arena_bytes = client_arena_bytes(config);
    frame.cut.resize(server.client().node_count());
    image_from_frame(frame.frame.data(), row, config.raster.width, config.raster.height, config.raster.format, frame.image);
    std::printf("%s: %llu bytes received\n", model.c_str(), static_cast<unsigned long long>(server.bytes_received()));
  } else {
    // Mapped, not read: the file's pages are the page cache's, taken as the
    // cut needs them, not a copy on the heap; so are the cut's bounds, from
    // the cut table beside it (MODEL.spg.cut) when there is one.
    if (!local.open(model, cone_rule(o.rule), error)) return fail(error);
    if (local.table_refused()) std::fprintf(stderr, "stipple-handheld: %s\n", local.table_note().c_str());
    file_bytes = local.file_bytes();
    if (!render_fixed(local, config, o.rule, o.view, frame, error, static_cast<int>(frames), memory ? heap_in_use : nullptr))
      return fail(model + ": " + error);
  }
  std::vector<double> t = frame.frame_seconds;
  std::sort(t.begin(), t.end());
  std::printf("%s: %zu nodes, %u points, arena %zu bytes, frame %.3f ms (median of %lu)\n", model.c_str(), frame.cut.size(),
              frame.stats.points, frame.arena_bytes, 1e3 * t[t.size() / 2], static_cast<unsigned long>(frames));
  if (memory)
    std::printf("memory: client arena %zu bytes, frame %zu bytes, model file %zu bytes%s; heap in use while drawing %zu bytes\n",
                frame.arena_bytes, frame.frame.size(), file_bytes,
                remote ? "" : local.table_mapped() ? " (cut table mapped)" : " (cut bounds built)", frame.heap_bytes);
  if (crc) std::printf("crc32 %08x\n", crc32(frame.image.rgb.data(), frame.image.rgb.size()));
  // The frame goes to each display asked for: the null one writes it as PPM.
  const size_t stride = static_cast<size_t>(config.raster.width) * bytes_per_pixel(config.raster.format);
  if (!output.empty()) {
    NullDisplay headless(config.raster.width, config.raster.height, config.raster.format, output);
    if (!headless.present(frame.frame.data(), stride, config.raster.width, config.raster.height, config.raster.format, error))
      return fail(error);
  }
  if (!fbdev.empty() &&
      !fb.present(frame.frame.data(), stride, config.raster.width, config.raster.height, config.raster.format, error))
    return fail(error);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  // Nothing below throws by design; what still escapes (out of memory) ends
  // with a message naming the input, never an abort.
  try {
    return run(argc, argv);
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "stipple-handheld: %s: out of memory\n", argc > 1 ? argv[1] : "");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "stipple-handheld: %s: %s\n", argc > 1 ? argv[1] : "", e.what());
  }
  return 1;
}
