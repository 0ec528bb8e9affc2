#pragma once
//! A small CPU ray tracer on Embree 3 for pictures of tracked frames (§5 figures): one primary ray per
//! sample, per-vertex colours interpolated, two-sided Lambert shading from a key light and a headlight,
//! optional wireframe overlay. Deterministic: every pixel is computed on its own, so the image is
//! bit-identical for any thread count.
#include <array>
#include <memory>
#include <span>
#include <vector>

#include "kernels/render/camera.hpp"
#include "kernels/render/image.hpp"

namespace topotrack {

//! Triangles to render: flat arrays, optional per-vertex RGB colours in [0,1].
struct RenderMesh {
  std::vector<Vec3> positions;
  std::vector<std::array<Index, 3>> triangles;
  std::vector<float> colors;  //!< empty, or 3 per vertex
};

//! An Embree scene built once for a mesh; reuse it for several views (turntable). Move-only.
class RenderScene {
public:
  //! \throw InvalidInput on an index out of range, a non-finite position or colours of the wrong size;
  //! Error when Embree fails.
  explicit RenderScene(RenderMesh mesh);
  ~RenderScene();
  RenderScene(RenderScene&&) noexcept;
  RenderScene& operator=(RenderScene&&) noexcept;
  RenderScene(const RenderScene&) = delete;
  RenderScene& operator=(const RenderScene&) = delete;

  const RenderMesh& mesh() const;
  BoundingBox bounds() const;
  double build_seconds() const;

  struct Impl;
  const Impl& impl() const { return *impl_; }

private:
  std::unique_ptr<Impl> impl_;
};

struct RenderParams {
  int width = 800;
  int height = 800;
  int samples_per_axis = 2;                      //!< supersampling: n x n jittered-free grid per pixel
  std::array<float, 3> background = {1.0f, 1.0f, 1.0f};
  std::array<float, 3> base_color = {0.72f, 0.74f, 0.78f};  //!< when the mesh has no colours
  bool smooth_shading = true;                    //!< interpolate area-weighted vertex normals
  bool wireframe = false;
  double wire_width_px = 1.0;                    //!< line width in pixels
  std::array<float, 3> wire_color = {0.1f, 0.1f, 0.1f};
  double ambient = 0.25, key = 0.6, fill = 0.25; //!< light weights (key from upper left, fill = headlight)
  double specular = 0.15;
};

struct RenderReport {
  double build_seconds = 0;   //!< BVH build (from the scene)
  double trace_seconds = 0;   //!< rays and shading
  std::size_t rays = 0;
  double covered_pixels = 0;  //!< sum over pixels of the share of samples that hit the mesh (silhouette area)
};

//! Render `scene` seen by `camera`. \throw InvalidInput for a size outside [1, 16384] or samples outside [1, 8].
Image render(const RenderScene& scene, const Camera& camera, const RenderParams& params = {},
             RenderReport* report = nullptr);

//! Build a scene and render it in one call.
Image render(RenderMesh mesh, const Camera& camera, const RenderParams& params = {}, RenderReport* report = nullptr);

}  // namespace topotrack
