// stipple platform — the SDL2 display: a desktop window that emulates the
// handheld. The device's screen (240x320 RGB565 by default; any size the
// client renders) sits in a simple device frame with a two-line status line
// under it and the D-pad and buttons drawn below; the whole device image is
// composed at device resolution and scaled x1..x4 by SDL with nearest
// filtering, so every device pixel is a crisp square.
//
// Input as platform/sdl2/sdl_input.h says (arrow keys the D-pad, a left
// drag orbits, a right drag is the stylus, ...); besides, the device's keys
// drawn under the screen are pressed with the mouse, and every key is lit
// while it is held, from the mouse or the keyboard.
//
// `headless` opens SDL's offscreen video driver instead: no window, the same
// composition (screenshot() reads it back). `inject` puts an input event
// into SDL's own queue as the key or mouse event that makes it, so a script
// drives the same path a user does.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "platform/display.h"
#include "platform/image.h"
#include "platform/sdl2/sdl_pointer.h"

struct SDL_Window;
struct SDL_Renderer;
struct SDL_Texture;

namespace stipple {

struct SdlDisplayOptions {
  uint16_t width = 240, height = 320;  // the device's screen, px
  int scale = 2;                       // window pixels per device pixel, 1..4; 0: 2, or less to fit the screen
  bool headless = false;               // SDL's offscreen driver: no window
  std::string title = "stipple";
};

class SdlDisplay final : public Display {
 public:
  SdlDisplay() = default;
  SdlDisplay(const SdlDisplay&) = delete;
  SdlDisplay& operator=(const SdlDisplay&) = delete;
  ~SdlDisplay() override;

  // Opens the window (or the offscreen one); false with SDL's reason.
  bool open(const SdlDisplayOptions& options, std::string& error);

  uint16_t width() const override { return options_.width; }
  uint16_t height() const override { return options_.height; }
  PixelFormat format() const override { return PixelFormat::kRgb565; }
  bool present(const uint8_t* frame, size_t stride, uint16_t width, uint16_t height, PixelFormat format,
               std::string& error) override;
  bool poll(InputEvent* event) override;

  // The status line's two lines (shown with the next present; letters,
  // digits, space and . : / % - , ( ) x).
  void set_status(const std::string& line1, const std::string& line2);
  // The window as it is on screen (scaled device image), for tests and the
  // docs' screenshots.
  bool screenshot(Image& out, std::string& error);
  // Queues `event` as the SDL event a user would make (see above).
  bool inject(const InputEvent& event);
  // Queues a mouse press (or release) on the on-screen key of `b`, as a
  // user's click; false when the device has no such key.
  bool click(Button b, bool down);
  // Lines shown over the screen (the help), kept by the caller; null: none.
  void set_overlay(const std::vector<std::string>* lines) { overlay_ = lines; }

  // The device image's size (unscaled) and where the screen sits in it.
  int device_width() const { return device_w_; }
  int device_height() const { return device_h_; }
  static constexpr int kMargin = 12;

 private:
  struct KeyRect {
    Button button;
    int x, y, w, h;  // device pixels
    const char* label;
  };
  static constexpr int kKeys = 8;  // the D-pad's four, select, colour, lighting, quality
  int keys(KeyRect out[kKeys]) const;
  bool key_rect(Button b, int* x, int* y) const;  // its centre, window pixels
  void compose(const Image& screen);

  SdlDisplayOptions options_;
  SDL_Window* window_ = nullptr;
  SDL_Renderer* renderer_ = nullptr;
  SDL_Texture* texture_ = nullptr;
  bool sdl_ = false;
  int device_w_ = 0, device_h_ = 0, status_y_ = 0, pad_y_ = 0;
  std::vector<uint8_t> device_;  // device_w_ x device_h_ RGB888
  Image screen_;
  std::string status_[2];
  const std::vector<std::string>* overlay_ = nullptr;
  SdlPointer pointer_;
  bool lit_[kButtonCount] = {};
  Button mouse_key_ = Button::kNone;  // the on-screen key the mouse holds
};

}  // namespace stipple
