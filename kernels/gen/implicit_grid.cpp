#include "kernels/gen/implicit_grid.hpp"

#include <cmath>
#include <memory>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "kernels/sdf/marching_cubes.hpp"
#include "kernels/sdf/signed_distance.hpp"

namespace topotrack {

openvdb::FloatGrid::Ptr sample_implicit(const ImplicitFunction& f, const BoundingBox& box, double voxel_size,
                                        double lipschitz) {
  ensure_openvdb_initialized();
  auto xform = voxel_transform(voxel_size);
  if (!(lipschitz > 0) || !std::isfinite(lipschitz))
    TT_THROW(InvalidInput, "sample_implicit: Lipschitz bound must be positive, got " << lipschitz);
  if (box.empty() || !box.min.allFinite() || !box.max.allFinite())
    TT_THROW(InvalidInput, "sample_implicit: empty or non-finite box");
  using LeafT = openvdb::FloatTree::LeafNodeType;
  // Blocks are VDB leaves (8^3 voxels, origins multiples of 8) covering the box plus one voxel.
  for (int a = 0; a < 3; ++a)
    if (std::max(std::abs(box.min[a]), std::abs(box.max[a])) / voxel_size > double(1 << 28))
      TT_THROW(InvalidInput, "sample_implicit: the box is too large for voxel size " << voxel_size);
  openvdb::Coord lo, hi;
  for (int a = 0; a < 3; ++a) {
    lo[a] = (int(std::floor(box.min[a] / voxel_size)) - 1) & ~7;
    hi[a] = (int(std::ceil(box.max[a] / voxel_size)) + 1) & ~7;
  }
  const std::int64_t nx = (hi.x() - lo.x()) / 8 + 1, ny = (hi.y() - lo.y()) / 8 + 1, nz = (hi.z() - lo.z()) / 8 + 1;
  if (nx * ny * nz > (std::int64_t(1) << 30))
    TT_THROW(InvalidInput, "sample_implicit: " << nx * ny * nz << " blocks is too many (voxel size " << voxel_size << ")");
  const std::size_t n_blocks = std::size_t(nx * ny * nz);
  // The cells with their minimum corner in a block reach one voxel beyond it: samples origin .. origin + 8.
  const double reach = lipschitz * 4.0 * std::sqrt(3.0) * voxel_size * (1.0 + 1e-9);
  const float background = float(reach);
  std::vector<std::unique_ptr<LeafT>> leaves(n_blocks);
  std::vector<std::int8_t> inside(n_blocks, 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n_blocks, 16), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t b = r.begin(); b != r.end(); ++b) {
      const openvdb::Coord origin(lo.x() + 8 * int(b / std::size_t(ny * nz)), lo.y() + 8 * int((b / std::size_t(nz)) % ny),
                                  lo.z() + 8 * int(b % std::size_t(nz)));
      const Vec3 centre = (Vec3(origin.x(), origin.y(), origin.z()) + Vec3::Constant(4.0)) * voxel_size;
      const double fc = f(centre);
      if (std::abs(fc) > reach) {
        inside[b] = fc < 0;
        continue;
      }
      auto leaf = std::make_unique<LeafT>(origin, background, true);
      for (openvdb::Index i = 0; i < LeafT::SIZE; ++i) {
        const openvdb::Coord c = leaf->offsetToGlobalCoord(i);
        leaf->setValueOnly(i, float(f(Vec3(c.x(), c.y(), c.z()) * voxel_size)));
      }
      leaves[b] = std::move(leaf);
    }
  });
  auto grid = openvdb::FloatGrid::create(background);
  grid->setTransform(xform);
  grid->setGridClass(openvdb::GRID_LEVEL_SET);
  auto& tree = grid->tree();
  for (std::size_t b = 0; b < n_blocks; ++b) {
    if (leaves[b])
      tree.addLeaf(leaves[b].release());
    else if (inside[b]) {
      const openvdb::Coord origin(lo.x() + 8 * int(b / std::size_t(ny * nz)), lo.y() + 8 * int((b / std::size_t(nz)) % ny),
                                  lo.z() + 8 * int(b % std::size_t(nz)));
      tree.addTile(1, origin, -background, false);
    }
  }
  return grid;
}

MeshData mesh_implicit(const ImplicitFunction& f, const BoundingBox& box, double voxel_size, double lipschitz) {
  return marching_cubes(*sample_implicit(f, box, voxel_size, lipschitz));
}

}  // namespace topotrack
