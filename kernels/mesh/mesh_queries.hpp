#pragma once
//! Queries over a SurfaceMesh that the stages need: normals, areas, bounding box, components,
//! Euler characteristic and genus, edge-length and angle statistics. Deleted elements are skipped.
#include <algorithm>
#include <cmath>
#include <vector>

#include "kernels/mesh/surface_mesh.hpp"

namespace topotrack {

struct BoundingBox {
  Vec3 min = Vec3::Constant(std::numeric_limits<double>::infinity());
  Vec3 max = Vec3::Constant(-std::numeric_limits<double>::infinity());
  void extend(const Vec3& p) {
    min = min.cwiseMin(p);
    max = max.cwiseMax(p);
  }
  bool empty() const { return !(min.x() <= max.x()); }
  double diagonal() const { return empty() ? 0.0 : (max - min).norm(); }
  Vec3 center() const { return 0.5 * (min + max); }
};

//! Summary statistics of a list of values.
struct Stats {
  std::size_t count = 0;
  double min = 0, max = 0, mean = 0, median = 0;
};
Stats make_stats(std::vector<double> values);

Vec3 face_normal(const SurfaceMesh& mesh, Face f);   //!< unit normal (zero for a degenerate face)
double face_area(const SurfaceMesh& mesh, Face f);
//! Angle-weighted unit vertex normals, indexed by vertex handle (zero for deleted/isolated vertices).
std::vector<Vec3> vertex_normals(const SurfaceMesh& mesh);
BoundingBox bounding_box(const SurfaceMesh& mesh);
double surface_area(const SurfaceMesh& mesh);
//! Per-vertex component label (kInvalidIndex for deleted vertices) and the number of components.
Index connected_components(const SurfaceMesh& mesh, std::vector<Index>* labels = nullptr);
//! V - E + F over live elements.
long euler_characteristic(const SurfaceMesh& mesh);
//! Total genus of a closed mesh: (2 C - chi) / 2.
long genus(const SurfaceMesh& mesh);
std::size_t boundary_edge_count(const SurfaceMesh& mesh);
Stats edge_length_stats(const SurfaceMesh& mesh);
double mean_edge_length(const SurfaceMesh& mesh);

//! Triangle-quality figures used by the improvement targets (§4.1).
struct QualityStats {
  double min_angle_deg = 180;             //!< smallest interior angle
  double share_below_10deg = 0;           //!< fraction of triangles with an angle below 10°
  std::size_t below_2deg = 0;             //!< triangles with an angle below 2°
  std::size_t near_degenerate = 0;        //!< triangles is_near_degenerate calls degenerate
  double min_dihedral_deg = 180;          //!< smallest dihedral angle (180 = flat)
  std::size_t dihedral_below_45deg = 0;   //!< interior edges whose dihedral angle is below 45°
  Stats edge_length;
};
QualityStats quality_stats(const SurfaceMesh& mesh);

//! sin of the smallest interior angle of triangle (p0, p1, p2): twice its area over the product of its two
//! longest edges (the smallest angle lies between them); 0 for a degenerate triangle.
inline double min_angle_sin(const Vec3& p0, const Vec3& p1, const Vec3& p2) {
  const Vec3 e0 = p1 - p0, e1 = p2 - p1, e2 = p0 - p2;
  const double l0 = e0.squaredNorm(), l1 = e1.squaredNorm(), l2 = e2.squaredNorm();
  const double twice_area = e0.cross(e2).norm();
  const double lmin = std::min({l0, l1, l2});
  const double prod = (l0 == lmin) ? l1 * l2 : (l1 == lmin ? l0 * l2 : l0 * l1);
  return prod > 0 ? twice_area / std::sqrt(prod) : 0.0;
}
//! sin of the smallest angle below which a triangle counts as degenerate (about 0.057°).
inline constexpr double kNearDegenerateSin = 1e-3;
//! Whether triangle (p0, p1, p2) is degenerate or nearly so — zero area, a needle (two corners almost
//! together) or a cap (a corner almost on the opposite edge): its smallest angle has a sine below
//! kNearDegenerateSin, computed from the corners as given or rounded to float (as PLY files store them;
//! `topotrack eval` calls a triangle of zero area there degenerate, so this is at least as strict).
bool is_near_degenerate(const Vec3& p0, const Vec3& p1, const Vec3& p2);

//! Dihedral angle across an interior edge in degrees: 180 for coplanar faces, 0 for a fold.
double dihedral_angle_deg(const SurfaceMesh& mesh, Edge e);
//! The three interior angles of a face in degrees.
std::array<double, 3> face_angles_deg(const SurfaceMesh& mesh, Face f);

//! The closest point to p on triangle (a, b, c) (Ericson, Real-Time Collision Detection §5.1.5).
Vec3 closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);

}  // namespace topotrack
