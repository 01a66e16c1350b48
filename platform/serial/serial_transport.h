// stipple platform — a serial line: a tty (a USB CDC-ACM device such as
// /dev/ttyACM0, a UART, or one end of a pseudo-terminal) in raw mode at a
// baud rate, as a non-blocking transport. Frames on a serial line are COBS
// framed (core/cobs.h) by the stream's ends; this only moves bytes.
#pragma once

#include <cstdint>
#include <string>

#include "platform/transport.h"

namespace stipple {

class SerialTransport final : public Transport {
 public:
  SerialTransport() = default;
  ~SerialTransport() override;
  SerialTransport(const SerialTransport&) = delete;
  SerialTransport& operator=(const SerialTransport&) = delete;

  // Opens `device` in raw mode (8N1, no flow control, no echo) at `baud`
  // (one of the termios rates: 9600 .. 4000000). error names the device.
  bool open(const std::string& device, uint32_t baud, std::string& error);
  // Takes an open tty descriptor (a pseudo-terminal's master) as it is.
  bool adopt(int fd, const std::string& name, std::string& error);

  TransportStatus read(uint8_t* out, size_t capacity, size_t* moved) override;
  TransportStatus write(const uint8_t* data, size_t size, size_t* moved) override;
  void close() override;
  const char* last_error() const override { return error_.c_str(); }
  int fd() const { return fd_; }

 private:
  int fd_ = -1;
  std::string name_, error_;
};

// A pseudo-terminal pair for tests: *master and the slave's path.
bool open_pty_pair(int* master, std::string* slave_path, std::string& error);

}  // namespace stipple
