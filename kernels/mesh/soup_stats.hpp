#pragma once
//! Statistics of a triangle soup as read from disk (no half-edge structure needed, so it works on
//! broken input too): what `topotrack info` prints and what input validation checks.
#include "io/mesh_data.hpp"
#include "kernels/mesh/mesh_queries.hpp"

namespace topotrack {

struct SoupStats {
  std::size_t vertices = 0, triangles = 0;
  std::size_t unreferenced_vertices = 0;
  std::size_t non_finite_vertices = 0;
  std::size_t degenerate_triangles = 0;   //!< repeated index or zero area
  std::size_t edges = 0;
  std::size_t boundary_edges = 0;         //!< edges with one triangle
  std::size_t non_manifold_edges = 0;     //!< edges with more than two triangles
  std::size_t inconsistent_edges = 0;     //!< two triangles traverse the edge the same way
  std::size_t non_manifold_vertices = 0;  //!< more than one fan of triangles around the vertex
  std::size_t components = 0;             //!< connected by shared vertices
  long euler = 0;                          //!< V (referenced) - E + F
  long genus = -1;                         //!< total genus when closed and manifold, else -1
  bool closed = false;                     //!< no boundary edges
  bool manifold = false;                   //!< no non-manifold edge or vertex, consistent orientation
  BoundingBox bbox;
  Stats edge_length;
  double min_angle_deg = 180;
  double share_below_10deg = 0;
  bool closed_manifold() const { return closed && manifold && degenerate_triangles == 0; }
};

SoupStats analyze_soup(const MeshData& mesh);

}  // namespace topotrack
