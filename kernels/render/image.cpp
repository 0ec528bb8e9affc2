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

ImageDifference compare_images(const Image& a, const Image& b, const CompareParams& params) {
  check(a, "compare_images");
  check(b, "compare_images");
  if (a.width != b.width || a.height != b.height)
    TT_THROW(InvalidInput, "compare_images: sizes differ: " << a.width << "x" << a.height << " vs " << b.width << "x"
                                                           << b.height);
  ImageDifference d;
  const std::size_t pixels = std::size_t(a.width) * a.height;
  auto ignored = [&](const std::uint8_t* p) {
    return params.ignore && p[0] == (*params.ignore)[0] && p[1] == (*params.ignore)[1] && p[2] == (*params.ignore)[2];
  };
  double sum = 0, sum2 = 0;
  std::size_t differing = 0;
  std::array<std::size_t, 256> histogram{};  // of the pixel differences
  for (std::size_t p = 0; p < pixels; ++p) {
    const std::uint8_t* pa = a.rgb.data() + 3 * p;
    const std::uint8_t* pb = b.rgb.data() + 3 * p;
    if (ignored(pa) && ignored(pb)) continue;
    int worst = 0;
    for (int c = 0; c < 3; ++c) {
      const int diff = std::abs(int(pa[c]) - int(pb[c]));
      sum += diff;
      sum2 += double(diff) * diff;
      worst = std::max(worst, diff);
    }
    ++histogram[worst];
    ++d.pixels_compared;
    if (worst > params.tolerance) ++differing;
  }
  const std::size_t n = d.pixels_compared;
  if (n == 0) return d;
  d.mean_abs = sum / (3.0 * n);
  d.rms = std::sqrt(sum2 / (3.0 * n));
  d.share_differing = double(differing) / n;
  std::size_t seen = 0, weighted = 0;
  bool p95_set = false;
  for (int v = 0; v < 256; ++v) {
    if (histogram[v] == 0) continue;
    seen += histogram[v];
    weighted += histogram[v] * std::size_t(v);
    d.max_abs = v;
    if (!p95_set && 20 * seen >= 19 * n) {
      d.pixel_p95 = v;
      p95_set = true;
    }
  }
  d.pixel_mean = double(weighted) / n;
  return d;
}

}  // namespace topotrack
