#pragma once
//! Closed test meshes built in code: tetrahedron, icosphere, torus, and a random-noise variant.
#include "kernels/mesh/surface_mesh.hpp"

namespace topotrack::test {

struct Soup {
  std::vector<Vec3> positions;
  std::vector<std::array<Index, 3>> triangles;
  SurfaceMesh mesh() const { return SurfaceMesh::from_triangles(positions, triangles); }
};

Soup tetrahedron();
//! Unit icosphere centred at `center`, `subdivisions` 4-to-1 refinements (0: icosahedron, 20 faces).
Soup icosphere(int subdivisions, double radius = 1.0, const Vec3& center = Vec3::Zero());
//! Torus about z with major radius R, minor radius r, n x m quads split into triangles.
Soup torus(int n, int m, double R = 1.0, double r = 0.35);
//! A cube surface of 12 triangles without its top two triangles (an open box).
Soup open_box();
//! Concatenate two soups (disjoint components).
Soup merge(const Soup& a, const Soup& b);
//! Move every vertex by a random vector of length <= amplitude (deterministic for a seed).
void jitter(Soup& s, double amplitude, unsigned seed);

}  // namespace topotrack::test
