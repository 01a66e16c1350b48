// stipple serve — serves a model's view-dependent cuts over TCP.
#include <csignal>
#include <memory>
#include <cstdio>
#include <ctime>
#include <string>
#include <vector>

#include "platform/file_io.h"
#include "platform/serial/serial_transport.h"
#include "platform/tcp/tcp_transport.h"
#include "tools/cli/cli.h"
#include "tools/embedded/render_options.h"
#include "tools/server/server.h"

namespace stipple {
namespace {

const char kServeHelp[] =
    "usage: stipple serve MODEL.spg [--tcp [ADDR:]PORT] [--serial DEV [--baud N]] [--max-clients N]\n"
    "                     [--no-cull] [--leaf-cone G] [--once]\n"
    "\n"
    "Serves the model to clients (`stipple render --connect`, `stipple-handheld\n"
    "--connect`, the emulator): each gets the startup for the attributes it asks\n"
    "for, then per camera update the change of its view-dependent cut and an\n"
    "update-end (docs/protocol.md). Logs each client's connect, hello, cut size\n"
    "and bytes sent, and its disconnect, to stderr. Stops on SIGINT or SIGTERM.\n"
    "\n"
    "  --tcp [ADDR:]PORT   listen there (default 127.0.0.1:7878: loopback unless told\n"
    "                      otherwise; [::1]:PORT for IPv6, 0.0.0.0:PORT for every\n"
    "                      interface; port 0 picks a free one and prints it)\n"
    "  --serial DEV        also serve the client at the other end of a serial line\n"
    "                      (e.g. /dev/ttyACM0; COBS framing, docs/protocol.md)\n"
    "  --baud N            its rate (default 115200)\n"
    "  --max-clients N     refuse more clients than this at once (default 64)\n"
    "  --no-cull           send nodes outside the view and facing away too\n"
    "  --leaf-cone G       a leaf's normal cone in sigma_n1 (default 1; docs/cut.md)\n"
    "  --once              exit once the last client has gone\n";

volatile std::sig_atomic_t g_stop = 0;
void on_signal(int) { g_stop = 1; }

}  // namespace

int cmd_serve(int argc, char** argv) {
  cli::Args args(argc, argv, 2);
  if (args.flag("--help") || args.flag("-h")) {
    std::fputs(kServeHelp, stdout);
    return 0;
  }
  std::string tcp = "127.0.0.1:7878", v, error;
  args.value("--tcp", tcp);
  ServerOptions o;
  unsigned long long u = 0;
  if (args.value("--max-clients", v)) {
    if (!cli::parse_uint(v, 4096, u) || u == 0) return cli::fail("serve: --max-clients: expected 1..4096, got '" + v + "'");
    o.max_clients = static_cast<uint32_t>(u);
  }
  o.cull = !args.flag("--no-cull");
  if (args.value("--leaf-cone", v) && !parse_leaf_cone(v, o.cones.leaf_gamma_q8, error)) return cli::fail("serve: " + error);
  std::string serial;
  const bool has_serial = args.value("--serial", serial);
  unsigned long long baud = 115200;
  const bool has_baud = args.value("--baud", v);
  if (has_baud && !cli::parse_uint(v, 4000000, baud)) return cli::fail("serve: --baud: expected a rate, got '" + v + "'");
  if (has_baud && !has_serial)
    return cli::fail("serve: --baud " + v + " sets the serial line's rate, but no --serial DEVICE is given");
  const bool once = args.flag("--once");
  const std::vector<std::string> files = args.positionals();
  if (args.bad()) return cli::fail("serve: " + args.error());
  if (!args.unknown_option().empty()) return cli::fail("serve: " + args.unknown_option_message());
  if (files.size() != 1) return cli::fail("serve: expected one .spg file (see stipple serve --help)");
  std::string host;
  uint16_t port = 0;
  if (!parse_host_port(tcp, "127.0.0.1", host, port, error)) return cli::fail("serve: --tcp " + error);
  std::vector<uint8_t> file;
  if (!read_file(files[0], file, error)) return cli::fail(error);
  o.log = [](const std::string& line) {
    const std::time_t now = std::time(nullptr);
    char stamp[32];
    std::strftime(stamp, sizeof stamp, "%H:%M:%S", std::localtime(&now));
    std::fprintf(stderr, "%s %s\n", stamp, line.c_str());
  };
  Server server;
  if (!server.init(std::move(file), files[0], o, error) || !server.listen_tcp(host, port, error))
    return cli::fail("serve: " + error);
  if (has_serial) {
    auto line = std::make_unique<SerialTransport>();
    if (!line->open(serial, static_cast<uint32_t>(baud), error)) return cli::fail("serve: --serial " + error);
    const int fd = line->fd();
    server.add_client(std::move(line), fd, serial, true);
  }
  std::printf("%s: serving on port %u\n", files[0].c_str(), server.port());
  std::fflush(stdout);
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  bool served = false;
  while (!g_stop) {
    const size_t clients = server.step(50);
    served = served || clients > 0;
    if (once && served && clients == 0) break;
  }
  return 0;
}

}  // namespace stipple
