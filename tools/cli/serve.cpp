// stipple serve — serves a model's view-dependent cuts over TCP.
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <csignal>
#include <cstdio>
#include <ctime>
#include <memory>
#include <string>
#include <thread>
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
    "usage: stipple serve MODEL.spg [--tcp [ADDR:]PORT] [--serial DEV [--baud N]] [--workers N]\n"
    "                     [--max-clients N] [--per-address N] [--hello-timeout S] [--idle-timeout S]\n"
    "                     [--token FILE] [--no-cull] [--leaf-cone G] [--once]\n"
    "\n"
    "Serves the model to clients (`stipple render --connect`, `stipple-handheld\n"
    "--connect`, the emulator): each gets the model's header for the attributes\n"
    "it asks for, then per camera update the change of its view-dependent cut —\n"
    "a cold start's coarse cut first, larger nodes first, each class just before\n"
    "the first node that uses it — and an update-end (docs/protocol.md; a client\n"
    "of protocol 2 or 3 gets the class tables whole first). The model is\n"
    "memory-mapped and shared by the workers (and, through the page cache, by\n"
    "other servers of the same file), and so is its cut table, MODEL.spg.cut\n"
    "(written by encode, or by stipple cut-table for an older file), so that a\n"
    "server starts without decoding the tree; without one the bounds are built\n"
    "in memory (36 bytes a node), which the log says.\n"
    "Logs each client's connect, hello, cut size and bytes sent, and each drop\n"
    "with its reason, to stderr. Stops on SIGINT or SIGTERM, saying goodbye to\n"
    "every client.\n"
    "\n"
    "  --tcp [ADDR:]PORT   listen there (default 127.0.0.1:7878: loopback unless told\n"
    "                      otherwise; [::1]:PORT for IPv6, 0.0.0.0:PORT for every\n"
    "                      interface, which the log points out; port 0 picks a free\n"
    "                      one and prints it)\n"
    "  --serial DEV        also serve a serial line (e.g. /dev/ttyACM0; COBS framing,\n"
    "                      docs/protocol.md): session after session, and reopened\n"
    "                      when the device comes back after a hang-up\n"
    "  --baud N            its rate (default 115200)\n"
    "  --workers N         threads serving clients, each with a listener on the same\n"
    "                      port (SO_REUSEPORT: the kernel spreads connections);\n"
    "                      default: one per core\n"
    "  --max-clients N     refuse more clients than this at once (default: sized from\n"
    "                      the memory available and the descriptor limit)\n"
    "  --per-address N     at most N connections from one address (default 64; 0: no\n"
    "                      limit, as behind a load balancer, docs/serving.md)\n"
    "  --hello-timeout S   close a connection that sends no hello in S seconds (10)\n"
    "  --idle-timeout S    close a client that sends nothing for S seconds (120; the\n"
    "                      clients send a keep-alive every 30; 0: never)\n"
    "  --token FILE        serve only clients whose hello carries this token (the\n"
    "                      file's bytes less trailing white space, at most 64;\n"
    "                      `stipple render --connect ... --token FILE`); it is not\n"
    "                      encryption: beyond a trusted network put TLS in front\n"
    "                      (docs/serving.md)\n"
    "  --no-cull           send nodes outside the view and facing away too\n"
    "  --leaf-cone G       a leaf's normal cone in sigma_n1 (default 1; docs/cut.md)\n"
    "  --once              exit once the last client has gone (a serial line: when\n"
    "                      its session ends or it hangs up)\n";

volatile std::sig_atomic_t g_stop = 0;
void on_signal(int) { g_stop = 1; }

// What one client may hold at its largest: its cut's sent set and fixed
// part (a few KB) and, while its first cut is on its way, that cut's frames
// (about 18 bytes a node for a 240x320 screen's 15-25 thousand nodes).
constexpr uint64_t kClientBudget = uint64_t{512} << 10;

