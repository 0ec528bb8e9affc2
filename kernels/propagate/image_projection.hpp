#pragma once
//! An image projected onto a frame like a slide projector: the image source of per-vertex colours to
//! propagate (§5: "a checkerboard pattern and a lava texture", an image revealed backwards in time). The
//! camera is the renderer's (kernels/render/camera.hpp), so a projection matches a picture from that camera.
#include <span>
#include <vector>

#include "kernels/render/camera.hpp"
#include "kernels/render/image.hpp"

namespace topotrack {

//! Project `image` through `camera` (aspect = image aspect) onto the positions like a slide projector: each
//! vertex gets the bilinearly sampled colour (RGB in [0,1]) of the pixel it projects to, `outside` when it
//! projects outside the image or behind the camera. `outside_count`, when given, receives how many did.
//! \throw InvalidInput for an empty image or `outside` not of size 3.
std::vector<float> project_image(std::span<const Vec3> positions, const Image& image, const Camera& camera,
                                 std::span<const float> outside, std::size_t* outside_count = nullptr);

}  // namespace topotrack
