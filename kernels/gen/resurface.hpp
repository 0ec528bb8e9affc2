#pragma once
//! Re-meshing a closed mesh through an OpenVDB level set (signed distance, §4.3, then marching cubes):
//! same surface up to the voxel size, new connectivity. Turns a coherent sequence into tracker input.
#include "io/mesh_data.hpp"

namespace topotrack {

struct ResurfaceParams {
  double voxel_size = 0;           //!< required, > 0
  double half_width_voxels = 2.0;  //!< band of the signed distance (marching cubes only needs the sign near 0)
};

struct ResurfaceReport {
  std::size_t active_voxels = 0;
  double seconds_distance = 0, seconds_marching = 0;
};

//! \pre `source` is a closed mesh. \throw InvalidInput on a bad voxel size, non-finite coordinates or an
//! index out of range.
MeshData resurface(const MeshData& source, const ResurfaceParams& params, ResurfaceReport* report = nullptr);

}  // namespace topotrack
