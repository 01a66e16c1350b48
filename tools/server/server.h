// stipple server — serves a model's view-dependent cuts to many clients at
// once (TOG05 §8): each client's hello, camera updates and keep-alives come
// in; its startup, cut changes and update-ends go out (core/stream.h over
// core/protocol.h frames), on any transport — TCP sockets accepted by the
// server, or a loopback pipe added by the program itself.
//
// One thread, one event loop (poll): nothing blocks on one client. A client
// whose outgoing queue is not empty gets no new update — only its latest
// camera is kept — so a slow or stalled client costs its own queue (bounded
// by one update) and never stalls the others. A client that sends a bad
// frame gets an error frame naming the fault and is closed; one that
// disconnects, even mid-frame, is removed and logged; the server's state for
// the others is untouched.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/node_decoder.h"
#include "core/protocol.h"
#include "core/spg_format.h"
#include "core/stream.h"
#include "platform/transport.h"

namespace stipple {

struct ServerOptions {
  uint32_t max_clients = 64;
  bool cull = true;  // frustum and back-face culling in every client's cut
  ConeRule cones;    // the normal cones back faces are culled by
  std::function<void(const std::string&)> log;  // one line per event; none: quiet
};

struct ClientReport {
  std::string name;
  bool hello = false;
  uint32_t updates = 0, cut_nodes = 0;
  uint64_t bytes_in = 0, bytes_out = 0;
  uint64_t queued_bytes = 0;  // the outgoing queue after the last step: bounded whatever the peer does
};

class Server {
 public:
  Server();
  ~Server();
  // Validates `file` (a whole .spg, kept by the server) and builds its decoder.
  bool init(std::vector<uint8_t> file, const std::string& name, const ServerOptions& options, std::string& error);
  // Listens on host:port (port 0: a free one, see port()).
  bool listen_tcp(const std::string& host, uint16_t port, std::string& error);
  uint16_t port() const { return port_; }
  // Serves a client over `transport`; `fd` is polled for it (-1: the loop
  // visits it every step, as for a loopback pipe).
  // `serial`: frames are COBS framed (a serial line); damaged packets are
  // dropped and a hello restarts the stream.
  void add_client(std::unique_ptr<Transport> transport, int fd, const std::string& name, bool serial = false);
  // One pass of the loop: waits up to timeout_ms for a socket, accepts, reads,
  // answers, writes. Returns the number of clients connected.
  size_t step(int timeout_ms);
  std::vector<ClientReport> report() const;

 private:
  struct Client;
  void log(const std::string& line) const;
  void handle(Client& c, const Frame& f);
  void close_client(Client& c, CloseReason reason, FrameStatus status, uint16_t sequence, const std::string& why);

  std::vector<uint8_t> file_;
  std::string name_;
  SpgView view_{};
  std::vector<uint32_t> decoder_storage_;
  NodeDecoder decoder_;
  std::vector<uint64_t> bounds_storage_;
  CutBounds bounds_;  // the model's, shared by every client's cut
  ServerOptions options_;
  int listen_fd_ = -1;
  uint16_t port_ = 0;
  uint32_t next_id_ = 1;
  std::vector<std::unique_ptr<Client>> clients_;
};

}  // namespace stipple
