#pragma once
//! Line charts as PNG-ready images (issue 8: drift, resampling and seconds per stage over frames), drawn
//! by hand: a few hundred pixels of lines and a 5x7 bitmap font do not justify a plotting dependency.
#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "kernels/render/image.hpp"

namespace topotrack {

struct PlotSeries {
  std::string name;
  std::vector<double> x, y;  //!< equal sizes; non-finite points are skipped
  std::array<std::uint8_t, 3> color{31, 119, 180};
};

struct PlotParams {
  int width = 800, height = 420;
  std::string title, x_label, y_label;
  bool y_from_zero = true;  //!< the y axis starts at 0 (when all values are >= 0)
};

//! A line chart of the series with axes, ticks, labels and a legend.
//! \throw InvalidInput when a series has x and y of different sizes or the image is smaller than 200x120.
Image line_plot(std::span<const PlotSeries> series, const PlotParams& params = {});

//! Draw `text` (ASCII; lower case drawn as upper case, unknown characters as blanks) with its top-left
//! corner at (x, y), `scale` pixels per font pixel.
void draw_text(Image& image, int x, int y, const std::string& text, std::array<std::uint8_t, 3> color, int scale = 1);

//! A distinct colour for series i (a fixed palette).
std::array<std::uint8_t, 3> series_color(std::size_t i);

}  // namespace topotrack
