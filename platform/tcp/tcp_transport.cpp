// stipple platform — TCP. See tcp_transport.h.
#include "platform/tcp/tcp_transport.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace stipple {
namespace {

bool set_nonblocking(int fd) {
  const int flags = fcntl(fd, F_GETFL, 0);
  return flags >= 0 && fcntl(fd, F_SETFL, flags | O_NONBLOCK) == 0;
}

std::string describe(const sockaddr_storage& a) {
  // Built by appending: GCC 12 at -O3 warns (-Wrestrict, a false positive)
  // on "[" + std::string(...) here.
  char host[INET6_ADDRSTRLEN] = "?";
  const bool v4 = a.ss_family == AF_INET;
  const auto* in4 = reinterpret_cast<const sockaddr_in*>(&a);
  const auto* in6 = reinterpret_cast<const sockaddr_in6*>(&a);
  if (v4) inet_ntop(AF_INET, &in4->sin_addr, host, sizeof host);
  else inet_ntop(AF_INET6, &in6->sin6_addr, host, sizeof host);
  std::string out;
  out.reserve(sizeof host + 8);
  if (!v4) out += '[';
  out += host;
  out += v4 ? ":" : "]:";
  out += std::to_string(ntohs(v4 ? in4->sin_port : in6->sin6_port));
  return out;
}

}  // namespace

TcpTransport::TcpTransport(int fd, std::string peer) : fd_(fd), peer_(std::move(peer)) {
  set_nonblocking(fd_);
  const int one = 1;
  setsockopt(fd_, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
}

TcpTransport::~TcpTransport() { close(); }

void TcpTransport::close() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

TransportStatus TcpTransport::read(uint8_t* out, size_t capacity, size_t* moved) {
  *moved = 0;
  if (fd_ < 0) return TransportStatus::kClosed;
  const ssize_t n = recv(fd_, out, capacity, MSG_DONTWAIT);
  if (n > 0) {
    *moved = static_cast<size_t>(n);
    return TransportStatus::kOk;
  }
  if (n == 0) return TransportStatus::kClosed;
  if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) return TransportStatus::kTimeout;
  if (errno == ECONNRESET || errno == EPIPE) return TransportStatus::kClosed;
  error_ = peer_ + ": " + std::strerror(errno);
  return TransportStatus::kError;
}

TransportStatus TcpTransport::write(const uint8_t* data, size_t size, size_t* moved) {
  *moved = 0;
  if (fd_ < 0) return TransportStatus::kClosed;
  const ssize_t n = send(fd_, data, size, MSG_DONTWAIT | MSG_NOSIGNAL);
  if (n >= 0) {
    *moved = static_cast<size_t>(n);
    return TransportStatus::kOk;
  }
  if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) return TransportStatus::kTimeout;
  if (errno == ECONNRESET || errno == EPIPE) return TransportStatus::kClosed;
  error_ = peer_ + ": " + std::strerror(errno);
  return TransportStatus::kError;
}

bool parse_host_port(const std::string& text, const std::string& default_host, std::string& host, uint16_t& port,
                     std::string& error) {
  std::string h = default_host, p = text;
  if (!text.empty() && text[0] == '[') {
    const size_t close = text.find("]:");
    if (close == std::string::npos) return error = "'" + text + "': expected [ADDRESS]:PORT", false;
    h = text.substr(1, close - 1);
    p = text.substr(close + 2);
  } else if (const size_t colon = text.rfind(':'); colon != std::string::npos) {
    h = text.substr(0, colon);
    p = text.substr(colon + 1);
  }
  char* end = nullptr;
  const long v = std::strtol(p.c_str(), &end, 10);
  if (p.empty() || *end != '\0' || v < 0 || v > 65535) return error = "'" + text + "': expected a port 0..65535", false;
  host = h.empty() ? default_host : h;
  port = static_cast<uint16_t>(v);
  return true;
}

