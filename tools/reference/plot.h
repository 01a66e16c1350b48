// stipple host — line charts rendered to an RGB image, for sweeps that a
// person would rather look at than read (e.g. `stipple levels --plot`).
//
// Linear axes with "nice" ticks (1, 2, 5 x 10^k), a light grid, one polyline
// with square markers per series, a legend, a title and axis labels drawn
// with a built-in 5x7 bitmap font (upper-case letters, digits and . - ( ) / ,
// : % + = _; lower case is drawn upper case). Deterministic: the same spec
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
};

Image render_plot(const PlotSpec& spec);

// Pixel position of data point (x, y) in the image `render_plot` makes for
// `spec` (for tests and annotations).
void plot_position(const PlotSpec& spec, double x, double y, int& px, int& py);

}  // namespace stipple
