#include "kernels/eval/surface_distance.hpp"

#include <cmath>

#include "io/error.hpp"

namespace topotrack {

DistanceStats one_sided_distance(std::span<const Vec3> points, const TargetSurface& to) {
  DistanceStats s;
  s.samples = points.size();
  if (points.empty()) return s;
  const auto hits = to.closest_points(points);
  double sum = 0, sum2 = 0;  // summed in index order: deterministic
  for (std::size_t i = 0; i < hits.size(); ++i) {
    const double d = hits[i].distance;
    sum += d;
    sum2 += d * d;
    if (d > s.max) {
      s.max = d;
      s.max_index = i;
    }
  }
  s.max_point = points[s.max_index];
  s.mean = sum / double(points.size());
  s.rms = std::sqrt(sum2 / double(points.size()));
  return s;
}

std::vector<Vec3> surface_samples(const SurfaceMesh& mesh) {
  std::vector<Vec3> pts;
  pts.reserve(mesh.n_vertices() + mesh.n_faces());
  for (Index i = 0; i < mesh.vertices_size(); ++i)
    if (!mesh.is_deleted(Vertex(i))) pts.push_back(mesh.position(Vertex(i)));
  for (Index f = 0; f < mesh.faces_size(); ++f) {
    if (mesh.is_deleted(Face(f))) continue;
    const auto v = mesh.vertices(Face(f));
    pts.push_back((mesh.position(v[0]) + mesh.position(v[1]) + mesh.position(v[2])) / 3.0);
  }
  return pts;
}

SurfaceDistance surface_distance(const SurfaceMesh& a, const SurfaceMesh& b) {
  if (a.n_faces() == 0 || b.n_faces() == 0) TT_THROW(InvalidInput, "surface distance: a mesh has no triangles");
  const TargetSurface ta = TargetSurface::from_mesh(a), tb = TargetSurface::from_mesh(b);
  SurfaceDistance d;
  d.a_to_b = one_sided_distance(surface_samples(a), tb);
  d.b_to_a = one_sided_distance(surface_samples(b), ta);
  return d;
}

}  // namespace topotrack
