#include "engine/frame_loader.hpp"

#include <openvdb/io/File.h>

#include "io/error.hpp"
#include "io/mesh_reader.hpp"
#include "kernels/mesh/mesh_convert.hpp"
#include "kernels/mesh/mesh_queries.hpp"
#include "kernels/sdf/signed_distance.hpp"

namespace topotrack {

openvdb::FloatGrid::Ptr read_level_set(const std::filesystem::path& path) {
  ensure_openvdb_initialized();
  if (!std::filesystem::exists(path)) TT_THROW(IoError, path.string() << ": no such file");
  openvdb::GridPtrVecPtr grids;
  try {
    openvdb::io::File file(path.string());
    file.open(/*delayLoad=*/false);
    grids = file.getGrids();
    file.close();
  } catch (const openvdb::Exception& e) {
    TT_THROW(InvalidInput, path.string() << ": not a readable OpenVDB file: " << e.what());
  }
  openvdb::FloatGrid::Ptr first;
  for (const auto& g : *grids) {
    auto f = openvdb::gridPtrCast<openvdb::FloatGrid>(g);
    if (!f) continue;
    if (f->getGridClass() == openvdb::GRID_LEVEL_SET) return f;
    if (!first) first = f;
  }
  if (!first) TT_THROW(InvalidInput, path.string() << ": no float grid (a level set is needed)");
  if (!first->transform().hasUniformScale())
    TT_THROW(InvalidInput, path.string() << ": grid '" << first->getName() << "' has non-uniform voxels");
  return first;
}

LoadedFrame load_frame(const std::filesystem::path& path) {
  LoadedFrame out;
  if (path.extension() == ".vdb") {
    out.grid = read_level_set(path);
    return out;
  }
  const MeshData data = read_mesh(path);
  if (data.triangles.empty()) TT_THROW(InvalidInput, path.string() << ": no triangles");
  try {
    out.mesh = to_surface_mesh(data);
    out.mesh.validate(/*require_closed=*/true);
  } catch (const Error& e) {
    TT_THROW(InvalidInput, path.string() << ": " << e.what()
                                         << " (the tracker needs closed 2-manifold surfaces; see docs/)");
  }
  return out;
}

}  // namespace topotrack
