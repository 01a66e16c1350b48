// stipple platform — a terminal progress bar for long host work.
//
// Draws `label [#####.....]  45%  detail  ~12 s left` on stderr (the time
// left from the pace since the first drawing, shown after 2 s), redrawn in place, only
// when stderr is a terminal (pipes and CI logs stay clean). Redraws are
// rate-limited to ~10 per second, so callers may report progress per item.
// Not thread-safe: report from one thread.
#pragma once

#include <chrono>
#include <cstdint>
#include <string>

namespace stipple {

class ProgressBar {
 public:
  explicit ProgressBar(std::string label, bool enabled = true);
  ~ProgressBar();
  ProgressBar(const ProgressBar&) = delete;
  ProgressBar& operator=(const ProgressBar&) = delete;

  // `fraction` in [0, 1]; `detail` is shown after the percentage.
  void update(double fraction, const std::string& detail = {});
  // Clears the line; called by the destructor.
  void finish();

 private:
  std::string label_;
  bool active_;
  bool drawn_ = false;
  std::chrono::steady_clock::time_point last_, start_;  // start_: the first drawing
};

// Monotonic seconds since an arbitrary origin.
double monotonic_seconds();
// Peak resident set size of this process so far, in bytes (0 if unknown).
size_t peak_rss_bytes();
// Physical memory of this host, in bytes (0 if unknown).
uint64_t physical_memory_bytes();

}  // namespace stipple
