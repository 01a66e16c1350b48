// stipple platform — a transport: a byte stream between a server and a
// client, behind the narrowest table that fits loopback (server and client
// in one process), TCP sockets and a USB serial line (issue 11). Framing,
// checksums and resynchronisation are core/protocol's; a transport moves
// bytes, reports how many, and says when the other side went away.
//
// read() and write() never block longer than the backend's configured
// timeout and may move fewer bytes than asked; a return other than kOk
// leaves *moved at what was moved. After kClosed or kError every call
// returns the same status again; close() is idempotent. A transport is used
// from one thread at a time. last_error() names the peer or device and the
// reason, for the host's messages.
#pragma once

#include <cstddef>
#include <cstdint>

namespace stipple {

enum class TransportStatus : uint8_t {
  kOk = 0,      // bytes moved (possibly fewer than asked)
  kTimeout,     // nothing moved before the timeout
  kClosed,      // the peer closed the stream (end of file, cable pulled)
  kError,       // the backend failed: last_error() says why
};

class Transport {
 public:
  virtual ~Transport() = default;
  [[nodiscard]] virtual TransportStatus read(uint8_t* out, size_t capacity, size_t* moved) = 0;
  [[nodiscard]] virtual TransportStatus write(const uint8_t* data, size_t size, size_t* moved) = 0;
  virtual void close() = 0;
  virtual const char* last_error() const = 0;
};

// A transport that forwards to another it does not own (a loopback end,
// which its pipe owns), for code that takes ownership of a transport.
class TransportRef final : public Transport {
 public:
  explicit TransportRef(Transport& to) : to_(to) {}
  TransportStatus read(uint8_t* out, size_t capacity, size_t* moved) override { return to_.read(out, capacity, moved); }
  TransportStatus write(const uint8_t* data, size_t size, size_t* moved) override { return to_.write(data, size, moved); }
  void close() override { to_.close(); }
  const char* last_error() const override { return to_.last_error(); }

 private:
  Transport& to_;
};

}  // namespace stipple
