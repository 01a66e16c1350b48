// stipple platform — an SDL2 window with an OpenGL 3.3 core context, for
// the GL desktop client: the same input as the emulator (platform/sdl2/
// sdl_input.h; the stylus in window pixels), optional multisampling, vsync.
#pragma once

#include <cstdint>
#include <string>

#include "platform/display.h"
#include "platform/sdl2/sdl_pointer.h"

struct SDL_Window;

namespace stipple {

class SdlGlWindow {
 public:
  SdlGlWindow() = default;
  SdlGlWindow(const SdlGlWindow&) = delete;
  SdlGlWindow& operator=(const SdlGlWindow&) = delete;
  ~SdlGlWindow();
  // Opens the window and makes its context current; `msaa` samples (0: none).
  bool open(int width, int height, int msaa, const std::string& title, std::string& error);
  bool poll(InputEvent* event);
  bool inject(const InputEvent& event);
  void swap();
  void set_title(const std::string& title);
  int width() const { return width_; }
  int height() const { return height_; }

 private:
  SDL_Window* window_ = nullptr;
  void* context_ = nullptr;
  bool sdl_ = false;
  SdlPointer pointer_;
  int width_ = 0, height_ = 0;
};

}  // namespace stipple
