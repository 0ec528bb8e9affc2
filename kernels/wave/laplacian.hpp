#pragma once
//! The discrete Laplace operator with cotangent weights and lumped (barycentric) masses [Botsch et al. 2010],
//! used by the wave simulation of §5 (eq. 1): laplace(h)_i = -(C h)_i / m_i.
#include <array>
#include <span>
#include <vector>

#include "kernels/mesh/surface_mesh.hpp"

namespace topotrack {

//! C in compressed rows: (C h)_i = sum_j w_ij (h_i - h_j), w_ij = (cot a_ij + cot b_ij) / 2, so C is symmetric
//! positive semi-definite (h^T C h is twice the Dirichlet energy of the piecewise linear h).
struct CotanLaplacian {
  std::vector<std::size_t> row_begin;  //!< size n + 1
  std::vector<Index> col;              //!< neighbours j of each row, increasing
  std::vector<double> weight;          //!< w_ij
  std::vector<double> diagonal;        //!< sum_j w_ij
  std::vector<double> mass;            //!< barycentric area m_i (one third of the adjacent triangle areas)

  std::size_t size() const { return mass.size(); }
  //! out = C h (rows in parallel, each row summed in a fixed order: deterministic).
  void apply(std::span<const double> h, std::span<double> out) const;
  //! h^T C h (per-row partials summed in order).
  double dirichlet(std::span<const double> h) const;
  //! Gershgorin bound on the largest eigenvalue of M^-1 C.
  double max_eigenvalue_bound() const;
};

//! Build C and M for a triangle soup. Robust on tracked meshes with slivers: a triangle with area below
//! 1e-12 times its longest edge squared contributes nothing; a triangle with a cotangent beyond cot(1 deg) has
//! all its weights scaled so the largest is cot(1 deg) (a positive scaling keeps C positive semi-definite, so
//! the explicit integrator stays stable and energy-conserving); masses are floored at 0.05 times the mean
//! mass (vertices of slivers only) so M^-1 C, and with it the CFL sub-step count, stays bounded.
//! \throw InvalidInput on an index out of range or a non-finite position.
CotanLaplacian cotan_laplacian(std::span<const Vec3> positions, std::span<const std::array<Index, 3>> triangles);

//! Area-weighted unit vertex normals of a triangle soup (zero for a vertex without triangles).
std::vector<Vec3> soup_vertex_normals(std::span<const Vec3> positions, std::span<const std::array<Index, 3>> triangles);

//! Displacement maps (§5): p_i + scale * h_i * n_i with area-weighted normals.
//! \throw InvalidInput when heights.size() != positions.size() or an index is out of range.
std::vector<Vec3> displace_along_normals(std::span<const Vec3> positions,
                                         std::span<const std::array<Index, 3>> triangles,
                                         std::span<const double> heights, double scale = 1.0);

}  // namespace topotrack
