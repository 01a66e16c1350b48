// stipple host — the encoder's one parallel loop: fn(0) .. fn(count - 1) on
// `threads` threads (the caller's among them), handed out `block` indices at
// a time. Results must not depend on which thread ran an index; the callers
// write disjoint outputs or combine fixed chunks in order.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <thread>
#include <vector>

namespace stipple {

template <class Fn>
void parallel_for(size_t count, int threads, size_t block, const Fn& fn) {
  std::atomic<size_t> next{0};
  auto worker = [&]() {
    for (size_t lo; (lo = next.fetch_add(block)) < count;)
      for (size_t k = lo; k < std::min(count, lo + block); ++k) fn(k);
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < std::max(1, threads) && static_cast<size_t>(t) * block < count; ++t) pool.emplace_back(worker);
  worker();
  for (std::thread& t : pool) t.join();
}

}  // namespace stipple