bool tcp_listen(const std::string& host, uint16_t port, int* out, uint16_t* bound_port, std::string& error,
                bool share_port) {
  sockaddr_storage addr{};
  socklen_t len = 0;
  auto* v4 = reinterpret_cast<sockaddr_in*>(&addr);
  auto* v6 = reinterpret_cast<sockaddr_in6*>(&addr);
  if (inet_pton(AF_INET, host.c_str(), &v4->sin_addr) == 1) {
    v4->sin_family = AF_INET;
    v4->sin_port = htons(port);
    len = sizeof *v4;
  } else if (inet_pton(AF_INET6, host.c_str(), &v6->sin6_addr) == 1) {
    v6->sin6_family = AF_INET6;
    v6->sin6_port = htons(port);
    len = sizeof *v6;
  } else {
    return error = host + ": not a numeric IPv4 or IPv6 address", false;
  }
  const int fd = socket(addr.ss_family, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return error = std::string("socket: ") + std::strerror(errno), false;
  const int one = 1;
  setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
  if (share_port && setsockopt(fd, SOL_SOCKET, SO_REUSEPORT, &one, sizeof one) != 0) {
    error = describe(addr) + ": SO_REUSEPORT: " + std::strerror(errno);
    ::close(fd);
    return false;
  }
  // The kernel's limit (somaxconn) caps the backlog: a thousand clients
  // connecting at once wait there, not in refusals.
  if (bind(fd, reinterpret_cast<sockaddr*>(&addr), len) != 0 || listen(fd, SOMAXCONN) != 0 || !set_nonblocking(fd)) {
    error = describe(addr) + ": " + std::strerror(errno);
    ::close(fd);
    return false;
  }
  socklen_t got = sizeof addr;
  getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &got);
  if (bound_port) *bound_port = ntohs(addr.ss_family == AF_INET ? v4->sin_port : v6->sin6_port);
  *out = fd;
  return true;
}

void tcp_close(int fd) { ::close(fd); }

int tcp_accept(int listen_fd, std::string* peer, int* error) {
  sockaddr_storage addr{};
  socklen_t len = sizeof addr;
  const int fd = accept4(listen_fd, reinterpret_cast<sockaddr*>(&addr), &len, SOCK_CLOEXEC);
  if (fd >= 0 && peer) *peer = describe(addr);
  if (error) *error = fd >= 0 ? 0 : errno == EWOULDBLOCK ? EAGAIN : errno;
  return fd;
}

bool tcp_connect(const std::string& host, uint16_t port, int timeout_ms, int* out, std::string& error) {
  addrinfo hints{}, *found = nullptr;
  hints.ai_socktype = SOCK_STREAM;
  const std::string service = std::to_string(port);
  if (const int r = getaddrinfo(host.c_str(), service.c_str(), &hints, &found); r != 0)
    return error = host + ": " + gai_strerror(r), false;
  error = host + ":" + service + ": no address";
  for (addrinfo* a = found; a != nullptr; a = a->ai_next) {
    const int fd = socket(a->ai_family, a->ai_socktype | SOCK_CLOEXEC, a->ai_protocol);
    if (fd < 0) continue;
    set_nonblocking(fd);
    int rc = connect(fd, a->ai_addr, a->ai_addrlen);
    if (rc != 0 && errno == EINPROGRESS) {
      pollfd p{fd, POLLOUT, 0};
      int soerr = 0;
      socklen_t sl = sizeof soerr;
      rc = poll(&p, 1, timeout_ms) == 1 && getsockopt(fd, SOL_SOCKET, SO_ERROR, &soerr, &sl) == 0 && soerr == 0 ? 0 : -1;
      if (rc != 0) errno = soerr != 0 ? soerr : ETIMEDOUT;
    }
    if (rc == 0) {
      freeaddrinfo(found);
      *out = fd;
      return true;
    }
    error = host + ":" + service + ": " + std::strerror(errno);
    ::close(fd);
  }
  freeaddrinfo(found);
  return false;
}

}  // namespace stipple