// The descriptors a process may hold, raised to the hard limit (each client
// is one); the default --max-clients fits in them and in the memory available.
uint32_t default_max_clients() {
  rlimit r{};
  uint64_t fds = 1024;
  if (getrlimit(RLIMIT_NOFILE, &r) == 0) {
    if (r.rlim_cur < r.rlim_max) {
      r.rlim_cur = r.rlim_max;
      setrlimit(RLIMIT_NOFILE, &r);
      getrlimit(RLIMIT_NOFILE, &r);
    }
    fds = r.rlim_cur == RLIM_INFINITY ? 1u << 20 : r.rlim_cur;
  }
  const long pages = sysconf(_SC_AVPHYS_PAGES), page = sysconf(_SC_PAGESIZE);
  const uint64_t memory = pages > 0 && page > 0 ? uint64_t(pages) * uint64_t(page) : uint64_t{1} << 30;
  uint64_t n = std::min<uint64_t>(fds > 64 ? fds - 64 : 1, memory / kClientBudget);
  return static_cast<uint32_t>(std::clamp<uint64_t>(n, 1, 65536));
}

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
  const bool has_max = args.value("--max-clients", v);
  if (has_max) {
    if (!cli::parse_uint(v, 1000000, u) || u == 0) return cli::fail("serve: --max-clients: expected 1..1000000, got '" + v + "'");
    o.max_clients = static_cast<uint32_t>(u);
  }
  o.per_address = 64;
  if (args.value("--per-address", v)) {
    if (!cli::parse_uint(v, 1000000, u)) return cli::fail("serve: --per-address: expected 0..1000000, got '" + v + "'");
    o.per_address = static_cast<uint32_t>(u);
  }
  const auto seconds = [&](const char* name, int& ms) {
    if (!args.value(name, v)) return true;
    if (!cli::parse_uint(v, 86400, u)) return cli::fail(std::string("serve: ") + name + ": expected seconds 0..86400, got '" + v + "'") == 0;
    ms = static_cast<int>(u * 1000);
    return true;
  };
  if (!seconds("--hello-timeout", o.hello_timeout_ms) || !seconds("--idle-timeout", o.idle_timeout_ms)) return 1;
  const unsigned cores = std::max(1u, std::thread::hardware_concurrency());
  unsigned long long workers = cores;
  if (args.value("--workers", v) && (!cli::parse_uint(v, 256, workers) || workers == 0))
    return cli::fail("serve: --workers: expected 1..256, got '" + v + "'");
  std::string token_file;
  if (args.value("--token", token_file) && !cli::read_token(token_file, o.token, error))
    return cli::fail("serve: --token " + error);
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
  o.serial_once = once;
  const std::vector<std::string> files = args.positionals();
  if (args.bad()) return cli::fail("serve: " + args.error());
  if (!args.unknown_option().empty()) return cli::fail("serve: " + args.unknown_option_message());
  if (files.size() != 1) return cli::fail("serve: expected one .spg file (see stipple serve --help)");
  std::string host;
  uint16_t port = 0;
  if (!parse_host_port(tcp, "127.0.0.1", host, port, error)) return cli::fail("serve: --tcp " + error);
  const uint32_t max_clients = has_max ? o.max_clients : default_max_clients();
  if (has_max) (void)default_max_clients();  // the descriptor limit is raised either way
  const auto started = std::chrono::steady_clock::now();
  auto model = std::make_shared<ServedModel>();
  if (!model->open(files[0], o.cones, error)) return cli::fail("serve: " + error);
  const auto log_line = [](const std::string& prefix) {
    return [prefix](const std::string& line) {
      const std::time_t now = std::time(nullptr);
      char stamp[32];
      std::tm tm{};
      localtime_r(&now, &tm);
      std::strftime(stamp, sizeof stamp, "%H:%M:%S", &tm);
      std::fprintf(stderr, "%s %s%s\n", stamp, prefix.c_str(), line.c_str());
    };
  };
  o.log = log_line("");
  {
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - started).count();
    char line[256];
    std::snprintf(line, sizeof line, "%s: %u nodes, %.1f MB %s, %.1f MB of tables on the heap, ready in %.0f ms; %llu workers, at most %u clients",
                  files[0].c_str(), model->view().header.node_count, static_cast<double>(model->file_bytes()) / 1e6,
                  model->expanded() ? "expanded from version 3 in memory" : "mapped",
                  static_cast<double>(model->table_bytes()) / 1e6, ms, workers, max_clients);
    o.log(line);
    o.log(model->table_note());
  }
  // One Server a worker, each on its own thread with its own listener on the
  // port (the first picks it when it is 0); the serial line is the first's.
  std::vector<std::unique_ptr<Server>> servers;
  for (unsigned long long w = 0; w < workers; ++w) {
    ServerOptions wo = o;
    wo.max_clients = static_cast<uint32_t>((max_clients + workers - 1) / workers);
    if (workers > 1) wo.log = log_line("worker " + std::to_string(w + 1) + ": ");
    auto server = std::make_unique<Server>();
    if (!server->init(model, wo, error) || !server->listen_tcp(host, port, error, workers > 1))
      return cli::fail("serve: " + error);
    port = server->port();
    servers.push_back(std::move(server));
  }
  if (has_serial) {
    const uint32_t rate = static_cast<uint32_t>(baud);
    auto line = std::make_unique<SerialTransport>();
    if (!line->open(serial, rate, error)) return cli::fail("serve: --serial " + error);
    const int fd = line->fd();
    Reopen reopen;
    if (!once)
      reopen = [serial, rate](int* out) -> std::unique_ptr<Transport> {
        auto again = std::make_unique<SerialTransport>();
        std::string ignored;
        if (!again->open(serial, rate, ignored)) return nullptr;
        *out = again->fd();
        return again;
      };
    servers[0]->add_client(std::move(line), fd, serial, true, std::move(reopen));
  }
  std::printf("%s: serving on port %u\n", files[0].c_str(), port);
  std::fflush(stdout);
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  std::signal(SIGPIPE, SIG_IGN);
  // Each worker loops until told to stop; --once stops them all when none
  // has a client left after one was served.
  std::atomic<bool> stop{false};
  std::vector<std::atomic<size_t>> connected(servers.size());
  std::atomic<bool> served{false};
  const auto run = [&](size_t w) {
    while (!stop.load(std::memory_order_relaxed)) {
      const size_t n = servers[w]->step(50);
      connected[w].store(n, std::memory_order_relaxed);
      if (n > 0) served.store(true, std::memory_order_relaxed);
    }
  };
  std::vector<std::thread> threads;
  for (size_t w = 1; w < servers.size(); ++w) threads.emplace_back(run, w);
  std::thread watcher([&] {
    while (!stop.load()) {
      if (g_stop) stop = true;
      if (once && served.load()) {
        size_t total = 0;
        for (const auto& c : connected) total += c.load();
        if (total == 0) stop = true;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  });
  run(0);
  for (std::thread& t : threads) t.join();
  watcher.join();
  for (auto& server : servers) server->shutdown(g_stop ? "a signal" : "--once: the last client has gone");
  return 0;
}

}  // namespace stipple
