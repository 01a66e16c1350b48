// stipple platform — what every display shares. See display.h.
#include "platform/display.h"

#include <chrono>

namespace stipple {

uint64_t Display::now_us() const {
  const auto t = std::chrono::steady_clock::now().time_since_epoch();
  return static_cast<uint64_t>(std::chrono::duration_cast<std::chrono::microseconds>(t).count());
}

}  // namespace stipple
