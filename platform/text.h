// stipple platform — a 5x7 bitmap font for the desktop viewers' status
// lines, help and legends, drawn into RGB888 images. SDL draws no text, and
// what the viewers write is a few dozen characters of digits and words, so
// a 50-glyph table is all it takes (a font library would add a dependency
// and a font file for it). Letters are drawn as capitals; a character the
// font lacks is a blank.
#pragma once

#include <cstdint>
#include <string>

namespace stipple {

inline constexpr int kGlyphWidth = 5, kGlyphHeight = 7, kGlyphAdvance = 6;

// Draws `text` into the w x h RGB888 image at (x, y), each font pixel a
// scale x scale square of `color` (0xRRGGBB); clipped to the image.
void draw_text(uint8_t* rgb, int w, int h, int x, int y, const std::string& text, uint32_t color, int scale = 1);
// Fills [x0, x1) x [y0, y1) with `color`, clipped.
void fill_rect(uint8_t* rgb, int w, int h, int x0, int y0, int x1, int y1, uint32_t color);
// The width of `text` in pixels at scale 1.
inline int text_width(const std::string& text) { return static_cast<int>(text.size()) * kGlyphAdvance; }

}  // namespace stipple
