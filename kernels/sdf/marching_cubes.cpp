#include "kernels/sdf/marching_cubes.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <openvdb/tools/Morphology.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "io/error.hpp"

namespace topotrack {
namespace {

constexpr std::int64_t kBias = std::int64_t(1) << 19;
constexpr std::uint64_t kCentroidFlag = std::uint64_t(1) << 63;
constexpr double kClamp = 1e-3;

bool in_key_range(const openvdb::Coord& m) {
  for (int a = 0; a < 3; ++a)
    if (m[a] < -kBias || m[a] > kBias - 2) return false;
  return true;
}

std::uint64_t pack(const openvdb::Coord& o, int axis) {
  return (std::uint64_t(o.x() + kBias) << 42) | (std::uint64_t(o.y() + kBias) << 22) |
         (std::uint64_t(o.z() + kBias) << 2) | std::uint64_t(axis);
}

openvdb::Coord corner_offset(int c) { return openvdb::Coord(c & 1, (c >> 1) & 1, (c >> 2) & 1); }

// The triangles of one work unit (a VDB leaf or a run of listed cells), before global numbering.
struct Chunk {
  std::vector<std::uint64_t> corners;        // 3 per triangle: lattice edge key or kCentroidFlag | local index
  std::vector<openvdb::Vec3d> centroids;     // index space
  std::vector<std::uint64_t> keys;           // distinct lattice edge keys used, sorted
  std::vector<std::uint32_t> triangle_tags;  // per triangle, the caller's tag of its cell
  bool non_finite = false, out_of_range = false;
};

// Emit the triangles of one cell (see the header for why this triangulation makes no duplicate edge).
void process_cell(const openvdb::Coord& m, const std::array<float, 8>& v, double iso, std::uint32_t tag, Chunk& out) {
  for (float x : v)
    if (!std::isfinite(x)) {
      out.non_finite = true;
      return;
    }
  const std::uint8_t mask = inside_mask(v, iso);
  if (mask == 0 || mask == 255) return;
  if (!in_key_range(m)) {
    out.out_of_range = true;
    return;
  }
  const cube::CubePolygons& P = cube::cube_polygons(mask);
  std::array<std::uint64_t, 12> key;
  std::array<openvdb::Vec3d, 12> pos;
  for (int p = 0; p < P.count; ++p) {
    const auto poly = P.polygon(p);
    const int n = int(poly.size());
    for (int i = 0; i < n; ++i) {
      const int e = poly[i];
      const LatticeEdge le = cell_edge(m, e);
      key[i] = pack(le.origin, le.axis);
      pos[i] = edge_point_index(le, v[cube::edge_corner(e, 0)], v[cube::edge_corner(e, 1)], iso);
    }
    auto tri = [&](std::uint64_t a, std::uint64_t b, std::uint64_t c) {
      out.corners.push_back(a);
      out.corners.push_back(b);
      out.corners.push_back(c);
    };
    int diagonal = -1;  // 0: corners 0-2, 1: corners 1-3
    if (n == 4) {
      const bool d02 = (P.quad_diagonals >> p) & 1, d13 = (P.quad_diagonals >> (p + 4)) & 1;
      if (d02 && d13) diagonal = (pos[0] - pos[2]).lengthSqr() <= (pos[1] - pos[3]).lengthSqr() ? 0 : 1;
      else if (d02) diagonal = 0;
      else if (d13) diagonal = 1;
    }
    if (n == 3) {
      tri(key[0], key[1], key[2]);
    } else if (diagonal == 0) {
      tri(key[0], key[1], key[2]);
      tri(key[0], key[2], key[3]);
    } else if (diagonal == 1) {
      tri(key[1], key[2], key[3]);
      tri(key[1], key[3], key[0]);
    } else {
      openvdb::Vec3d c(0.0);
      for (int i = 0; i < n; ++i) c += pos[i];
      c /= double(n);
      const std::uint64_t ck = kCentroidFlag | out.centroids.size();
      out.centroids.push_back(c);
      for (int i = 0; i < n; ++i) tri(ck, key[i], key[(i + 1) % n]);
    }
    for (int i = 0; i < n; ++i) out.keys.push_back(key[i]);
  }
  out.triangle_tags.resize(out.corners.size() / 3, tag);
}

void finish_chunk(Chunk& c) {
  std::sort(c.keys.begin(), c.keys.end());
  c.keys.erase(std::unique(c.keys.begin(), c.keys.end()), c.keys.end());
}

// Number the vertices and triangles of all chunks (in chunk order) into one mesh.
CellMesh assemble(const openvdb::FloatGrid& grid, std::vector<Chunk>& chunks, double iso, bool with_tags) {
  for (const Chunk& c : chunks) {
    if (c.non_finite) TT_THROW(InvalidInput, "marching cubes: grid '" << grid.getName() << "' has a non-finite value");
    if (c.out_of_range)
      TT_THROW(InvalidInput, "marching cubes: grid '" << grid.getName() << "' has voxels beyond +-" << kBias);
  }
  const std::size_t n_chunks = chunks.size();
  std::vector<std::size_t> key_off(n_chunks + 1, 0), cen_off(n_chunks + 1, 0), tri_off(n_chunks + 1, 0);
  for (std::size_t i = 0; i < n_chunks; ++i) {
    key_off[i + 1] = key_off[i] + chunks[i].keys.size();
    cen_off[i + 1] = cen_off[i] + chunks[i].centroids.size();
    tri_off[i + 1] = tri_off[i] + chunks[i].corners.size() / 3;
  }
  std::vector<std::uint64_t> keys(key_off[n_chunks]);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n_chunks), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i)
      std::copy(chunks[i].keys.begin(), chunks[i].keys.end(), keys.begin() + std::ptrdiff_t(key_off[i]));
  });
  tbb::parallel_sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  const std::size_t n_edge_vertices = keys.size();

  CellMesh out;
  MeshData& mesh = out.mesh;
  const openvdb::math::Transform& xform = grid.transform();
  mesh.positions.resize(n_edge_vertices + cen_off[n_chunks]);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n_edge_vertices, 4096),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      auto acc = grid.getConstAccessor();
                      for (std::size_t i = r.begin(); i != r.end(); ++i) {
                        const LatticeEdge e = lattice_edge_from_key(keys[i]);
                        openvdb::Coord b = e.origin;
                        b[e.axis] += 1;
                        const auto p = xform.indexToWorld(
                            edge_point_index(e, acc.getValue(e.origin), acc.getValue(b), iso));
                        mesh.positions[i] = {p.x(), p.y(), p.z()};
                      }
                    });
  mesh.triangles.resize(tri_off[n_chunks]);
  if (with_tags) out.triangle_cells.resize(tri_off[n_chunks]);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n_chunks), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      const Chunk& c = chunks[i];
      for (std::size_t k = 0; k < c.centroids.size(); ++k) {
        const auto p = xform.indexToWorld(c.centroids[k]);
        mesh.positions[n_edge_vertices + cen_off[i] + k] = {p.x(), p.y(), p.z()};
      }
      const std::size_t nt = c.corners.size() / 3;
      for (std::size_t t = 0; t < nt; ++t) {
        auto& tri = mesh.triangles[tri_off[i] + t];
        for (int j = 0; j < 3; ++j) {
          const std::uint64_t k = c.corners[3 * t + j];
          if (k & kCentroidFlag)
            tri[j] = std::int64_t(n_edge_vertices + cen_off[i] + (k & ~kCentroidFlag));
          else
            tri[j] = std::lower_bound(keys.begin(), keys.end(), k) - keys.begin();
        }
        if (with_tags) out.triangle_cells[tri_off[i] + t] = c.triangle_tags[t];
      }
    }
  });
  if (with_tags) {
    out.vertex_keys = std::move(keys);
    out.vertex_keys.resize(mesh.positions.size(), CellMesh::kCentroidVertex);
  }
  return out;
}

}  // namespace

