// Links the installed engine and checks a closed mesh round trip through the public headers.
#include <cstdio>

#include "kernels/mesh/mesh_queries.hpp"
#include "kernels/mesh/surface_mesh.hpp"

int main() {
  using namespace topotrack;
  const std::vector<Vec3> p = {{1, 1, 1}, {1, -1, -1}, {-1, 1, -1}, {-1, -1, 1}};
  const std::vector<std::array<Index, 3>> t = {{0, 1, 2}, {0, 3, 1}, {0, 2, 3}, {1, 3, 2}};
  SurfaceMesh m = SurfaceMesh::from_triangles(p, t);
  m.validate();
  const long chi = euler_characteristic(m);
  std::printf("consumer: tetrahedron euler %ld\n", chi);
  return chi == 2 ? 0 : 1;
}
