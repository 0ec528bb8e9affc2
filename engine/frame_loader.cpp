#include "engine/frame_loader.hpp"

#include <openvdb/io/File.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "io/error.hpp"
#include "io/mesh_reader.hpp"
#include "kernels/mesh/mesh_convert.hpp"
#include "kernels/mesh/mesh_queries.hpp"
#include "kernels/sdf/close_holes.hpp"
#include "kernels/sdf/signed_distance.hpp"

namespace topotrack {
namespace {

using DirectedEdge = std::pair<std::int64_t, std::int64_t>;

//! Every triangle's three directed edges, sorted (for binary search of the reverse edge).
std::vector<DirectedEdge> directed_edges(const MeshData& data) {
  std::vector<DirectedEdge> e;
  e.reserve(3 * data.triangles.size());
  for (const auto& t : data.triangles)
    for (int k = 0; k < 3; ++k) e.emplace_back(t[k], t[(k + 1) % 3]);
  std::sort(e.begin(), e.end());
  return e;
}

bool contains(const std::vector<DirectedEdge>& sorted, const DirectedEdge& e) {
  return std::binary_search(sorted.begin(), sorted.end(), e);
}

Vec3 position(const MeshData& data, std::int64_t i) {
  const auto& p = data.positions[std::size_t(i)];
  return {p[0], p[1], p[2]};
}

//! Bounding-box diagonal of a loop's vertices: the size of the hole.
double loop_extent(const MeshData& data, const std::vector<std::int64_t>& loop) {
  Vec3 lo = position(data, loop.front()), hi = lo;
  for (auto i : loop) {
    lo = lo.cwiseMin(position(data, i));
    hi = hi.cwiseMax(position(data, i));
  }
  return (hi - lo).norm();
}

std::string holes_summary(const MeshData& data, const std::vector<std::vector<std::int64_t>>& loops) {
  std::size_t edges = 0, largest = 0;
  double extent = 0;
  for (std::size_t l = 0; l < loops.size(); ++l) {
    edges += loops[l].size();
    const double x = loop_extent(data, loops[l]);
    if (x > extent) {
      extent = x;
      largest = l;
    }
  }
  std::ostringstream os;
  os << edges << " boundary edges in " << loops.size() << (loops.size() == 1 ? " hole" : " holes")
     << " (largest: " << loops[largest].size() << " edges, " << extent << " across)";
  return os.str();
}

}  // namespace

double soup_mean_edge_length(const MeshData& data) {
  const auto edges = directed_edges(data);
  double sum = 0;
  std::size_t n = 0;
  for (const auto& [a, b] : edges) {
    if (a > b && contains(edges, {b, a})) continue;  // an interior edge counts once
    sum += (position(data, a) - position(data, b)).norm();
    ++n;
  }
  return n ? sum / double(n) : 0.0;
}

std::vector<std::vector<std::int64_t>> boundary_loops(const MeshData& data) {
  std::vector<std::array<Index, 3>> triangles;
  triangles.reserve(data.triangles.size());
  for (const auto& t : data.triangles) {
    for (auto v : t)
      if (v < 0 || std::size_t(v) >= data.positions.size())
        TT_THROW(InvalidInput, "boundary loops: vertex index " << v << " out of range");
    triangles.push_back({Index(t[0]), Index(t[1]), Index(t[2])});
  }
  std::vector<std::vector<std::int64_t>> loops;
  for (const auto& loop : boundary_loops(std::span<const std::array<Index, 3>>(triangles)))
    loops.emplace_back(loop.begin(), loop.end());
  return loops;
}

SurfaceMesh close_holes(const MeshData& data, const FrameLoadParams& params, const std::string& name,
                        FrameLoadReport* report) {
  if (data.triangles.empty()) TT_THROW(InvalidInput, name << ": no triangles");
  const double h = params.voxel_size > 0 ? params.voxel_size : soup_mean_edge_length(data);
  if (!(h > 0) || !std::isfinite(h)) TT_THROW(InvalidInput, name << ": no edge length to close holes at");
  const auto loops = boundary_loops(data);
  for (const auto& loop : loops) {
    const double extent = loop_extent(data, loop);
    if (extent > params.max_hole_voxels * h)
      TT_THROW(InvalidInput, name << ": a hole of " << loop.size() << " boundary edges is " << extent
                                  << " across, larger than --close-holes closes (" << params.max_hole_voxels
                                  << " voxels of " << h << "); " << holes_summary(data, loops));
  }

  // The geometry (caps, level set, marching cubes) is kernels/sdf/close_holes.hpp.
  std::vector<Vec3> positions;
  positions.reserve(data.positions.size());
  for (std::size_t i = 0; i < data.positions.size(); ++i) positions.push_back(position(data, std::int64_t(i)));
  std::vector<std::array<Index, 3>> triangles;
  triangles.reserve(data.triangles.size());
  for (const auto& t : data.triangles) triangles.push_back({Index(t[0]), Index(t[1]), Index(t[2])});
  CloseHolesParams cp;
  cp.voxel_size = h;
  cp.max_hole_voxels = params.max_hole_voxels;
  CloseHolesReport cr;
  MeshData closed;
  try {
    closed = close_holes(positions, triangles, cp, &cr);
  } catch (const InvalidInput& e) {
    TT_THROW(InvalidInput, name << ": " << e.what());
  }
  FrameLoadReport rep;
  rep.voxel_size = h;
  rep.holes_closed = cr.holes_closed;
  rep.hole_boundary_edges = cr.hole_boundary_edges;
  rep.largest_hole = cr.largest_hole;
  SurfaceMesh mesh = to_surface_mesh(closed);
  mesh.validate(/*require_closed=*/true);
  if (rep.holes_closed > 0) {
    std::ostringstream os;
    os << "closed " << rep.holes_closed << (rep.holes_closed == 1 ? " hole" : " holes") << " ("
       << rep.hole_boundary_edges << " boundary edges, largest " << rep.largest_hole
       << " across) through the level set at voxel size " << h << ": " << data.positions.size() << " -> "
       << mesh.n_vertices() << " vertices";
    rep.warnings.push_back(os.str());
  }
  if (report) *report = std::move(rep);
  return mesh;
}

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
  // The first level set, else the first float grid; either must have cubic voxels.
  openvdb::FloatGrid::Ptr grid;
  for (const auto& g : *grids) {
    auto f = openvdb::gridPtrCast<openvdb::FloatGrid>(g);
    if (!f) continue;
    if (!grid) grid = f;
    if (f->getGridClass() == openvdb::GRID_LEVEL_SET) {
      grid = f;
      break;
    }
  }
  if (!grid) TT_THROW(InvalidInput, path.string() << ": no float grid (a level set is needed)");
  if (!grid->transform().hasUniformScale())
    TT_THROW(InvalidInput, path.string() << ": grid '" << grid->getName() << "' has non-uniform voxels");
  return grid;
}

