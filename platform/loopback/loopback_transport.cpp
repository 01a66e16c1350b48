// stipple platform — the loopback transport. See loopback_transport.h.
#include "platform/loopback/loopback_transport.h"

#include <algorithm>
#include <cstring>

namespace stipple {

LoopbackPipe::LoopbackPipe(size_t capacity) : capacity_(capacity) {
  for (int k = 0; k < 2; ++k) {
    rings_[k].bytes.reset(new uint8_t[capacity]);
    ends_[k].pipe_ = this;
    ends_[k].side_ = k;
  }
}

TransportStatus LoopbackEnd::read(uint8_t* out, size_t capacity, size_t* moved) {
  *moved = 0;
  LoopbackPipe::Ring& r = pipe_->rings_[1 - side_];
  if (pipe_->closed_[side_]) return TransportStatus::kClosed;
  if (r.size == 0) return pipe_->closed_[1 - side_] ? TransportStatus::kClosed : TransportStatus::kTimeout;
  const size_t n = capacity < r.size ? capacity : r.size;
  const size_t first = std::min(n, pipe_->capacity_ - r.head);  // up to the ring's end, then from its start
  std::memcpy(out, r.bytes.get() + r.head, first);
  std::memcpy(out + first, r.bytes.get(), n - first);
  r.head = (r.head + n) % pipe_->capacity_;
  r.size -= n;
  *moved = n;
  return TransportStatus::kOk;
}

TransportStatus LoopbackEnd::write(const uint8_t* data, size_t size, size_t* moved) {
  *moved = 0;
  if (pipe_->closed_[side_] || pipe_->closed_[1 - side_]) return TransportStatus::kClosed;
  LoopbackPipe::Ring& r = pipe_->rings_[side_];
  const size_t room = pipe_->capacity_ - r.size, n = size < room ? size : room;
  if (n == 0) return TransportStatus::kTimeout;
  const size_t tail = (r.head + r.size) % pipe_->capacity_, first = std::min(n, pipe_->capacity_ - tail);
  std::memcpy(r.bytes.get() + tail, data, first);
  std::memcpy(r.bytes.get(), data + first, n - first);
  r.size += n;
  *moved = n;
  return TransportStatus::kOk;
}

void LoopbackEnd::close() { pipe_->closed_[side_] = true; }

}  // namespace stipple
