// stipple platform — the link shaper. See shaped_pipe.h.
#include "platform/shaper/shaped_pipe.h"

namespace stipple {

ShapedPipe::ShapedPipe(const LinkProfile& down, const LinkProfile& up, size_t capacity)
    : down_(down), up_(up), capacity_(capacity) {
  for (int k = 0; k < 2; ++k) {
    ends_[k].pipe_ = this;
    ends_[k].side_ = k;
    links_[k].rng = (k == 0 ? down.seed : up.seed) * 0x9E3779B97F4A7C15ull + 1;
  }
}

uint32_t ShapedPipe::random(Link& l) {  // xorshift64*: one value per byte, seeded
  l.rng ^= l.rng >> 12;
  l.rng ^= l.rng << 25;
  l.rng ^= l.rng >> 27;
  return static_cast<uint32_t>((l.rng * 0x2545F4914F6CDD1Dull) >> 32);
}

TransportStatus ShapedEnd::write(const uint8_t* data, size_t size, size_t* moved) {
  *moved = 0;
  ShapedPipe& p = *pipe_;
  if (p.closed_[side_] || p.closed_[1 - side_]) return TransportStatus::kClosed;
  ShapedPipe::Link& l = p.links_[side_];
  const LinkProfile& prof = p.profile(side_);
  size_t n = 0;
  for (; n < size && l.bytes.size() < p.capacity_; ++n) {
    const uint64_t start = l.free_at_us > p.now_us_ ? l.free_at_us : p.now_us_;
    l.free_at_us = start + (8'000'000 + prof.bits_per_second - 1) / prof.bits_per_second;
    uint8_t byte = data[n];
    if (prof.loss_per_million && p.random(l) % 1000000 < prof.loss_per_million) {
      ++l.lost;
      continue;
    }
    if (prof.flip_per_million && p.random(l) % 1000000 < prof.flip_per_million) {
      byte = static_cast<uint8_t>(byte ^ (1u << (p.random(l) % 8)));
      ++l.flipped;
    }
    l.bytes.push_back({l.free_at_us + prof.latency_us, byte});
  }
  *moved = n;
  return n > 0 ? TransportStatus::kOk : TransportStatus::kTimeout;
}

TransportStatus ShapedEnd::read(uint8_t* out, size_t capacity, size_t* moved) {
  *moved = 0;
  ShapedPipe& p = *pipe_;
  if (p.closed_[side_]) return TransportStatus::kClosed;
  ShapedPipe::Link& l = p.links_[1 - side_];
  size_t n = 0;
  while (n < capacity && !l.bytes.empty() && l.bytes.front().at_us <= p.now_us_) {
    out[n++] = l.bytes.front().byte;
    l.bytes.pop_front();
  }
  *moved = n;
  if (n > 0) return TransportStatus::kOk;
  return p.closed_[1 - side_] && l.bytes.empty() ? TransportStatus::kClosed : TransportStatus::kTimeout;
}

void ShapedEnd::close() { pipe_->closed_[side_] = true; }

}  // namespace stipple
