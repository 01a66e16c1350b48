// stipple platform — the SDL2 display. See sdl_display.h.
#include "platform/sdl2/sdl_display.h"

#include "platform/sdl2/sdl_input.h"

#include <SDL.h>

#include <algorithm>
#include <cstdio>
#include <cstring>

#include "platform/text.h"

namespace stipple {
namespace {

constexpr int kStatusHeight = 18;  // two 7-px lines and their gaps
constexpr int kPadHeight = 30;     // the D-pad and the buttons

constexpr uint32_t kBody = 0x2B2F36, kBezel = 0x111316, kText = 0x9FE0A0, kKey = 0x4A505B, kKeyText = 0xD0D4DA,
                   kKeyLit = 0xF2C14E, kOverlay = 0x101418;

struct Canvas {
  uint8_t* rgb;
  int w, h;
  void fill(int x0, int y0, int x1, int y1, uint32_t color) { fill_rect(rgb, w, h, x0, y0, x1, y1, color); }
  void text(int x, int y, const std::string& s, uint32_t color) { draw_text(rgb, w, h, x, y, s, color); }
  void key(int x, int y, int kw, int kh, const char* label, bool lit) {
    const uint32_t face = lit ? kKeyLit : kKey;
    fill(x + 1, y, x + kw - 1, y + kh, face);  // corners cut: a rounded look at this size
    fill(x, y + 1, x + kw, y + kh - 1, face);
    const int len = static_cast<int>(std::strlen(label));
    text(x + (kw - kGlyphAdvance * len + 1) / 2, y + (kh - kGlyphHeight) / 2, label, lit ? kBody : kKeyText);
  }
};

}  // namespace

SdlDisplay::~SdlDisplay() {
  if (texture_) SDL_DestroyTexture(texture_);
  if (renderer_) SDL_DestroyRenderer(renderer_);
  if (window_) SDL_DestroyWindow(window_);
  if (sdl_) SDL_QuitSubSystem(SDL_INIT_VIDEO);
}

bool SdlDisplay::open(const SdlDisplayOptions& options, std::string& error) {
  if (options.width < 16 || options.height < 16 || options.width > 4096 || options.height > 4096 || options.scale < 0 ||
      options.scale > 4)
    return error = "the emulated screen must be 16..4096 px a side and the scale 1..4", false;
  options_ = options;
  if (!sdl_open_video(options.headless, error)) return false;
  sdl_ = true;
  device_w_ = options.width + 2 * kMargin;
  status_y_ = kMargin + options.height + 4;
  pad_y_ = status_y_ + kStatusHeight + 2;
  device_h_ = pad_y_ + kPadHeight + kMargin / 2;
  device_.assign(static_cast<size_t>(device_w_) * device_h_ * 3, 0);
  // The window fits the screen: the default scale (2) or the one asked for,
  // made smaller while the window would be taller or wider than the
  // display's usable area (a 1080-line screen less its panels).
  const int asked = options.scale == 0 ? 2 : options.scale;
  options_.scale = asked;
  SDL_Rect usable;
  if (!options.headless && SDL_GetDisplayUsableBounds(0, &usable) == 0 && usable.h > 0 && usable.w > 0) {
    while (options_.scale > 1 && (device_h_ * options_.scale > usable.h || device_w_ * options_.scale > usable.w))
      --options_.scale;
    if (options_.scale < asked && options.scale != 0)
      std::fprintf(stderr, "stipple: --scale %d would make the window %dx%d, larger than the screen's %dx%d: scale %d\n",
                   asked, device_w_ * asked, device_h_ * asked, usable.w, usable.h, options_.scale);
  }
  const int ww = device_w_ * options_.scale, wh = device_h_ * options_.scale;
  window_ = SDL_CreateWindow(options.title.c_str(), SDL_WINDOWPOS_CENTERED, SDL_WINDOWPOS_CENTERED, ww, wh,
                             options.headless ? SDL_WINDOW_HIDDEN : SDL_WINDOW_SHOWN);
  if (window_ == nullptr) return error = std::string("SDL window: ") + SDL_GetError(), false;
  renderer_ = SDL_CreateRenderer(window_, -1, options.headless ? SDL_RENDERER_SOFTWARE : 0);
  if (renderer_ == nullptr) renderer_ = SDL_CreateRenderer(window_, -1, SDL_RENDERER_SOFTWARE);
  if (renderer_ == nullptr) return error = std::string("SDL renderer: ") + SDL_GetError(), false;
  texture_ = SDL_CreateTexture(renderer_, SDL_PIXELFORMAT_RGB24, SDL_TEXTUREACCESS_STREAMING, device_w_, device_h_);
  if (texture_ == nullptr) return error = std::string("SDL texture: ") + SDL_GetError(), false;
  SDL_SetTextureScaleMode(texture_, SDL_ScaleModeNearest);
  screen_.width = options.width;
  screen_.height = options.height;
  screen_.rgb.assign(static_cast<size_t>(options.width) * options.height * 3, 0);
  compose(screen_);
  return true;
}

void SdlDisplay::set_status(const std::string& line1, const std::string& line2) {
  status_[0] = line1;
  status_[1] = line2;
}

int SdlDisplay::keys(KeyRect out[kKeys]) const {
  // The D-pad on the left (four arms round a centre), the buttons on the right.
  const int cx = kMargin + 14, cy = pad_y_ + kPadHeight / 2, s = 8;
  out[0] = KeyRect{Button::kUp, cx - s / 2, cy - s / 2 - s, s, s, ""};
  out[1] = KeyRect{Button::kDown, cx - s / 2, cy + s / 2, s, s, ""};
  out[2] = KeyRect{Button::kLeft, cx - s / 2 - s, cy - s / 2, s, s, ""};
  out[3] = KeyRect{Button::kRight, cx + s / 2, cy - s / 2, s, s, ""};
  static const char* const labels[] = {"SEL", "C", "L", "Q"};
  static const Button buttons[] = {Button::kSelect, Button::kColor, Button::kLighting, Button::kQuality};
  int x = device_w_ - kMargin;
  for (int k = 3; k >= 0; --k) {
    const int bw = k == 0 ? 22 : 14;
    x -= bw;
    out[4 + k] = KeyRect{buttons[k], x, cy - 6, bw, 13, labels[k]};
    x -= 4;
  }
  return kKeys;
}

void SdlDisplay::compose(const Image& screen) {
  Canvas c{device_.data(), device_w_, device_h_};
  c.fill(0, 0, device_w_, device_h_, kBody);
  c.fill(kMargin - 2, kMargin - 2, kMargin + options_.width + 2, kMargin + options_.height + 2, kBezel);
  const int w = std::min<int>(screen.width, options_.width), h = std::min<int>(screen.height, options_.height);
  for (int y = 0; y < h; ++y)
    std::memcpy(&device_[(static_cast<size_t>(kMargin + y) * device_w_ + kMargin) * 3],
                &screen.rgb[static_cast<size_t>(y) * screen.width * 3], static_cast<size_t>(w) * 3);
  c.fill(kMargin - 2, status_y_ - 2, kMargin + options_.width + 2, status_y_ + kStatusHeight, kBezel);
  c.text(kMargin + 1, status_y_, status_[0], kText);
  c.text(kMargin + 1, status_y_ + 9, status_[1], kText);
  // The D-pad (its centre too) and the buttons, each lit while pressed.
  KeyRect k[kKeys];
  keys(k);
  c.fill(k[2].x + k[2].w, k[0].y + k[0].h, k[3].x, k[1].y, kKey);
  for (const KeyRect& key : k) c.key(key.x, key.y, key.w, key.h, key.label, lit_[static_cast<int>(key.button)]);
  // The help, over the screen.
  if (overlay_ && !overlay_->empty()) {
    const int lines = static_cast<int>(overlay_->size()), box_h = lines * 9 + 6;
    const int y0 = kMargin + std::max(0, (options_.height - box_h) / 2);
    c.fill(kMargin + 4, y0, kMargin + options_.width - 4, y0 + box_h, kOverlay);
    for (int i = 0; i < lines; ++i) c.text(kMargin + 8, y0 + 4 + 9 * i, (*overlay_)[static_cast<size_t>(i)], kText);
  }
}

bool SdlDisplay::present(const uint8_t* frame, size_t stride, uint16_t width, uint16_t height, PixelFormat format,
                         std::string& error) {
  if (renderer_ == nullptr) return error = "the SDL display is not open", false;
  image_from_frame(frame, stride, width, height, format, screen_);
  compose(screen_);
  if (SDL_UpdateTexture(texture_, nullptr, device_.data(), device_w_ * 3) != 0 || SDL_RenderClear(renderer_) != 0 ||
      SDL_RenderCopy(renderer_, texture_, nullptr, nullptr) != 0)
    return error = std::string("SDL: ") + SDL_GetError(), false;
  SDL_RenderPresent(renderer_);
  return true;
}

bool SdlDisplay::screenshot(Image& out, std::string& error) {
  if (renderer_ == nullptr) return error = "the SDL display is not open", false;
  int w = 0, h = 0;
  if (SDL_GetRendererOutputSize(renderer_, &w, &h) != 0) return error = std::string("SDL: ") + SDL_GetError(), false;
  out.width = w;
  out.height = h;
  out.rgb.assign(static_cast<size_t>(w) * h * 3, 0);
  if (SDL_RenderClear(renderer_) != 0 || SDL_RenderCopy(renderer_, texture_, nullptr, nullptr) != 0 ||
      SDL_RenderReadPixels(renderer_, nullptr, SDL_PIXELFORMAT_RGB24, out.rgb.data(), w * 3) != 0)
    return error = std::string("SDL read-back: ") + SDL_GetError(), false;
  return true;
}

bool SdlDisplay::poll(InputEvent* event) {
  const SdlInputGeometry g{options_.scale, kMargin, options_.width, options_.height};
  SDL_Event e;
  while (SDL_PollEvent(&e)) {
    // The on-screen keys, pressed with the mouse.
    if (e.type == SDL_MOUSEBUTTONDOWN && e.button.button == SDL_BUTTON_LEFT && mouse_key_ == Button::kNone) {
      const int dx = e.button.x / options_.scale, dy = e.button.y / options_.scale;
      KeyRect k[kKeys];
      keys(k);
      for (const KeyRect& key : k)
        if (dx >= key.x && dx < key.x + key.w && dy >= key.y && dy < key.y + key.h) {
          mouse_key_ = key.button;
          lit_[static_cast<int>(key.button)] = true;
          *event = InputEvent{InputKind::kButtonDown, key.button, 0, 0};
          return true;
        }
    }
    if (e.type == SDL_MOUSEBUTTONUP && e.button.button == SDL_BUTTON_LEFT && mouse_key_ != Button::kNone) {
      lit_[static_cast<int>(mouse_key_)] = false;
      *event = InputEvent{InputKind::kButtonUp, mouse_key_, 0, 0};
      mouse_key_ = Button::kNone;
      return true;
    }
    if (sdl_translate(e, g, &pointer_, event)) {
      if (event->kind == InputKind::kButtonDown || event->kind == InputKind::kButtonUp)
        lit_[static_cast<int>(event->button)] = event->kind == InputKind::kButtonDown;
      return true;
    }
  }
  return false;
}

bool SdlDisplay::key_rect(Button b, int* x, int* y) const {
  KeyRect k[kKeys];
  keys(k);
  for (const KeyRect& key : k)
    if (key.button == b) {
      *x = (key.x + key.w / 2) * options_.scale;
      *y = (key.y + key.h / 2) * options_.scale;
      return true;
    }
  return false;
}

bool SdlDisplay::click(Button b, bool down) {
  int x = 0, y = 0;
  if (!key_rect(b, &x, &y)) return false;
  SDL_Event e;
  std::memset(&e, 0, sizeof e);
  e.type = down ? SDL_MOUSEBUTTONDOWN : SDL_MOUSEBUTTONUP;
  e.button.button = SDL_BUTTON_LEFT;
  e.button.state = down ? SDL_PRESSED : SDL_RELEASED;
  e.button.x = x;
  e.button.y = y;
  return SDL_PushEvent(&e) == 1;
}

bool SdlDisplay::inject(const InputEvent& in) {
  return sdl_inject(in, SdlInputGeometry{options_.scale, kMargin, options_.width, options_.height});
}

}  // namespace stipple
