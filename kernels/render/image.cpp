#include "kernels/render/image.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "io/error.hpp"

namespace topotrack {

Image::Image(int w, int h, std::uint8_t fill) : width(w), height(h) {
  if (w < 0 || h < 0) TT_THROW(InvalidInput, "Image: bad size " << w << "x" << h);
  rgb.assign(std::size_t(3) * w * h, fill);
}

static void check(const Image& im, const char* what) {
  if (im.width < 0 || im.height < 0 || im.rgb.size() != std::size_t(3) * im.width * im.height)
    TT_THROW(InvalidInput, what << ": image of " << im.width << "x" << im.height << " has " << im.rgb.size()
                                << " bytes");
}

Image contact_sheet(std::span<const Image> images, const ContactSheetParams& params) {
  if (images.empty()) TT_THROW(InvalidInput, "contact_sheet: no images");
  int cell_w = 0, cell_h = 0;
  for (const Image& im : images) {
    check(im, "contact_sheet");
    cell_w = std::max(cell_w, im.width);
    cell_h = std::max(cell_h, im.height);
  }
  const int n = int(images.size());
  const int cols = params.columns > 0 ? std::min(params.columns, n) : int(std::ceil(std::sqrt(double(n))));
  const int rows = (n + cols - 1) / cols;
  const int gap = std::max(0, params.gap);
  Image sheet(cols * cell_w + (cols + 1) * gap, rows * cell_h + (rows + 1) * gap);
  for (std::size_t i = 0; i < sheet.rgb.size(); ++i) sheet.rgb[i] = params.background[i % 3];
  for (int k = 0; k < n; ++k) {
    const Image& im = images[k];
    const int x0 = gap + (k % cols) * (cell_w + gap) + (cell_w - im.width) / 2;
    const int y0 = gap + (k / cols) * (cell_h + gap) + (cell_h - im.height) / 2;
    for (int y = 0; y < im.height; ++y) std::copy_n(im.pixel(0, y), 3 * im.width, sheet.pixel(x0, y0 + y));
  }
  return sheet;
}

ImageDifference compare_images(const Image& a, const Image& b, int tolerance) {
  check(a, "compare_images");
  check(b, "compare_images");
  if (a.width != b.width || a.height != b.height)
    TT_THROW(InvalidInput, "compare_images: sizes differ: " << a.width << "x" << a.height << " vs " << b.width << "x"
                                                           << b.height);
  ImageDifference d;
  const std::size_t pixels = std::size_t(a.width) * a.height;
  if (pixels == 0) return d;
  double sum = 0, sum2 = 0;
  std::size_t differing = 0;
  for (std::size_t p = 0; p < pixels; ++p) {
    int worst = 0;
    for (int c = 0; c < 3; ++c) {
      const int diff = std::abs(int(a.rgb[3 * p + c]) - int(b.rgb[3 * p + c]));
      sum += diff;
      sum2 += double(diff) * diff;
      worst = std::max(worst, diff);
    }
    d.max_abs = std::max(d.max_abs, worst);
    if (worst > tolerance) ++differing;
  }
  d.mean_abs = sum / (3.0 * pixels);
  d.rms = std::sqrt(sum2 / (3.0 * pixels));
  d.share_differing = double(differing) / pixels;
  return d;
}

}  // namespace topotrack
