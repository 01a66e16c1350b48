// stipple core — carving one caller-provided buffer into 8-byte-aligned
// pieces: how every part sizes its storage (`*_bytes`) and then finds its
// tables in it, with one definition of the alignment.
#pragma once

#include <cstddef>

namespace stipple {

constexpr size_t align8(size_t n) { return (n + 7) & ~size_t{7}; }

// take(bytes) returns the offset of the next piece and moves past it,
// rounded up to 8 bytes; total() is the storage all pieces need.
class ArenaCarver {
 public:
  size_t take(size_t bytes) {
    const size_t here = at_;
    at_ += align8(bytes);
    return here;
  }
  size_t total() const { return at_; }

 private:
  size_t at_ = 0;
};

}  // namespace stipple
