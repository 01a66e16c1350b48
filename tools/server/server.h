// stipple server — serves a model's view-dependent cuts to many clients at
// once (TOG05 §8): each client's hello, camera updates and keep-alives come
// in; its startup, cut changes and update-ends go out (core/stream.h over
// core/protocol.h frames), on any transport — TCP sockets accepted by the
// server, a serial line, or a loopback pipe added by the program itself.
//
// The model (ServedModel) is memory-mapped read-only, validated once, and
// its per-node cut bounds built once; it is shared by every Server over it
// (`stipple serve --workers N`: one Server a thread, each with its own
// listener on the same port). A Server is one thread and one event loop
// (poll): nothing blocks on one client. What a client costs follows what it
// sees, not the model: its cut's sent set (1-2 bytes a sent node) and a fixed
// part; the work space of an update is the Server's, shared by its clients.
// Until its hello is valid a connection holds only the fixed part.
//
// A client whose outgoing queue is not empty gets no new update — only its
// latest camera is kept — so a slow or stalled client costs its own queue
// (bounded by one update) and never stalls the others. A client that sends
// a bad frame gets an error frame naming the fault and is closed; one that
// sends no hello in time, or nothing at all for the idle timeout, is closed
// with reason "timeout"; one that disconnects, even mid-frame, is removed.
// Every drop is logged with its reason. A serial line serves session after
// session: a hello always starts one, a close ends it, and a line that
// hangs up is reopened when its device comes back.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/node_decoder.h"
#include "core/protocol.h"
#include "core/spg_format.h"
#include "core/stream.h"
#include "platform/file_io.h"
#include "platform/transport.h"
#include "tools/embedded/model_file.h"

namespace stipple {

// A model as servers serve it: a ModelFile (mapped, validated once, its
// cut bounds mapped from its cut table or built), read-only once made, so
// any number of Servers on any threads share one.
using ServedModel = ModelFile;

struct ServerOptions {
  uint32_t max_clients = 64;       // at once; more are refused with "server full" (serve sizes it from memory)
  uint32_t per_address = 0;        // most connections from one address at once (0: no limit)
  int hello_timeout_ms = 10000;    // a connection that sends no valid hello this long is closed (0: never)
  int idle_timeout_ms = 120000;    // a client that sends nothing this long is closed (0: never)
  bool serial_once = false;        // a serial line is let go when its first session ends (serve --once)
  std::string token;               // non-empty: every hello must carry it (protocol 3, serve --token FILE)
  bool cull = true;  // frustum and back-face culling in every client's cut
  ConeRule cones;    // the normal cones back faces are culled by (when the Server makes the model)
  std::function<void(const std::string&)> log;  // one line per event; none: quiet
};

struct ClientReport {
  std::string name;
  bool hello = false;
  uint32_t updates = 0, cut_nodes = 0;
  uint32_t sessions = 0;  // hellos that started a stream (a serial line serves one after another)
  uint64_t bytes_in = 0, bytes_out = 0;
  uint64_t queued_bytes = 0;  // the outgoing queue after the last step: bounded whatever the peer does
  uint64_t state_bytes = 0;   // what the client holds beside its queue: its cut's sent set and fixed part
};

// Reopens a serial line that hung up: the new transport and its fd, or null
// while the device is not back.
using Reopen = std::function<std::unique_ptr<Transport>(int* fd)>;

class Server {
 public:
  Server();
  ~Server();
  // Over a model shared with other Servers.
  bool init(std::shared_ptr<const ServedModel> model, const ServerOptions& options, std::string& error);
  // Validates `file` (a whole .spg, kept by the server) and builds its model.
  bool init(std::vector<uint8_t> file, const std::string& name, const ServerOptions& options, std::string& error);
  // Listens on host:port (port 0: a free one, see port()). `share_port`:
  // beside other listeners on that port (SO_REUSEPORT, serve's workers).
  bool listen_tcp(const std::string& host, uint16_t port, std::string& error, bool share_port = false);
  uint16_t port() const { return port_; }
  // Serves a client over `transport`; `fd` is polled for it (-1: the loop
  // visits it every step, as for a loopback pipe).
  // `serial`: frames are COBS framed (a serial line); damaged packets are
  // dropped, a hello starts a session, a close ends it, and the line stays
  // served. When it hangs up it is reopened through `reopen` (null: the
  // client is removed).
  void add_client(std::unique_ptr<Transport> transport, int fd, const std::string& name, bool serial = false,
                  Reopen reopen = nullptr);
  // One pass of the loop: waits up to timeout_ms for a socket, accepts, reads,
  // answers, writes, times out. Returns the number of clients connected.
  size_t step(int timeout_ms);
  // Says goodbye: a close (reason "server shutting down") to every client,
  // what can be written now, and a log line with what was served.
  void shutdown(const std::string& why);
  std::vector<ClientReport> report() const;
  // The update work space, shared by this Server's clients (grows with the
  // largest cut served).
  size_t scratch_bytes() const { return scratch_storage_.size() * 8; }

 private:
  struct Client;
  using Clock = std::chrono::steady_clock;
  void log(const std::string& line) const;
  void handle(Client& c, const Frame& f);
  void close_client(Client& c, CloseReason reason, FrameStatus status, uint16_t sequence, const std::string& why);
  bool update(Client& c);  // the cut for the client's latest camera; grows storage as the cut needs
  bool grow_state(Client& c, size_t needed);  // the client's sent-set storage to at least `needed` bytes
  void begin_session(Client& c);  // a hello (or a resume) taken: the stream is on
  void end_session(Client& c);
  void accept_all(Clock::time_point now);
  void read_from(Client& c, Clock::time_point now);
  void reopen_line(Client& c, Clock::time_point now);

  std::shared_ptr<const ServedModel> model_;
  std::vector<uint64_t> scratch_storage_;
  SenderScratch scratch_;
  ServerOptions options_;
  int listen_fd_ = -1;
  uint16_t port_ = 0;
  uint32_t next_id_ = 1;
  uint64_t served_ = 0;  // clients removed so far
  Clock::time_point accept_paused_until_{};
  std::vector<std::unique_ptr<Client>> clients_;
};

}  // namespace stipple