LoadedFrame load_frame(const std::filesystem::path& path, const FrameLoadParams& params) {
  LoadedFrame out;
  if (path.extension() == ".vdb") {
    out.grid = read_level_set(path);
    return out;
  }
  const MeshData data = read_mesh(path);
  if (data.triangles.empty()) TT_THROW(InvalidInput, path.string() << ": no triangles");
  // A closed 2-manifold, the usual frame, passes the check straight away; only a mesh that fails it is
  // searched for holes (boundary_loops sorts all directed edges: at 100k vertices as long as building the
  // mesh), so that an open one is still reported, or closed, as such.
  std::string fault;
  try {
    out.mesh = to_surface_mesh(data);
    out.mesh.validate(/*require_closed=*/true);
    return out;
  } catch (const Error& e) {
    fault = e.what();
  }
  out.mesh = SurfaceMesh();
  const auto loops = boundary_loops(data);
  if (!loops.empty()) {
    if (params.close_holes) {
      out.mesh = close_holes(data, params, path.string(), &out.report);
      return out;
    }
    TT_THROW(InvalidInput, path.string() << ": the surface is open: " << holes_summary(data, loops)
                                         << "; the tracker needs closed 2-manifold surfaces (--close-holes closes "
                                            "holes up to "
                                         << params.max_hole_voxels << " voxels across; see docs/robustness.md)");
  }
  TT_THROW(InvalidInput, path.string() << ": " << fault
                                       << " (the tracker needs closed 2-manifold surfaces; see docs/robustness.md)");
}

}  // namespace topotrack
