#pragma once
//! 8-bit RGB images for the renderer (§5 pictures): storage, contact sheets, per-pixel comparison.
#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

namespace topotrack {

//! An RGB image, 3 bytes per pixel, rows top to bottom.
struct Image {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgb;  //!< size 3 * width * height

  Image() = default;
  Image(int w, int h, std::uint8_t fill = 0);
  std::uint8_t* pixel(int x, int y) { return rgb.data() + 3 * (std::size_t(y) * width + x); }
  const std::uint8_t* pixel(int x, int y) const { return rgb.data() + 3 * (std::size_t(y) * width + x); }
};

struct ContactSheetParams {
  int columns = 0;                            //!< <= 0: ceil(sqrt(n))
  int gap = 4;                                //!< pixels between and around the tiles
  std::uint8_t background[3] = {255, 255, 255};
};

//! Tile `images` in a grid, row by row; tiles may differ in size (each cell is as large as the largest).
//! \throw InvalidInput when `images` is empty or an image's pixel buffer has the wrong size.
Image contact_sheet(std::span<const Image> images, const ContactSheetParams& params = {});

//! Per-pixel comparison of two images of equal size. A pixel's difference is its largest channel difference.
struct CompareParams {
  int tolerance = 0;  //!< a pixel differs when its difference exceeds this
  //! Pixels of this colour in both images (e.g. the background) are left out of every statistic.
  std::optional<std::array<std::uint8_t, 3>> ignore;
};
struct ImageDifference {
  std::size_t pixels_compared = 0;
  double mean_abs = 0;        //!< mean absolute channel difference, in [0, 255]
  double rms = 0;             //!< root mean square channel difference
  int max_abs = 0;            //!< largest channel difference
  double pixel_mean = 0;      //!< mean pixel difference
  int pixel_p95 = 0;          //!< 95th percentile of the pixel differences
  double share_differing = 0; //!< fraction of the pixels compared differing by more than the tolerance
};
//! \throw InvalidInput when the sizes differ.
ImageDifference compare_images(const Image& a, const Image& b, const CompareParams& params = {});

}  // namespace topotrack
