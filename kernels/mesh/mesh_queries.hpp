#pragma once
//! Queries over a SurfaceMesh that the stages need: normals, areas, bounding box, components,
//! Euler characteristic and genus, edge-length and angle statistics. Deleted elements are skipped.
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
  double min_dihedral_deg = 180;          //!< smallest dihedral angle (180 = flat)
  std::size_t dihedral_below_45deg = 0;   //!< interior edges whose dihedral angle is below 45°
  Stats edge_length;
};
QualityStats quality_stats(const SurfaceMesh& mesh);

//! Dihedral angle across an interior edge in degrees: 180 for coplanar faces, 0 for a fold.
double dihedral_angle_deg(const SurfaceMesh& mesh, Edge e);
//! The three interior angles of a face in degrees.
std::array<double, 3> face_angles_deg(const SurfaceMesh& mesh, Face f);

}  // namespace topotrack
