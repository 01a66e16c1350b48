// stipple platform — an SDL2 window with an OpenGL context. See sdl_gl_window.h.
#include "platform/sdl2/sdl_gl_window.h"

#include <SDL.h>

#include "platform/sdl2/sdl_input.h"

namespace stipple {

SdlGlWindow::~SdlGlWindow() {
  if (context_) SDL_GL_DeleteContext(static_cast<SDL_GLContext>(context_));
  if (window_) SDL_DestroyWindow(window_);
  if (sdl_) SDL_QuitSubSystem(SDL_INIT_VIDEO);
}

bool SdlGlWindow::open(int width, int height, int msaa, const std::string& title, std::string& error) {
  if (!sdl_open_video(false, error)) return false;
  sdl_ = true;
  SDL_GL_SetAttribute(SDL_GL_CONTEXT_MAJOR_VERSION, 3);
  SDL_GL_SetAttribute(SDL_GL_CONTEXT_MINOR_VERSION, 3);
  SDL_GL_SetAttribute(SDL_GL_CONTEXT_PROFILE_MASK, SDL_GL_CONTEXT_PROFILE_CORE);
  SDL_GL_SetAttribute(SDL_GL_DEPTH_SIZE, 24);
  SDL_GL_SetAttribute(SDL_GL_DOUBLEBUFFER, 1);
  if (msaa > 0) {
    SDL_GL_SetAttribute(SDL_GL_MULTISAMPLEBUFFERS, 1);
    SDL_GL_SetAttribute(SDL_GL_MULTISAMPLESAMPLES, msaa);
  }
  window_ = SDL_CreateWindow(title.c_str(), SDL_WINDOWPOS_CENTERED, SDL_WINDOWPOS_CENTERED, width, height,
                             SDL_WINDOW_OPENGL | SDL_WINDOW_SHOWN);
  if (window_ == nullptr) return error = std::string("SDL window: ") + SDL_GetError(), false;
  context_ = SDL_GL_CreateContext(window_);
  if (context_ == nullptr) return error = std::string("SDL OpenGL 3.3 core context: ") + SDL_GetError(), false;
  SDL_GL_SetSwapInterval(1);
  SDL_GL_GetDrawableSize(window_, &width_, &height_);
  return true;
}

bool SdlGlWindow::poll(InputEvent* event) {
  const SdlInputGeometry g{1, 0, width_, height_};
  SDL_Event e;
  while (SDL_PollEvent(&e))
    if (sdl_translate(e, g, &pointer_, event)) return true;
  return false;
}

bool SdlGlWindow::inject(const InputEvent& event) { return sdl_inject(event, SdlInputGeometry{1, 0, width_, height_}); }

void SdlGlWindow::swap() { SDL_GL_SwapWindow(window_); }

void SdlGlWindow::set_title(const std::string& title) { SDL_SetWindowTitle(window_, title.c_str()); }

}  // namespace stipple
