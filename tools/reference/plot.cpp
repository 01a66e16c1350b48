// stipple host — line chart renderer. See plot.h.
#include "tools/reference/plot.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <vector>

namespace stipple {
namespace {

struct Glyph {
  char c;
  uint8_t rows[7];  // bit 4 = leftmost column
};

// A 5x7 font: digits, upper-case letters and a few signs.
constexpr Glyph kFont[] = {
    {'0', {14, 17, 19, 21, 25, 17, 14}}, {'1', {4, 12, 4, 4, 4, 4, 14}},     {'2', {14, 17, 1, 2, 4, 8, 31}},
    {'3', {31, 2, 4, 2, 1, 17, 14}},     {'4', {2, 6, 10, 18, 31, 2, 2}},    {'5', {31, 16, 30, 1, 1, 17, 14}},
    {'6', {6, 8, 16, 30, 17, 17, 14}},   {'7', {31, 1, 2, 4, 8, 8, 8}},      {'8', {14, 17, 17, 14, 17, 17, 14}},
    {'9', {14, 17, 17, 15, 1, 2, 12}},   {'A', {14, 17, 17, 31, 17, 17, 17}}, {'B', {30, 17, 17, 30, 17, 17, 30}},
    {'C', {14, 17, 16, 16, 16, 17, 14}}, {'D', {28, 18, 17, 17, 17, 18, 28}}, {'E', {31, 16, 16, 30, 16, 16, 31}},
    {'F', {31, 16, 16, 30, 16, 16, 16}}, {'G', {14, 17, 16, 23, 17, 17, 15}}, {'H', {17, 17, 17, 31, 17, 17, 17}},
    {'I', {14, 4, 4, 4, 4, 4, 14}},      {'J', {7, 2, 2, 2, 2, 18, 12}},     {'K', {17, 18, 20, 24, 20, 18, 17}},
    {'L', {16, 16, 16, 16, 16, 16, 31}}, {'M', {17, 27, 21, 21, 17, 17, 17}}, {'N', {17, 17, 25, 21, 19, 17, 17}},
    {'O', {14, 17, 17, 17, 17, 17, 14}}, {'P', {30, 17, 17, 30, 16, 16, 16}}, {'Q', {14, 17, 17, 17, 21, 18, 13}},
    {'R', {30, 17, 17, 30, 20, 18, 17}}, {'S', {15, 16, 16, 14, 1, 1, 30}},  {'T', {31, 4, 4, 4, 4, 4, 4}},
    {'U', {17, 17, 17, 17, 17, 17, 14}}, {'V', {17, 17, 17, 17, 17, 10, 4}},  {'W', {17, 17, 17, 21, 21, 21, 10}},
    {'X', {17, 17, 10, 4, 10, 17, 17}},  {'Y', {17, 17, 10, 4, 4, 4, 4}},     {'Z', {31, 1, 2, 4, 8, 16, 31}},
    {'.', {0, 0, 0, 0, 0, 12, 12}},      {'-', {0, 0, 0, 31, 0, 0, 0}},       {'(', {2, 4, 8, 8, 8, 4, 2}},
    {')', {8, 4, 2, 2, 2, 4, 8}},        {'/', {0, 1, 2, 4, 8, 16, 0}},       {',', {0, 0, 0, 0, 12, 4, 8}},
    {':', {0, 12, 12, 0, 12, 12, 0}},    {'%', {24, 25, 2, 4, 8, 19, 3}},     {'+', {0, 4, 4, 31, 4, 4, 0}},
    {'=', {0, 0, 31, 0, 31, 0, 0}},      {'_', {0, 0, 0, 0, 0, 0, 31}},
};

constexpr int kScale = 2;                  // font pixels per glyph pixel
constexpr int kAdvance = 6 * kScale;       // glyph width plus one column of space
constexpr int kLeft = 90, kRight = 30, kTop = 50, kBottom = 70;

class Canvas {
 public:
  explicit Canvas(Image& img) : img_(img) {}
  void set(int x, int y, uint32_t c) {
    if (x < 0 || y < 0 || x >= img_.width || y >= img_.height) return;
    uint8_t* p = &img_.rgb[(static_cast<size_t>(y) * static_cast<size_t>(img_.width) + static_cast<size_t>(x)) * 3];
    p[0] = static_cast<uint8_t>(c >> 16);
    p[1] = static_cast<uint8_t>(c >> 8);
    p[2] = static_cast<uint8_t>(c);
  }
  void rect(int x0, int y0, int x1, int y1, uint32_t c) {
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) set(x, y, c);
  }
  // Bresenham line, `thick` pixels wide.
  void line(int x0, int y0, int x1, int y1, uint32_t c, int thick = 1) {
    const int dx = std::abs(x1 - x0), dy = -std::abs(y1 - y0);
    const int sx = x0 < x1 ? 1 : -1, sy = y0 < y1 ? 1 : -1;
    int err = dx + dy;
    while (true) {
      rect(x0 - thick / 2, y0 - thick / 2, x0 + (thick - 1) / 2, y0 + (thick - 1) / 2, c);
      if (x0 == x1 && y0 == y1) break;
      const int e2 = 2 * err;
      if (e2 >= dy) {
        err += dy;
        x0 += sx;
      }
      if (e2 <= dx) {
        err += dx;
        y0 += sy;
      }
    }
  }
  void text(int x, int y, const std::string& s, uint32_t c, bool vertical = false) {
    for (char ch : s) {
      const char up = static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
      for (const Glyph& g : kFont) {
        if (g.c != up) continue;
        for (int r = 0; r < 7; ++r)
          for (int col = 0; col < 5; ++col)
            if ((g.rows[r] >> (4 - col)) & 1) {
              const int gx = col * kScale, gy = r * kScale;
              for (int a = 0; a < kScale; ++a)
                for (int b = 0; b < kScale; ++b) {
                  if (vertical) set(x + gy + b, y - gx - a, c);
                  else set(x + gx + a, y + gy + b, c);
                }
            }
      }
      if (vertical) y -= kAdvance;
      else x += kAdvance;
    }
  }

