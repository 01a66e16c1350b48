// stipple platform — the loopback transport: server and client in one
// process (the embedded default), and the tests. Two byte rings of a fixed
// capacity joined back to back: what one end writes the other reads. Writes
// take what fits (a full ring reads as kTimeout: the writer tries again
// later), reads take what is there (kTimeout when nothing is). Closing one
// end makes the other read the rest and then kClosed. Single-threaded: both
// ends are driven by one loop. Storage is sized at construction; reads and
// writes allocate nothing.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>

#include "platform/transport.h"

namespace stipple {

class LoopbackPipe;

class LoopbackEnd final : public Transport {
 public:
  TransportStatus read(uint8_t* out, size_t capacity, size_t* moved) override;
  TransportStatus write(const uint8_t* data, size_t size, size_t* moved) override;
  void close() override;
  const char* last_error() const override { return "loopback: the other end closed"; }

 private:
  friend class LoopbackPipe;
  LoopbackPipe* pipe_ = nullptr;
  int side_ = 0;
};

class LoopbackPipe {
 public:
  explicit LoopbackPipe(size_t capacity = 1 << 20);
  LoopbackPipe(const LoopbackPipe&) = delete;
  LoopbackPipe& operator=(const LoopbackPipe&) = delete;
  LoopbackEnd& server() { return ends_[0]; }
  LoopbackEnd& client() { return ends_[1]; }

 private:
  friend class LoopbackEnd;
  struct Ring {
    std::unique_ptr<uint8_t[]> bytes;
    size_t head = 0, size = 0;
  };
  size_t capacity_;
  Ring rings_[2];  // rings_[k]: written by side k, read by the other
  bool closed_[2] = {false, false};
  LoopbackEnd ends_[2];
};

}  // namespace stipple
