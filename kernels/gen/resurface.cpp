#include "kernels/gen/resurface.hpp"

#include <chrono>

#include "kernels/sdf/marching_cubes.hpp"
#include "kernels/sdf/signed_distance.hpp"

namespace topotrack {

MeshData resurface(const MeshData& source, const ResurfaceParams& params, ResurfaceReport* report) {
  using Clock = std::chrono::steady_clock;
  std::vector<Vec3> positions(source.positions.size());
  for (std::size_t i = 0; i < positions.size(); ++i)
    positions[i] = Vec3(source.positions[i][0], source.positions[i][1], source.positions[i][2]);
  std::vector<std::array<Index, 3>> triangles(source.triangles.size());
  for (std::size_t f = 0; f < triangles.size(); ++f)
    for (int j = 0; j < 3; ++j) {
      const std::int64_t v = source.triangles[f][j];
      if (v < 0 || std::size_t(v) >= positions.size())
        TT_THROW(InvalidInput, "resurface: triangle " << f << " has vertex index " << v << " out of range");
      triangles[f][j] = Index(v);
    }
  const auto t0 = Clock::now();
  auto grid = signed_distance(positions, triangles, params.voxel_size, params.half_width_voxels);
  const auto t1 = Clock::now();
  MeshData out = marching_cubes(*grid);
  const auto t2 = Clock::now();
  if (report) {
    report->active_voxels = grid->activeVoxelCount();
    report->seconds_distance = std::chrono::duration<double>(t1 - t0).count();
    report->seconds_marching = std::chrono::duration<double>(t2 - t1).count();
  }
  return out;
}

}  // namespace topotrack
