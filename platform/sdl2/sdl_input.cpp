// stipple platform — SDL2 events as the device's input. See sdl_input.h.
#include "platform/sdl2/sdl_input.h"

#include <algorithm>
#include <cstring>

namespace stipple {
namespace {

// The keyboard as the device's buttons.
Button button_of(SDL_Scancode s) {
  switch (s) {
    case SDL_SCANCODE_UP:
    case SDL_SCANCODE_W: return Button::kUp;
    case SDL_SCANCODE_DOWN:
    case SDL_SCANCODE_S: return Button::kDown;
    case SDL_SCANCODE_LEFT:
    case SDL_SCANCODE_A: return Button::kLeft;
    case SDL_SCANCODE_RIGHT:
    case SDL_SCANCODE_D: return Button::kRight;
    case SDL_SCANCODE_RETURN:
    case SDL_SCANCODE_SPACE: return Button::kSelect;
    case SDL_SCANCODE_C: return Button::kColor;
    case SDL_SCANCODE_L: return Button::kLighting;
    case SDL_SCANCODE_Q: return Button::kQuality;
    default: return Button::kNone;
  }
}

SDL_Scancode scancode_of(Button b) {
  switch (b) {
    case Button::kUp: return SDL_SCANCODE_UP;
    case Button::kDown: return SDL_SCANCODE_DOWN;
    case Button::kLeft: return SDL_SCANCODE_LEFT;
    case Button::kRight: return SDL_SCANCODE_RIGHT;
    case Button::kSelect: return SDL_SCANCODE_RETURN;
    case Button::kColor: return SDL_SCANCODE_C;
    case Button::kLighting: return SDL_SCANCODE_L;
    case Button::kQuality: return SDL_SCANCODE_Q;
    case Button::kNone: break;
  }
  return SDL_SCANCODE_UNKNOWN;
}

}  // namespace

bool sdl_translate(const SDL_Event& e, const SdlInputGeometry& g, bool* stylus_down, InputEvent* event) {
  *event = InputEvent{};
  const auto to_screen = [&](int wx, int wy) {
    event->x = std::clamp(wx / g.scale - g.margin, 0, g.width - 1);
    event->y = std::clamp(wy / g.scale - g.margin, 0, g.height - 1);
  };
  switch (e.type) {
    case SDL_QUIT: event->kind = InputKind::kQuit; return true;
    case SDL_KEYDOWN:
    case SDL_KEYUP: {
      if (e.key.keysym.scancode == SDL_SCANCODE_ESCAPE) {
        if (e.type != SDL_KEYDOWN) return false;
        event->kind = InputKind::kQuit;
        return true;
      }
      const Button b = button_of(e.key.keysym.scancode);
      if (b == Button::kNone || e.key.repeat) return false;  // held keys: the program sees down, then up
      event->kind = e.type == SDL_KEYDOWN ? InputKind::kButtonDown : InputKind::kButtonUp;
      event->button = b;
      return true;
    }
    case SDL_MOUSEBUTTONDOWN: {
      if (e.button.button != SDL_BUTTON_LEFT) return false;
      const int sx = e.button.x / g.scale - g.margin, sy = e.button.y / g.scale - g.margin;
      if (sx < 0 || sy < 0 || sx >= g.width || sy >= g.height) return false;  // off the screen
      *stylus_down = true;
      event->kind = InputKind::kStylusDown;
      to_screen(e.button.x, e.button.y);
      return true;
    }
    case SDL_MOUSEMOTION:
      if (!*stylus_down) return false;
      event->kind = InputKind::kStylusMove;
      to_screen(e.motion.x, e.motion.y);
      return true;
    case SDL_MOUSEBUTTONUP:
      if (e.button.button != SDL_BUTTON_LEFT || !*stylus_down) return false;
      *stylus_down = false;
      event->kind = InputKind::kStylusUp;
      to_screen(e.button.x, e.button.y);
      return true;
    default: return false;
  }
}

bool sdl_inject(const InputEvent& in, const SdlInputGeometry& g) {
  SDL_Event e;
  std::memset(&e, 0, sizeof e);
  const int wx = (in.x + g.margin) * g.scale + g.scale / 2, wy = (in.y + g.margin) * g.scale + g.scale / 2;
  switch (in.kind) {
    case InputKind::kQuit: e.type = SDL_QUIT; break;
    case InputKind::kButtonDown:
    case InputKind::kButtonUp:
      e.type = in.kind == InputKind::kButtonDown ? SDL_KEYDOWN : SDL_KEYUP;
      e.key.state = in.kind == InputKind::kButtonDown ? SDL_PRESSED : SDL_RELEASED;
      e.key.keysym.scancode = scancode_of(in.button);
      e.key.keysym.sym = SDL_GetKeyFromScancode(e.key.keysym.scancode);
      break;
    case InputKind::kStylusDown:
    case InputKind::kStylusUp:
      e.type = in.kind == InputKind::kStylusDown ? SDL_MOUSEBUTTONDOWN : SDL_MOUSEBUTTONUP;
      e.button.button = SDL_BUTTON_LEFT;
      e.button.state = in.kind == InputKind::kStylusDown ? SDL_PRESSED : SDL_RELEASED;
      e.button.x = wx;
      e.button.y = wy;
      break;
    case InputKind::kStylusMove:
      e.type = SDL_MOUSEMOTION;
      e.motion.x = wx;
      e.motion.y = wy;
      e.motion.state = SDL_BUTTON_LMASK;
      break;
    case InputKind::kNone: return false;
  }
  return SDL_PushEvent(&e) == 1;
}

}  // namespace stipple
