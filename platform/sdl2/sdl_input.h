// stipple platform — SDL2 events as the device's input (platform/display.h),
// shared by the emulator's display and the GL client's window: arrow keys
// or WASD the D-pad, Enter/Space select, C L Q the buttons, the left mouse
// button the stylus (inside the screen), Escape or closing the window quit.
#pragma once

#include <SDL.h>

#include "platform/display.h"

namespace stipple {

// Where the screen sits in the window: window pixels per screen pixel, the
// screen's offset in screen pixels, its size.
struct SdlInputGeometry {
  int scale, margin, width, height;
};

// One SDL event as input; false when it means nothing to the device.
// `stylus_down` tracks the stylus between events.
bool sdl_translate(const SDL_Event& e, const SdlInputGeometry& g, bool* stylus_down, InputEvent* out);
// Queues `in` as the SDL event a user would make.
bool sdl_inject(const InputEvent& in, const SdlInputGeometry& g);

}  // namespace stipple