 private:
  Image& img_;
};

int text_width(const std::string& s) { return static_cast<int>(s.size()) * kAdvance - kScale; }

// "Nice" tick step for a range: 1, 2 or 5 x 10^k, about 6 ticks.
double nice_step(double range) {
  const double raw = range / 6;
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  const double f = raw / mag;
  return (f < 1.5 ? 1 : f < 3.5 ? 2 : f < 7.5 ? 5 : 10) * mag;
}

struct Axes {
  double x0, x1, y0, y1;  // data range, padded to ticks
  double xstep, ystep;
};

bool drawn(const PlotSpec& spec, double x, double y) {
  return std::isfinite(x) && std::isfinite(y) && (!spec.log_x || x > 0);
}

Axes axes_for(const PlotSpec& spec) {
  double xmin = INFINITY, xmax = -INFINITY, ymin = INFINITY, ymax = -INFINITY;
  for (const PlotSeries& s : spec.series)
    for (size_t i = 0; i < std::min(s.x.size(), s.y.size()); ++i) {
      if (!drawn(spec, s.x[i], s.y[i])) continue;
      xmin = std::min(xmin, s.x[i]);
      xmax = std::max(xmax, s.x[i]);
      ymin = std::min(ymin, s.y[i]);
      ymax = std::max(ymax, s.y[i]);
    }
  if (!std::isfinite(xmin)) xmin = 0, xmax = 1, ymin = 0, ymax = 1;
  if (xmax - xmin < 1e-12) xmin -= 0.5, xmax += 0.5;
  if (ymax - ymin < 1e-12) ymin -= 0.5, ymax += 0.5;
  Axes a;
  a.ystep = nice_step(ymax - ymin);
  if (spec.log_x) {
    if (!std::isfinite(xmin) || xmin <= 0) xmin = 1, xmax = 10;
    a.x0 = std::pow(10.0, std::floor(std::log10(xmin)));
    a.x1 = std::pow(10.0, std::ceil(std::log10(xmax)));
    if (a.x1 <= a.x0) a.x1 = a.x0 * 10;
    a.xstep = 0;  // ticks at 1, 2, 5 x 10^k
  } else {
    a.xstep = nice_step(xmax - xmin);
    a.x0 = std::floor(xmin / a.xstep) * a.xstep;
    a.x1 = std::ceil(xmax / a.xstep) * a.xstep;
  }
  a.y0 = std::floor(ymin / a.ystep) * a.ystep;
  a.y1 = std::ceil(ymax / a.ystep) * a.ystep;
  return a;
}

void to_pixel(const PlotSpec& spec, const Axes& a, double x, double y, int& px, int& py) {
  const int w = spec.width - kLeft - kRight, h = spec.height - kTop - kBottom;
  const double t = spec.log_x ? std::log10(x / a.x0) / std::log10(a.x1 / a.x0) : (x - a.x0) / (a.x1 - a.x0);
  px = kLeft + static_cast<int>(std::lround(t * w));
  py = kTop + h - static_cast<int>(std::lround((y - a.y0) / (a.y1 - a.y0) * h));
}

std::string tick_label(double v, double step) {
  char buf[32];
  const int decimals = std::max(0, static_cast<int>(-std::floor(std::log10(step) + 1e-9)));
  std::snprintf(buf, sizeof buf, "%.*f", decimals, std::abs(v) < step * 1e-9 ? 0.0 : v);
  return buf;
}

}  // namespace

void plot_position(const PlotSpec& spec, double x, double y, int& px, int& py) {
  to_pixel(spec, axes_for(spec), x, y, px, py);
}

Image render_plot(const PlotSpec& spec) { return render_plot(spec, nullptr); }

