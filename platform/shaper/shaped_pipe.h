// stipple platform — a link shaper: a loopback pipe with a link's bandwidth,
// latency, byte loss and bit errors in each direction, on a simulated clock,
// to emulate a 115,200-baud serial line, USB 1.1 or 802.11b in tests and
// benchmarks — the same run every time, as fast as the CPU allows.
//
// A byte written at time t is readable at the other end from
//   max(t, when the previous byte finished) + 8 / bandwidth + latency.
// Loss drops a byte, a bit error flips one bit of it, each with its own
// probability per byte, from a seeded generator. Time moves only by
// advance(); both ends are driven by one loop. Buffers are bounded by
// `capacity` bytes a direction (a full link reads as kTimeout to the writer).
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>

#include "platform/transport.h"

namespace stipple {

struct LinkProfile {
  uint64_t bits_per_second = 115200;
  uint32_t latency_us = 1000;
  uint32_t loss_per_million = 0;  // bytes lost per million
  uint32_t flip_per_million = 0;  // bytes with one flipped bit per million
  uint64_t seed = 1;
};

// The links the issue names, as their payload rates (framing of the medium
// included): 115,200 baud with 8N1 is 11,520 bytes/s; USB 1.1 full speed
// moves ~1 MB/s of bulk data; 802.11b ~5 Mbit/s of its 11.
inline constexpr LinkProfile kSerial115200{92160, 1000, 0, 0, 1};
inline constexpr LinkProfile kUsb11{8000000, 1000, 0, 0, 1};
inline constexpr LinkProfile k80211b{5000000, 2000, 0, 0, 1};

class ShapedPipe;

class ShapedEnd final : public Transport {
 public:
  TransportStatus read(uint8_t* out, size_t capacity, size_t* moved) override;
  TransportStatus write(const uint8_t* data, size_t size, size_t* moved) override;
  void close() override;
  const char* last_error() const override { return "shaped link: the other end closed"; }

 private:
  friend class ShapedPipe;
  ShapedPipe* pipe_ = nullptr;
  int side_ = 0;
};

class ShapedPipe {
 public:
  ShapedPipe(const LinkProfile& down, const LinkProfile& up, size_t capacity = 1 << 22);
  ShapedPipe(const ShapedPipe&) = delete;
  ShapedPipe& operator=(const ShapedPipe&) = delete;
  ShapedEnd& server() { return ends_[0]; }  // writes go down to the client
  ShapedEnd& client() { return ends_[1]; }  // writes go up to the server
  void advance(uint64_t us) { now_us_ += us; }
  uint64_t now_us() const { return now_us_; }
  // When the last byte written so far reaches the other end (for idling to it).
  uint64_t drained_at(int side) const { return links_[side].free_at_us + profile(side).latency_us; }
  uint64_t lost(int side) const { return links_[side].lost; }
  uint64_t flipped(int side) const { return links_[side].flipped; }

 private:
  friend class ShapedEnd;
  struct InFlight {
    uint64_t at_us;
    uint8_t byte;
  };
  struct Link {
    std::deque<InFlight> bytes;
    uint64_t free_at_us = 0;
    uint64_t rng;
    uint64_t lost = 0, flipped = 0;
  };
  const LinkProfile& profile(int side) const { return side == 0 ? down_ : up_; }
  uint32_t random(Link& l);
  LinkProfile down_, up_;
  size_t capacity_;
  uint64_t now_us_ = 0;
  Link links_[2];  // links_[k]: written by side k
  bool closed_[2] = {false, false};
  ShapedEnd ends_[2];
};

}  // namespace stipple
