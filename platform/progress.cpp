#include "platform/progress.h"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>

namespace stipple {

ProgressBar::ProgressBar(std::string label, bool enabled)
    : label_(std::move(label)), active_(enabled && isatty(STDERR_FILENO) != 0) {}

ProgressBar::~ProgressBar() { finish(); }

void ProgressBar::update(double fraction, const std::string& detail) {
  if (!active_) return;
  const auto now = std::chrono::steady_clock::now();
  if (drawn_ && fraction < 1.0 && now - last_ < std::chrono::milliseconds(100)) return;
  if (!drawn_) start_ = now;
  last_ = now;
  drawn_ = true;
  fraction = std::clamp(fraction, 0.0, 1.0);
  constexpr int kWidth = 30;
  const int filled = static_cast<int>(fraction * kWidth + 0.5);
  std::string bar(static_cast<size_t>(filled), '#');
  bar.append(static_cast<size_t>(kWidth - filled), '.');
  // The time left, from the pace so far, once there is a pace to go by.
  char left[32] = "";
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  if (fraction >= 0.02 && fraction < 1.0 && elapsed >= 2.0) {
    const double rest = elapsed * (1.0 - fraction) / fraction;
    if (rest < 90) std::snprintf(left, sizeof left, "  ~%.0f s left", rest);
    else std::snprintf(left, sizeof left, "  ~%.0f min left", rest / 60);
  }
  std::fprintf(stderr, "\r\033[K%s [%s] %3d%%  %s%s", label_.c_str(), bar.c_str(),
               static_cast<int>(fraction * 100.0 + 0.5), detail.c_str(), left);
  std::fflush(stderr);
}

void ProgressBar::finish() {
  if (active_ && drawn_) {
    std::fprintf(stderr, "\r\033[K");
    std::fflush(stderr);
  }
  drawn_ = false;
}

double monotonic_seconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

uint64_t physical_memory_bytes() {
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
  return pages > 0 && page > 0 ? static_cast<uint64_t>(pages) * static_cast<uint64_t>(page) : 0;
}

size_t peak_rss_bytes() {
  rusage usage{};
  if (getrusage(RUSAGE_SELF, &usage) != 0) return 0;
  return static_cast<size_t>(usage.ru_maxrss) * 1024;  // Linux reports KiB
}

}  // namespace stipple
