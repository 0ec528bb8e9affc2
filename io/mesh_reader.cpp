#include "io/mesh_reader.hpp"

#include <algorithm>
#include <cctype>

#include "io/error.hpp"
#include "io/obj_reader.hpp"
#include "io/ply_reader.hpp"

namespace topotrack {

MeshData read_mesh(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  if (ext == ".ply") return read_ply(path);
  if (ext == ".obj") return read_obj(path);
  TT_THROW(InvalidInput, path.string() << ": unknown mesh format '" << ext << "' (expected .obj or .ply)");
}

}  // namespace topotrack
