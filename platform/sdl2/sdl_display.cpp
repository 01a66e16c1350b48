// stipple platform — the SDL2 display. See sdl_display.h.
#include "platform/sdl2/sdl_display.h"

#include "platform/sdl2/sdl_input.h"

#include <SDL.h>

#include <algorithm>
#include <cstring>

namespace stipple {
namespace {

constexpr int kStatusHeight = 18;  // two 7-px lines and their gaps
constexpr int kPadHeight = 30;     // the D-pad and the buttons

constexpr uint32_t kBody = 0x2B2F36, kBezel = 0x111316, kText = 0x9FE0A0, kKey = 0x4A505B, kKeyText = 0xD0D4DA;

// A 5x7 font for the status line and the button labels: rows top to
// bottom, bit 4 the leftmost column. SDL draws no text and the line is a
// few dozen characters of digits and words, so a table is all it takes (a
// font library would add a dependency and a font file for it).
struct Glyph {
  char c;
  uint8_t rows[7];
};
constexpr Glyph kFont[] = {
    {'0', {0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E}}, {'1', {0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E}},
    {'2', {0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F}}, {'3', {0x1F, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0E}},
    {'4', {0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02}}, {'5', {0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E}},
    {'6', {0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E}}, {'7', {0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08}},
    {'8', {0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E}}, {'9', {0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C}},
    {'A', {0x0E, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11}}, {'B', {0x1E, 0x11, 0x11, 0x1E, 0x11, 0x11, 0x1E}},
    {'C', {0x0E, 0x11, 0x10, 0x10, 0x10, 0x11, 0x0E}}, {'D', {0x1C, 0x12, 0x11, 0x11, 0x11, 0x12, 0x1C}},
    {'E', {0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x1F}}, {'F', {0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x10}},
    {'G', {0x0E, 0x11, 0x10, 0x17, 0x11, 0x11, 0x0F}}, {'H', {0x11, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11}},
    {'I', {0x0E, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0E}}, {'J', {0x07, 0x02, 0x02, 0x02, 0x02, 0x12, 0x0C}},
    {'K', {0x11, 0x12, 0x14, 0x18, 0x14, 0x12, 0x11}}, {'L', {0x10, 0x10, 0x10, 0x10, 0x10, 0x10, 0x1F}},
    {'M', {0x11, 0x1B, 0x15, 0x15, 0x11, 0x11, 0x11}}, {'N', {0x11, 0x11, 0x19, 0x15, 0x13, 0x11, 0x11}},
    {'O', {0x0E, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E}}, {'P', {0x1E, 0x11, 0x11, 0x1E, 0x10, 0x10, 0x10}},
    {'Q', {0x0E, 0x11, 0x11, 0x11, 0x15, 0x12, 0x0D}}, {'R', {0x1E, 0x11, 0x11, 0x1E, 0x14, 0x12, 0x11}},
    {'S', {0x0F, 0x10, 0x10, 0x0E, 0x01, 0x01, 0x1E}}, {'T', {0x1F, 0x04, 0x04, 0x04, 0x04, 0x04, 0x04}},
    {'U', {0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E}}, {'V', {0x11, 0x11, 0x11, 0x11, 0x11, 0x0A, 0x04}},
    {'W', {0x11, 0x11, 0x11, 0x15, 0x15, 0x15, 0x0A}}, {'X', {0x11, 0x11, 0x0A, 0x04, 0x0A, 0x11, 0x11}},
    {'Y', {0x11, 0x11, 0x11, 0x0A, 0x04, 0x04, 0x04}}, {'Z', {0x1F, 0x01, 0x02, 0x04, 0x08, 0x10, 0x1F}},
    {'.', {0x00, 0x00, 0x00, 0x00, 0x00, 0x0C, 0x0C}}, {':', {0x00, 0x0C, 0x0C, 0x00, 0x0C, 0x0C, 0x00}},
    {'/', {0x00, 0x01, 0x02, 0x04, 0x08, 0x10, 0x00}}, {'%', {0x18, 0x19, 0x02, 0x04, 0x08, 0x13, 0x03}},
    {'-', {0x00, 0x00, 0x00, 0x1F, 0x00, 0x00, 0x00}}, {',', {0x00, 0x00, 0x00, 0x00, 0x0C, 0x04, 0x08}},
    {'(', {0x02, 0x04, 0x08, 0x08, 0x08, 0x04, 0x02}}, {')', {0x08, 0x04, 0x02, 0x02, 0x02, 0x04, 0x08}},
};

const Glyph* glyph(char c) {
  if (c >= 'a' && c <= 'z') c = static_cast<char>(c - 'a' + 'A');
  for (const Glyph& g : kFont)
    if (g.c == c) return &g;
  return nullptr;  // a space, or a character the font lacks: blank
}

struct Canvas {
  uint8_t* rgb;
  int w, h;
  void fill(int x0, int y0, int x1, int y1, uint32_t color) {
    for (int y = std::max(y0, 0); y < std::min(y1, h); ++y)
      for (int x = std::max(x0, 0); x < std::min(x1, w); ++x) {
        uint8_t* p = rgb + (static_cast<size_t>(y) * w + x) * 3;
        p[0] = static_cast<uint8_t>(color >> 16);
        p[1] = static_cast<uint8_t>(color >> 8);
        p[2] = static_cast<uint8_t>(color);
      }
  }
  void text(int x, int y, const std::string& s, uint32_t color) {
    for (char c : s) {
      if (const Glyph* g = glyph(c))
        for (int r = 0; r < 7; ++r)
          for (int k = 0; k < 5; ++k)
            if ((g->rows[r] >> (4 - k)) & 1) fill(x + k, y + r, x + k + 1, y + r + 1, color);
      x += 6;
    }
  }
  void key(int x, int y, int kw, int kh, const char* label) {
    fill(x + 1, y, x + kw - 1, y + kh, kKey);  // corners cut: a rounded look at this size
    fill(x, y + 1, x + kw, y + kh - 1, kKey);
    const int len = static_cast<int>(std::strlen(label));
    text(x + (kw - 6 * len + 1) / 2, y + (kh - 7) / 2, label, kKeyText);
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
  if (options.width < 16 || options.height < 16 || options.width > 4096 || options.height > 4096 || options.scale < 1 ||
      options.scale > 4)
    return error = "the emulated screen must be 16..4096 px a side and the scale 1..4", false;
  options_ = options;
  if (options.headless) SDL_SetHint(SDL_HINT_VIDEODRIVER, "offscreen");
  if (SDL_InitSubSystem(SDL_INIT_VIDEO) != 0) return error = std::string("SDL: ") + SDL_GetError(), false;
  sdl_ = true;
  device_w_ = options.width + 2 * kMargin;
  status_y_ = kMargin + options.height + 4;
  pad_y_ = status_y_ + kStatusHeight + 2;
  device_h_ = pad_y_ + kPadHeight + kMargin / 2;
  device_.assign(static_cast<size_t>(device_w_) * device_h_ * 3, 0);
  const int ww = device_w_ * options.scale, wh = device_h_ * options.scale;
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
  // The D-pad on the left, the buttons on the right.
  const int cx = kMargin + 14, cy = pad_y_ + kPadHeight / 2, s = 8;
  c.fill(cx - s / 2, cy - s / 2 - s, cx + s / 2, cy + s / 2 + s, kKey);
  c.fill(cx - s / 2 - s, cy - s / 2, cx + s / 2 + s, cy + s / 2, kKey);
  static const char* const labels[] = {"SEL", "C", "L", "Q"};
  int x = device_w_ - kMargin;
  for (int k = 3; k >= 0; --k) {
    const int bw = k == 0 ? 22 : 14;
    x -= bw;
    c.key(x, cy - 6, bw, 13, labels[k]);
    x -= 4;
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
  while (SDL_PollEvent(&e))
    if (sdl_translate(e, g, &stylus_down_, event)) return true;
  return false;
}

bool SdlDisplay::inject(const InputEvent& in) {
  return sdl_inject(in, SdlInputGeometry{options_.scale, kMargin, options_.width, options_.height});
}

}  // namespace stipple
