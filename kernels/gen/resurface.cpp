#include "kernels/gen/resurface.hpp"

#include <algorithm>
#include <chrono>

#include "kernels/gen/fill_voids.hpp"
#include "kernels/mesh/mesh_convert.hpp"
#include "kernels/sdf/marching_cubes.hpp"
#include "kernels/sdf/signed_distance.hpp"

namespace topotrack {

MeshData resurface(const MeshData& source, const ResurfaceParams& params, ResurfaceReport* report) {
  using Clock = std::chrono::steady_clock;
  const std::vector<Vec3> positions = positions_of(source);
  std::vector<std::array<Index, 3>> triangles(source.triangles.size());
  for (std::size_t f = 0; f < triangles.size(); ++f)
    for (int j = 0; j < 3; ++j) {
      const std::int64_t v = source.triangles[f][j];
      if (v < 0 || std::size_t(v) >= positions.size())
        TT_THROW(InvalidInput, "resurface: triangle " << f << " has vertex index " << v << " out of range");
      triangles[f][j] = Index(v);
    }
  const auto t0 = Clock::now();
  SignedDistanceParams sdf;
  sdf.voxel_size = params.voxel_size;
  sdf.origin = params.origin;
  sdf.min_thickness_voxels = std::max(0.0, params.min_thickness_voxels);
  sdf.half_width_voxels = std::max(params.half_width_voxels, sdf.min_thickness_voxels > 0 ? 0.5 * sdf.min_thickness_voxels + 1.5 : 1.0);
  sdf.exact_sign_band_voxels = std::min(params.exact_sign_band_voxels, sdf.half_width_voxels);
  sdf.sign_method = SignMethod::kWindingNumber;
  SignedDistanceReport sdf_report;
  auto grid = signed_distance(positions, triangles, sdf, &sdf_report);
  const auto t1 = Clock::now();
  MeshData out = marching_cubes(*grid);
  const auto t2 = Clock::now();
  FillVoidsReport fill;
  if (params.fill_voids) out = fill_voids(out, &fill);
  const auto t3 = Clock::now();
  if (report) {
    report->active_voxels = sdf_report.active_voxels;
    report->signs_flipped = sdf_report.signs_flipped;
    report->thin_vertices = sdf_report.thin_vertices;
    report->seconds_distance = std::chrono::duration<double>(t1 - t0).count();
    report->seconds_marching = std::chrono::duration<double>(t2 - t1).count();
    report->voids_filled = fill.voids_filled;
    report->islands_removed = fill.islands_removed;
    report->seconds_fill = std::chrono::duration<double>(t3 - t2).count();
  }
  return out;
}

}  // namespace topotrack
