#pragma once
//! Tracker state between frames, for `track --resume`: the tracked mesh at full precision (double
//! positions, connectivity, persistent ids, the id counter) and the tracker's fixed scalars. The PLY
//! output stores float positions, so resuming from it would not reproduce an uninterrupted run; the
//! checkpoint does, bit for bit.
//!
//! Format (little endian): "TTCHECK1", u32 version 2, i64 frame number, i64 frame index, f64 target edge
//! length, f64 voxel size, 3 x f64 lattice origin (not in version 1, which is still read: origin 0), u64 next id, u64 V, u64 F, V x (f64 x, f64 y, f64 z), V x u64 id,
//! F x (u32 a, u32 b, u32 c), u64 FNV-1a hash of all preceding bytes.
#include <filesystem>

#include "kernels/mesh/surface_mesh.hpp"

namespace topotrack {

struct Checkpoint {
  long frame_number = 0;   //!< the input frame number the mesh belongs to
  long frame_index = 0;    //!< its position in the input sequence
  double target_edge_length = 0;
  double voxel_size = 0;
  SurfaceMesh mesh;
  Vec3 lattice_origin = Vec3::Zero();  //!< Tracker::lattice_origin
};

//! Write atomically. \throw IoError
void write_checkpoint(const std::filesystem::path& path, const Checkpoint& c);
//! \throw IoError (missing) or InvalidInput (corrupt: bad magic, size, hash or connectivity), naming the path.
Checkpoint read_checkpoint(const std::filesystem::path& path);

}  // namespace topotrack
