// stipple platform — which of the pointer's gestures is under way between
// SDL events (platform/sdl2/sdl_input.h), without SDL's headers, for the
// windows that keep it.
#pragma once

#include <cstdint>

namespace stipple {

struct SdlPointer {
  enum Gesture : uint8_t { kNone, kStylus, kOrbit } gesture = kNone;
};

}  // namespace stipple
