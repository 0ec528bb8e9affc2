#pragma once
//! Conversion between the flat MeshData of io/ and SurfaceMesh.
#include "io/mesh_data.hpp"
#include "kernels/mesh/surface_mesh.hpp"

namespace topotrack {

//! Build a SurfaceMesh from flat arrays. Vertices no triangle references are dropped (they carry no
//! surface); ids are kept when present; float attributes become float vertex properties of the same
//! name and width. \throw InvalidInput as SurfaceMesh::from_triangles, plus non-finite coordinates
//! and duplicate ids. The message does not name a file: callers prefix it.
SurfaceMesh to_surface_mesh(const MeshData& data);

//! The positions of `data` as Vec3 (no check; to_surface_mesh checks them).
std::vector<Vec3> positions_of(const MeshData& data);

//! Flat arrays of the live elements of `mesh` (deleted ones skipped, vertices in handle order), with
//! ids and, when `with_properties`, every float vertex property as an attribute.
MeshData to_mesh_data(const SurfaceMesh& mesh, bool with_properties = true);

//! Positions and triangles of the live elements (the form Embree, OpenVDB and the writers take);
//! `vertex_of_index`, when given, receives the mesh vertex of each output vertex.
void extract_triangles(const SurfaceMesh& mesh, std::vector<Vec3>& positions,
                       std::vector<std::array<Index, 3>>& triangles, std::vector<Vertex>* vertex_of_index = nullptr);

}  // namespace topotrack