std::uint64_t lattice_edge_key(const LatticeEdge& e) {
  if (!in_key_range(e.origin) || e.axis < 0 || e.axis > 2)
    TT_THROW(InvalidInput, "lattice edge " << e.origin << " axis " << e.axis << " is out of the key range");
  return pack(e.origin, e.axis);
}

LatticeEdge lattice_edge_from_key(std::uint64_t key) {
  constexpr std::uint64_t m20 = (std::uint64_t(1) << 20) - 1;
  LatticeEdge e;
  e.axis = int(key & 3);
  e.origin = openvdb::Coord(int(std::int64_t((key >> 42) & m20) - kBias), int(std::int64_t((key >> 22) & m20) - kBias),
                            int(std::int64_t((key >> 2) & m20) - kBias));
  return e;
}

LatticeEdge cell_edge(const openvdb::Coord& cell, int cube_edge) {
  return {cell + corner_offset(cube::edge_corner(cube_edge, 0)), cube::edge_axis(cube_edge)};
}

std::array<float, 8> cell_values(const openvdb::FloatGrid& grid, const openvdb::Coord& cell) {
  auto acc = grid.getConstAccessor();
  std::array<float, 8> v;
  for (int c = 0; c < 8; ++c) v[c] = acc.getValue(cell + corner_offset(c));
  return v;
}

