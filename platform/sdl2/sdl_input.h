// stipple platform — SDL2 events as the device's input (platform/display.h),
// shared by the emulator's display and the GL client's window:
//   arrow keys            the D-pad; Enter or Space select; C L Q the buttons
//   R, S or F12, H or F1  reset the view, a screenshot, the keys on screen
//   left drag             orbit (kOrbit*: where the pointer went, screen px)
//   right drag, or shift with the left button
//                         the stylus: the refinement window
//   wheel                 kWheel (notches)
//   Escape, closing the window   quit
// Pointer events count inside the screen only (a press outside it is the
// emulator's to take: its on-screen keys).
#pragma once

#include <SDL.h>

#include <string>

#include "platform/display.h"
#include "platform/sdl2/sdl_pointer.h"

namespace stipple {

// Where the screen sits in the window: window pixels per screen pixel, the
// screen's offset in screen pixels, its size.
struct SdlInputGeometry {
  int scale, margin, width, height;
};

// One SDL event as input; false when it means nothing to the device.
bool sdl_translate(const SDL_Event& e, const SdlInputGeometry& g, SdlPointer* pointer, InputEvent* out);
// Queues `in` as the SDL event a user would make (the stylus as the right
// button, an orbit as the left, a button as its first key).
bool sdl_inject(const InputEvent& in, const SdlInputGeometry& g);

// SDL's video: `headless` asks for its offscreen driver. Without it, a
// machine with no display (DISPLAY and WAYLAND_DISPLAY unset: an SSH
// session, a container) is refused at once with a message that says so,
// rather than SDL falling back to a driver that shows nothing.
bool sdl_open_video(bool headless, std::string& error);

}  // namespace stipple
