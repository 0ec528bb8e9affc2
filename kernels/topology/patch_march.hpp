#pragma once
//! The breadth-first march of §4.4 over a patch of vertices: starting from the vertices around the patch,
//! each patch vertex, in breadth-first order, takes the average of its already-visited neighbours.
#include <cstdint>
#include <vector>

#include "kernels/mesh/surface_mesh.hpp"

namespace topotrack::topology {

//! One patch: its vertices in march order, the rule of each (sources: boundary vertices or vertices
//! earlier in `order`), and its boundary (the non-patch vertices adjacent to it, sorted).
struct MarchedPatch {
  std::vector<Index> order;               //!< vertex indices, march order (vertices without rule last)
  std::vector<std::uint32_t> rule_begin;  //!< rule of order[i]: terms [rule_begin[i], rule_begin[i+1])
  std::vector<std::pair<Index, double>> terms;
  std::size_t ruled = 0;                  //!< order[0, ruled) have rules; the rest has no path to a boundary
  std::vector<Index> boundary;
};

//! Split the vertices with in_patch[v] into connected patches (adjacency given in CSR form: neighbours of
//! v are adj[adj_begin[v], adj_begin[v+1])) and march each. Patches come in order of their smallest vertex;
//! deterministic.
std::vector<MarchedPatch> march_patches(const std::vector<std::uint8_t>& in_patch,
                                        const std::vector<std::uint32_t>& adj_begin, const std::vector<Index>& adj);

//! CSR adjacency of the live vertices of a mesh (neighbours in one-ring order).
void mesh_adjacency(const SurfaceMesh& mesh, std::vector<std::uint32_t>& adj_begin, std::vector<Index>& adj);
//! The same with rows only for the vertices with rows[v] (the others get an empty row): all that
//! march_patches reads when rows is its in_patch, at a cost proportional to the patches, not the mesh.
//! \throw InvalidInput when rows does not have one flag per vertex (vertices_size()).
void mesh_adjacency(const SurfaceMesh& mesh, const std::vector<std::uint8_t>& rows, std::vector<std::uint32_t>& adj_begin,
                    std::vector<Index>& adj);

}  // namespace topotrack::topology