std::uint8_t inside_mask(const std::array<float, 8>& values, double iso) {
  std::uint8_t m = 0;
  for (int c = 0; c < 8; ++c)
    if (double(values[c]) < iso) m |= std::uint8_t(1u << c);
  return m;
}

openvdb::Vec3d edge_point_index(const LatticeEdge& e, double v0, double v1, double iso) {
  double t = (iso - v0) / (v1 - v0);
  t = std::clamp(std::isfinite(t) ? t : 0.5, kClamp, 1.0 - kClamp);
  openvdb::Vec3d p(e.origin.x(), e.origin.y(), e.origin.z());
  p[e.axis] += t;
  return p;
}

MeshData marching_cubes(const openvdb::FloatGrid& grid, double iso) {
  // Cells with at least one active corner: the active topology dilated towards -x, -y, -z (a full
  // 26-neighbour dilation is a cheap superset; cells without a crossing emit nothing).
  openvdb::MaskTree cells(grid.tree(), false, openvdb::TopologyCopy());
  openvdb::tools::dilateActiveValues(cells, 1, openvdb::tools::NN_FACE_EDGE_VERTEX, openvdb::tools::IGNORE_TILES);
  std::vector<const openvdb::MaskTree::LeafNodeType*> leaves;
  cells.getNodes(leaves);
  std::vector<Chunk> chunks(leaves.size());
  const openvdb::FloatTree& tree = grid.tree();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaves.size()), [&](const tbb::blocked_range<std::size_t>& r) {
    auto acc = grid.getConstAccessor();
    std::array<float, 8> v;
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      const auto* mleaf = leaves[i];
      const auto* leaf = tree.probeConstLeaf(mleaf->origin());
      for (auto it = mleaf->cbeginValueOn(); it; ++it) {
        const openvdb::Coord m = it.getCoord();
        const openvdb::Coord local = m - mleaf->origin();
        if (leaf && local.x() < 7 && local.y() < 7 && local.z() < 7) {
          const auto& buf = leaf->buffer();
          const openvdb::Index o = leaf->coordToOffset(m);
          // Offsets in a leaf: x stride 64, y stride 8, z stride 1.
          for (int c = 0; c < 8; ++c) v[c] = buf[o + (c & 1) * 64 + ((c >> 1) & 1) * 8 + ((c >> 2) & 1)];
        } else {
          for (int c = 0; c < 8; ++c) v[c] = acc.getValue(m + corner_offset(c));
        }
        process_cell(m, v, iso, 0, chunks[i]);
      }
      finish_chunk(chunks[i]);
    }
  });
  return std::move(assemble(grid, chunks, iso, false).mesh);
}

CellMesh marching_cubes_cells(const openvdb::FloatGrid& grid, std::span<const openvdb::Coord> cells, double iso) {
  constexpr std::size_t kChunk = 256;
  std::vector<Chunk> chunks((cells.size() + kChunk - 1) / kChunk);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, chunks.size()), [&](const tbb::blocked_range<std::size_t>& r) {
    auto acc = grid.getConstAccessor();
    std::array<float, 8> v;
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      const std::size_t end = std::min(cells.size(), (i + 1) * kChunk);
      for (std::size_t k = i * kChunk; k < end; ++k) {
        for (int c = 0; c < 8; ++c) v[c] = acc.getValue(cells[k] + corner_offset(c));
        process_cell(cells[k], v, iso, std::uint32_t(k), chunks[i]);
      }
      finish_chunk(chunks[i]);
    }
  });
  return assemble(grid, chunks, iso, true);
}

}  // namespace topotrack
