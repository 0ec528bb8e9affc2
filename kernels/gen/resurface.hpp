#pragma once
//! Re-meshing a closed mesh through an OpenVDB level set (signed distance, §4.3, then marching cubes):
//! same surface up to the voxel size, new connectivity. Turns a coherent sequence into tracker input.
//!
//! Real frames need two things plain meshToVolume + marching cubes lacks (measured on /work/shared/data at
//! 128 voxels across): exact signs next to the surface, from the winding number because the frames cross
//! themselves (OpenVDB's sign left single wrong voxels: samba.0001 came out with 2 components, samba.0021
//! with genus 2); and a minimum thickness, because the elephant's ears are sheets 0.1 voxel thick, which
//! marching cubes turned into a lace and 96 one-voxel specks (97 components in frame 1). 1.75 voxels is
//! enough to keep the ears in one piece and moves the surface less than a voxel.
//! A third, our choice: enclosed voids are filled (fill_voids.hpp), because the thickening and the winding
//! number's union seal thin gaps of a self-intersecting capture into inner cavities (pcow frame 81: 2),
//! and a captured body has none.
#include "io/mesh_data.hpp"
#include "kernels/mesh/surface_mesh.hpp"

namespace topotrack {

struct ResurfaceParams {
  double voxel_size = 0;           //!< required, > 0
  double half_width_voxels = 2.0;  //!< band of the signed distance; raised to what the thickening needs
  //! Voxels nearer the surface than this get the winding number's sign (exact_sign.hpp); <= 0: OpenVDB's.
  double exact_sign_band_voxels = 3.0;
  //! Parts thinner than this many voxels are thickened to it (kernels/sdf/thicken.hpp); 0: as they are.
  double min_thickness_voxels = 1.75;
  //! Remove the components enclosed by others (cavity walls and what floats in them), fill_voids.hpp.
  bool fill_voids = true;
  Vec3 origin = Vec3::Zero();  //!< the grid's node (0, 0, 0) (SignedDistanceParams::origin)
};

struct ResurfaceReport {
  std::size_t active_voxels = 0;
  std::size_t signs_flipped = 0;     //!< voxels whose OpenVDB sign was wrong
  std::size_t thin_vertices = 0;     //!< source vertices on parts thinner than min_thickness_voxels
  std::size_t voids_filled = 0;      //!< enclosed cavities removed (FillVoidsReport)
  std::size_t islands_removed = 0;   //!< components inside a cavity removed with it
  double seconds_distance = 0, seconds_marching = 0, seconds_fill = 0;
};

//! \pre `source` is a closed mesh. \throw InvalidInput on a bad voxel size, non-finite coordinates or an
//! index out of range.
MeshData resurface(const MeshData& source, const ResurfaceParams& params, ResurfaceReport* report = nullptr);

}  // namespace topotrack