Image render_plot(const PlotSpec& spec, size_t* labels_left_out) {
  Image img;
  img.width = spec.width;
  img.height = spec.height;
  img.rgb.assign(static_cast<size_t>(spec.width) * static_cast<size_t>(spec.height) * 3, 0xFF);
  Canvas c(img);
  const Axes a = axes_for(spec);
  const uint32_t kInk = 0x000000, kGrid = 0xDDDDDD;
  const int right = spec.width - kRight, bottom = spec.height - kBottom;
  int px, py;
  std::vector<double> xticks;
  if (spec.log_x) {
    for (double decade = a.x0; decade <= a.x1 * (1 + 1e-9); decade *= 10)
      for (double m : {1.0, 2.0, 5.0})
        if (m * decade <= a.x1 * (1 + 1e-9)) xticks.push_back(m * decade);
  } else {
    for (double x = a.x0; x <= a.x1 + a.xstep * 1e-9; x += a.xstep) xticks.push_back(x);
  }
  for (double x : xticks) {
    to_pixel(spec, a, x, a.y0, px, py);
    c.line(px, kTop, px, bottom, kGrid);
    c.line(px, bottom, px, bottom + 5, kInk);
    const std::string label = spec.log_x ? tick_label(x, std::min(1.0, x)) : tick_label(x, a.xstep);
    c.text(px - text_width(label) / 2, bottom + 10, label, kInk);
  }
  for (double y = a.y0; y <= a.y1 + a.ystep * 1e-9; y += a.ystep) {
    to_pixel(spec, a, a.x0, y, px, py);
    c.line(kLeft, py, right, py, kGrid);
    c.line(kLeft - 5, py, kLeft, py, kInk);
    const std::string label = tick_label(y, a.ystep);
    c.text(kLeft - 10 - text_width(label), py - 7, label, kInk);
  }
  c.line(kLeft, kTop, kLeft, bottom, kInk);
  c.line(kLeft, bottom, right, bottom, kInk);
  c.text((spec.width - text_width(spec.title)) / 2, 15, spec.title, kInk);
  c.text(kLeft + (right - kLeft - text_width(spec.x_label)) / 2, spec.height - 28, spec.x_label, kInk);
  c.text(12, kTop + (bottom - kTop + text_width(spec.y_label)) / 2, spec.y_label, kInk, true);
  // What labels must not cover: the legend and every marker, then each
  // label as it is placed.
  struct Box {
    int x0, y0, x1, y1;
    bool overlaps(const Box& b) const { return x0 <= b.x1 && b.x0 <= x1 && y0 <= b.y1 && b.y0 <= y1; }
  };
  std::vector<Box> taken;
  const int legend_top = bottom - 20 * static_cast<int>(spec.series.size()) - 10;
  int legend_left = right;
  for (const PlotSeries& s : spec.series) legend_left = std::min(legend_left, right - 20 - text_width(s.label) - 30);
  taken.push_back(Box{legend_left - 4, legend_top - 4, right, bottom});
  for (const PlotSeries& s : spec.series)
    for (size_t i = 0; i < std::min(s.x.size(), s.y.size()); ++i)
      if (drawn(spec, s.x[i], s.y[i])) {
        to_pixel(spec, a, s.x[i], s.y[i], px, py);
        taken.push_back(Box{px - 4, py - 4, px + 4, py + 4});
      }
  size_t left_out = 0;
  int legend_y = legend_top;
  for (const PlotSeries& s : spec.series) {
    int prev_x = 0, prev_y = 0;
    bool have_prev = false;
    for (size_t i = 0; i < std::min(s.x.size(), s.y.size()); ++i) {
      if (!drawn(spec, s.x[i], s.y[i])) continue;
      to_pixel(spec, a, s.x[i], s.y[i], px, py);
      if (have_prev) c.line(prev_x, prev_y, px, py, s.rgb, 2);
      prev_x = px;
      prev_y = py;
      have_prev = true;
    }
    for (size_t i = 0; i < std::min(s.x.size(), s.y.size()); ++i) {
      if (!drawn(spec, s.x[i], s.y[i])) continue;
      to_pixel(spec, a, s.x[i], s.y[i], px, py);
      c.rect(px - 3, py - 3, px + 3, py + 3, s.rgb);
      if (i >= s.point_labels.size() || s.point_labels[i].empty()) continue;
      const int w = text_width(s.point_labels[i]), h = 7 * kScale;
      const int candidates[][2] = {{px + 6, py - h - 4}, {px + 6, py + 5}, {px - 6 - w, py - h - 4}, {px - 6 - w, py + 5},
                                   {px + 8, py - h / 2}, {px - 8 - w, py - h / 2}};
      bool placed = false;
      for (const auto& at : candidates) {
        const Box box{at[0] - 1, at[1] - 1, at[0] + w + 1, at[1] + h + 1};
        if (box.x0 < kLeft || box.x1 > right || box.y0 < kTop || box.y1 > bottom) continue;
        if (std::any_of(taken.begin(), taken.end(), [&](const Box& t) { return t.overlaps(box); })) continue;
        c.text(at[0], at[1], s.point_labels[i], 0x555555);
        taken.push_back(box);
        placed = true;
        break;
      }
      left_out += !placed;
    }
    const int lx = right - 20 - text_width(s.label) - 30;
    c.rect(lx, legend_y + 4, lx + 20, legend_y + 8, s.rgb);
    c.text(lx + 28, legend_y, s.label, kInk);
    legend_y += 20;
  }
  if (labels_left_out) *labels_left_out = left_out;
  return img;
}

}  // namespace stipple
