#include "kernels/propagate/image_projection.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "io/error.hpp"

namespace topotrack {

std::vector<float> project_image(std::span<const Vec3> positions, const Image& image, const Camera& camera,
                                 std::span<const float> outside, std::size_t* outside_count) {
  if (image.width <= 0 || image.height <= 0 || image.rgb.size() != std::size_t(3) * image.width * image.height)
    TT_THROW(InvalidInput, "project_image: empty or inconsistent image");
  if (outside.size() != 3) TT_THROW(InvalidInput, "project_image: the outside colour needs 3 values");
  const Vec3 fwd = camera.forward(), right = camera.right(), up = camera.true_up();
  const double tan_half = std::tan(0.5 * camera.fov_y_deg * std::numbers::pi / 180);
  const double aspect = double(image.width) / image.height;
  std::vector<float> out(3 * positions.size());
  std::size_t missed = 0;
  for (std::size_t i = 0; i < positions.size(); ++i) {
    const Vec3 d = positions[i] - camera.eye;
    const double z = d.dot(fwd);
    float* dst = out.data() + 3 * i;
    // Image coordinates with pixel centres at integers + 0.5.
    const double x = z > 0 ? (d.dot(right) / (z * tan_half * aspect) + 1) * 0.5 * image.width : -1;
    const double y = z > 0 ? (1 - d.dot(up) / (z * tan_half)) * 0.5 * image.height : -1;
    if (!(z > 0) || !(x >= 0 && x <= image.width && y >= 0 && y <= image.height)) {
      std::copy(outside.begin(), outside.end(), dst);
      ++missed;
      continue;
    }
    const double fx = std::clamp(x - 0.5, 0.0, double(image.width - 1));
    const double fy = std::clamp(y - 0.5, 0.0, double(image.height - 1));
    const int x0 = int(fx), y0 = int(fy);
    const int x1 = std::min(x0 + 1, image.width - 1), y1 = std::min(y0 + 1, image.height - 1);
    const double ax = fx - x0, ay = fy - y0;
    for (int c = 0; c < 3; ++c) {
      const double top = (1 - ax) * image.pixel(x0, y0)[c] + ax * image.pixel(x1, y0)[c];
      const double bottom = (1 - ax) * image.pixel(x0, y1)[c] + ax * image.pixel(x1, y1)[c];
      dst[c] = float(((1 - ay) * top + ay * bottom) / 255.0);
    }
  }
  if (outside_count) *outside_count = missed;
  return out;
}

}  // namespace topotrack
