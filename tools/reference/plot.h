// stipple host — line charts rendered to an RGB image, for sweeps that a
// person would rather look at than read (e.g. `stipple levels --plot`).
//
// Linear axes with "nice" ticks (1, 2, 5 x 10^k) — or a logarithmic x axis,
// ticked at 1, 2 and 5 of each decade — a light grid, one polyline with
// square markers per series, a legend, a title and axis labels drawn
// with a built-in 5x7 bitmap font (upper-case letters, digits and . - ( ) / ,
// : % + = _; lower case is drawn upper case). A point's label goes beside
// its marker where it overlaps no label, marker or the legend already
// placed (right, then left, above or below), and is left out where none is
// free: crowded points keep readable labels. Deterministic: the same spec
// gives the same pixels.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "platform/image.h"

namespace stipple {

struct PlotSeries {
  std::string label;
  std::vector<double> x, y;
  uint32_t rgb = 0x1f77b4;  // 0xRRGGBB
  std::vector<std::string> point_labels;  // optional, drawn beside each marker
};

struct PlotSpec {
  std::string title, x_label, y_label;
  std::vector<PlotSeries> series;
  int width = 900, height = 560;
  bool log_x = false;  // logarithmic x axis (points with x <= 0 are not drawn)
};

Image render_plot(const PlotSpec& spec);
// The same, counting the point labels left out for want of room.
Image render_plot(const PlotSpec& spec, size_t* labels_left_out);

// Pixel position of data point (x, y) in the image `render_plot` makes for
// `spec` (for tests and annotations).
void plot_position(const PlotSpec& spec, double x, double y, int& px, int& py);

}  // namespace stipple
