// stipple platform — the serial line. See serial_transport.h.
#include "platform/serial/serial_transport.h"

#include <fcntl.h>
#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>

namespace stipple {
namespace {

bool speed_of(uint32_t baud, speed_t* out) {
  const struct {
    uint32_t baud;
    speed_t speed;
  } rates[] = {{9600, B9600},     {19200, B19200},   {38400, B38400},   {57600, B57600},   {115200, B115200},
               {230400, B230400}, {460800, B460800}, {921600, B921600}, {1000000, B1000000}, {2000000, B2000000},
               {4000000, B4000000}};
  for (const auto& r : rates)
    if (r.baud == baud) return *out = r.speed, true;
  return false;
}

}  // namespace

SerialTransport::~SerialTransport() { close(); }

bool SerialTransport::open(const std::string& device, uint32_t baud, std::string& error) {
  speed_t speed;
  if (!speed_of(baud, &speed)) return error = device + ": " + std::to_string(baud) + " baud is not a termios rate", false;
  const int fd = ::open(device.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) return error = device + ": " + std::strerror(errno), false;
  termios t{};
  if (tcgetattr(fd, &t) != 0) {
    error = device + ": not a serial line (" + std::strerror(errno) + ")";
    ::close(fd);
    return false;
  }
  cfmakeraw(&t);
  t.c_cflag |= CLOCAL | CREAD;
  t.c_cflag &= ~static_cast<tcflag_t>(CRTSCTS | CSTOPB | PARENB);
  t.c_cc[VMIN] = 0;
  t.c_cc[VTIME] = 0;
  if (cfsetispeed(&t, speed) != 0 || cfsetospeed(&t, speed) != 0 || tcsetattr(fd, TCSANOW, &t) != 0) {
    error = device + ": " + std::strerror(errno);
    ::close(fd);
    return false;
  }
  fd_ = fd;
  name_ = device;
  return true;
}

bool SerialTransport::adopt(int fd, const std::string& name, std::string& error) {
  const int flags = fcntl(fd, F_GETFL, 0);
  if (flags < 0 || fcntl(fd, F_SETFL, flags | O_NONBLOCK) != 0) return error = name + ": " + std::strerror(errno), false;
  fd_ = fd;
  name_ = name;
  return true;
}

TransportStatus SerialTransport::read(uint8_t* out, size_t capacity, size_t* moved) {
  *moved = 0;
  if (fd_ < 0) return TransportStatus::kClosed;
  const ssize_t n = ::read(fd_, out, capacity);
  if (n > 0) {
    *moved = static_cast<size_t>(n);
    return TransportStatus::kOk;
  }
  if (n == 0) {
    // A raw tty reads 0 both when nothing is there (VMIN = VTIME = 0) and
    // when the line hung up (a USB CDC-ACM device unplugged, a pty's other
    // end closed): poll tells them apart.
    pollfd p{fd_, POLLIN, 0};
    if (poll(&p, 1, 0) == 1 && (p.revents & (POLLHUP | POLLERR | POLLNVAL)) != 0) {
      error_ = name_ + ": the line hung up";
      return TransportStatus::kClosed;
    }
    return TransportStatus::kTimeout;
  }
  if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) return TransportStatus::kTimeout;
  if (errno == EIO || errno == ENXIO || errno == ENODEV) {  // hung up, unplugged
    error_ = name_ + ": the line hung up (" + std::strerror(errno) + ")";
    return TransportStatus::kClosed;
  }
  error_ = name_ + ": " + std::strerror(errno);
  return TransportStatus::kError;
}

TransportStatus SerialTransport::write(const uint8_t* data, size_t size, size_t* moved) {
  *moved = 0;
  if (fd_ < 0) return TransportStatus::kClosed;
  const ssize_t n = ::write(fd_, data, size);
  if (n >= 0) {
    *moved = static_cast<size_t>(n);
    return TransportStatus::kOk;
  }
  if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) return TransportStatus::kTimeout;
  if (errno == EIO || errno == ENXIO || errno == ENODEV) return TransportStatus::kClosed;
  error_ = name_ + ": " + std::strerror(errno);
  return TransportStatus::kError;
}

void SerialTransport::close() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

bool open_pty_pair(int* master, std::string* slave_path, std::string& error) {
  const int m = posix_openpt(O_RDWR | O_NOCTTY);
  if (m < 0 || grantpt(m) != 0 || unlockpt(m) != 0) {
    error = std::string("posix_openpt: ") + std::strerror(errno);
    if (m >= 0) ::close(m);
    return false;
  }
  char name[128];
  if (ptsname_r(m, name, sizeof name) != 0) {
    error = std::string("ptsname: ") + std::strerror(errno);
    ::close(m);
    return false;
  }
  termios t{};
  tcgetattr(m, &t);
  cfmakeraw(&t);
  tcsetattr(m, TCSANOW, &t);
  *master = m;
  *slave_path = name;
  return true;
}

}  // namespace stipple
