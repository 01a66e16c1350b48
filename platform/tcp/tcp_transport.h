// stipple platform — TCP: a transport over a connected, non-blocking stream
// socket (IPv4 or IPv6), a listener, and a connect with a timeout. POSIX
// sockets; writes never raise SIGPIPE (a peer gone reads as kClosed).
#pragma once

#include <cstdint>
#include <string>

#include "platform/transport.h"

namespace stipple {

class TcpTransport final : public Transport {
 public:
  // Takes ownership of a connected socket (made non-blocking here).
  TcpTransport(int fd, std::string peer);
  ~TcpTransport() override;
  TcpTransport(const TcpTransport&) = delete;
  TcpTransport& operator=(const TcpTransport&) = delete;

  // Never blocks: kTimeout when the socket has nothing to read or no room to write.
  TransportStatus read(uint8_t* out, size_t capacity, size_t* moved) override;
  TransportStatus write(const uint8_t* data, size_t size, size_t* moved) override;
  void close() override;
  const char* last_error() const override { return error_.c_str(); }
  int fd() const { return fd_; }
  const std::string& peer() const { return peer_; }

 private:
  int fd_;
  std::string peer_, error_;
};

// "PORT", "HOST:PORT", "[V6]:PORT"; an empty host means `default_host`.
bool parse_host_port(const std::string& text, const std::string& default_host, std::string& host, uint16_t& port,
                     std::string& error);

// A listening socket on host:port (numeric IPv4 or IPv6; port 0 picks a free
// one, see *bound_port). Non-blocking, SO_REUSEADDR.
// Every socket is close-on-exec: a program that starts another (a test
// starting a load balancer) does not hand it its listeners and links.
// `share_port`: SO_REUSEPORT, so several listeners (a server's workers)
// bind the same port and the kernel spreads connections across them.
bool tcp_listen(const std::string& host, uint16_t port, int* fd, uint16_t* bound_port, std::string& error,
                bool share_port = false);
// A pending connection, or -1 when there is none or accept failed: *error
// (when given) is then EAGAIN for none, else accept's errno (EMFILE: out of
// descriptors). *peer names the connection ("address:port").
int tcp_accept(int listen_fd, std::string* peer, int* error = nullptr);
// Closes a listening socket.
void tcp_close(int fd);
// Connects to host:port (a name or a numeric address) within timeout_ms.
bool tcp_connect(const std::string& host, uint16_t port, int timeout_ms, int* fd, std::string& error);

}  // namespace stipple
