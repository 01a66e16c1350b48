// stipple platform — a display: where a client's frames go and where its
// input comes from. One interface, one folder per backend (SDL's shape):
//   fbdev/  a Linux framebuffer device (the handheld)
//   null/   no screen: keeps every frame, writes it to a file (tests, CI)
//   sdl2/   a desktop window emulating the device (issue 12)
//
// present() takes the client's native frame — `height` rows of `stride`
// bytes in its pixel format — and converts it into the device's format on
// the way; it allocates nothing (every buffer is sized when the display is
// opened). A display is used from one thread. Failures return false and say
// why in `error`, naming the device or file.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "raster/point_raster.h"

namespace stipple {

// What the user did, as a handheld has it: a D-pad, a few buttons, a
// stylus. The desktop viewers add what a mouse and keyboard do there: a
// drag that orbits (kOrbit*, the left button), the wheel (kWheel: y notches,
// positive away from the user, towards the screen) and three keys (reset,
// screenshot, help) the device lacks.
enum class InputKind : uint8_t {
  kNone, kQuit, kButtonDown, kButtonUp, kStylusDown, kStylusMove, kStylusUp, kOrbitDown, kOrbitMove, kOrbitUp, kWheel
};
enum class Button : uint8_t { kNone, kUp, kDown, kLeft, kRight, kSelect, kColor, kLighting, kQuality, kReset, kScreenshot, kHelp };
inline constexpr int kButtonCount = 12;

struct InputEvent {
  InputKind kind = InputKind::kNone;
  Button button = Button::kNone;
  int x = 0, y = 0;  // stylus or pointer position, frame pixels; kWheel: y notches
};

class Display {
 public:
  virtual ~Display() = default;
  // The frame size and pixel format the display shows natively; a client
  // that renders in these needs no conversion (or only a copy).
  virtual uint16_t width() const = 0;
  virtual uint16_t height() const = 0;
  virtual PixelFormat format() const = 0;
  // Shows one frame (cropped to the display when larger).
  [[nodiscard]] virtual bool present(const uint8_t* frame, size_t stride, uint16_t width, uint16_t height,
                                     PixelFormat format, std::string& error) = 0;
  // The next pending input event; false when there is none. Never blocks.
  virtual bool poll(InputEvent* event) = 0;
  // The display's clock, microseconds from an arbitrary origin, never going
  // back: frame pacing and the status line's rates. A monotonic wall clock
  // unless a backend says otherwise (the null display's is simulated).
  virtual uint64_t now_us() const;
};

}  // namespace stipple
