// stipple platform — SDL2 events as the device's input. See sdl_input.h.
#include "platform/sdl2/sdl_input.h"

#include <algorithm>
#include <cstdlib>
#include <cstring>

namespace stipple {
namespace {

// The keyboard as the device's buttons and the viewers' keys.
Button button_of(SDL_Scancode s) {
  switch (s) {
    case SDL_SCANCODE_UP: return Button::kUp;
    case SDL_SCANCODE_DOWN: return Button::kDown;
    case SDL_SCANCODE_LEFT: return Button::kLeft;
    case SDL_SCANCODE_RIGHT: return Button::kRight;
    case SDL_SCANCODE_RETURN:
    case SDL_SCANCODE_SPACE: return Button::kSelect;
    case SDL_SCANCODE_C: return Button::kColor;
    case SDL_SCANCODE_L: return Button::kLighting;
    case SDL_SCANCODE_Q: return Button::kQuality;
    case SDL_SCANCODE_R: return Button::kReset;
    case SDL_SCANCODE_S:
    case SDL_SCANCODE_F12: return Button::kScreenshot;
    case SDL_SCANCODE_H:
    case SDL_SCANCODE_F1: return Button::kHelp;
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
    case Button::kReset: return SDL_SCANCODE_R;
    case Button::kScreenshot: return SDL_SCANCODE_S;
    case Button::kHelp: return SDL_SCANCODE_H;
    case Button::kNone: break;
  }
  return SDL_SCANCODE_UNKNOWN;
}

}  // namespace

bool sdl_translate(const SDL_Event& e, const SdlInputGeometry& g, SdlPointer* pointer, InputEvent* event) {
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
      if (pointer->gesture != SdlPointer::kNone) return false;
      const bool left = e.button.button == SDL_BUTTON_LEFT, right = e.button.button == SDL_BUTTON_RIGHT;
      if (!left && !right) return false;
      const int sx = e.button.x / g.scale - g.margin, sy = e.button.y / g.scale - g.margin;
      if (sx < 0 || sy < 0 || sx >= g.width || sy >= g.height) return false;  // off the screen
      const bool stylus = right || (SDL_GetModState() & KMOD_SHIFT) != 0;
      pointer->gesture = stylus ? SdlPointer::kStylus : SdlPointer::kOrbit;
      event->kind = stylus ? InputKind::kStylusDown : InputKind::kOrbitDown;
      to_screen(e.button.x, e.button.y);
      return true;
    }
    case SDL_MOUSEMOTION:
      if (pointer->gesture == SdlPointer::kNone) return false;
      event->kind = pointer->gesture == SdlPointer::kStylus ? InputKind::kStylusMove : InputKind::kOrbitMove;
      to_screen(e.motion.x, e.motion.y);
      return true;
    case SDL_MOUSEBUTTONUP: {
      if (pointer->gesture == SdlPointer::kNone) return false;
      if (e.button.button != SDL_BUTTON_LEFT && e.button.button != SDL_BUTTON_RIGHT) return false;
      event->kind = pointer->gesture == SdlPointer::kStylus ? InputKind::kStylusUp : InputKind::kOrbitUp;
      pointer->gesture = SdlPointer::kNone;
      to_screen(e.button.x, e.button.y);
      return true;
    }
    case SDL_MOUSEWHEEL: {
      const int notches = e.wheel.direction == SDL_MOUSEWHEEL_FLIPPED ? -e.wheel.y : e.wheel.y;
      if (notches == 0) return false;
      event->kind = InputKind::kWheel;
      event->y = notches;
      return true;
    }
    default: return false;
  }
}

bool sdl_inject(const InputEvent& in, const SdlInputGeometry& g) {
  SDL_Event e;
  std::memset(&e, 0, sizeof e);
  const int wx = (in.x + g.margin) * g.scale + g.scale / 2, wy = (in.y + g.margin) * g.scale + g.scale / 2;
  const auto pointer = [&](Uint32 type, Uint8 button) {
    e.type = type;
    if (type == SDL_MOUSEMOTION) {
      e.motion.x = wx;
      e.motion.y = wy;
      e.motion.state = SDL_BUTTON(button);
    } else {
      e.button.button = button;
      e.button.state = type == SDL_MOUSEBUTTONDOWN ? SDL_PRESSED : SDL_RELEASED;
      e.button.x = wx;
      e.button.y = wy;
    }
  };
  switch (in.kind) {
    case InputKind::kQuit: e.type = SDL_QUIT; break;
    case InputKind::kButtonDown:
    case InputKind::kButtonUp:
      e.type = in.kind == InputKind::kButtonDown ? SDL_KEYDOWN : SDL_KEYUP;
      e.key.state = in.kind == InputKind::kButtonDown ? SDL_PRESSED : SDL_RELEASED;
      e.key.keysym.scancode = scancode_of(in.button);
      e.key.keysym.sym = SDL_GetKeyFromScancode(e.key.keysym.scancode);
      break;
    case InputKind::kStylusDown: pointer(SDL_MOUSEBUTTONDOWN, SDL_BUTTON_RIGHT); break;
    case InputKind::kStylusMove: pointer(SDL_MOUSEMOTION, SDL_BUTTON_RIGHT); break;
    case InputKind::kStylusUp: pointer(SDL_MOUSEBUTTONUP, SDL_BUTTON_RIGHT); break;
    case InputKind::kOrbitDown: pointer(SDL_MOUSEBUTTONDOWN, SDL_BUTTON_LEFT); break;
    case InputKind::kOrbitMove: pointer(SDL_MOUSEMOTION, SDL_BUTTON_LEFT); break;
    case InputKind::kOrbitUp: pointer(SDL_MOUSEBUTTONUP, SDL_BUTTON_LEFT); break;
    case InputKind::kWheel:
      e.type = SDL_MOUSEWHEEL;
      e.wheel.y = in.y;
      e.wheel.direction = SDL_MOUSEWHEEL_NORMAL;
      break;
    case InputKind::kNone: return false;
  }
  return SDL_PushEvent(&e) == 1;
}

bool sdl_open_video(bool headless, std::string& error) {
  if (headless) {
    SDL_SetHint(SDL_HINT_VIDEODRIVER, "offscreen");
  } else {
    const char* x11 = std::getenv("DISPLAY");
    const char* wayland = std::getenv("WAYLAND_DISPLAY");
    const char* driver = std::getenv("SDL_VIDEODRIVER");
    if ((x11 == nullptr || *x11 == 0) && (wayland == nullptr || *wayland == 0) && (driver == nullptr || *driver == 0))
      return error = "no display: DISPLAY and WAYLAND_DISPLAY are not set (an SSH session without -X, a container?); "
                     "--headless -o FRAME.png draws without one",
             false;
  }
  if (SDL_InitSubSystem(SDL_INIT_VIDEO) != 0) return error = std::string("SDL: ") + SDL_GetError(), false;
  const char* used = SDL_GetCurrentVideoDriver();
  const std::string name = used ? used : "";
  if (!headless && (name == "offscreen" || name == "dummy") && std::getenv("SDL_VIDEODRIVER") == nullptr) {
    SDL_QuitSubSystem(SDL_INIT_VIDEO);
    return error = "no display: SDL found only its '" + name + "' video driver; --headless -o FRAME.png draws without one", false;
  }
  return true;
}

}  // namespace stipple
