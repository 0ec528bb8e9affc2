#pragma once
//! Generalized winding number of a triangle mesh (Jacobson et al. 2013), evaluated fast with a bounding
//! volume hierarchy whose far nodes are replaced by their dipole (Barill et al. 2018, first order).
//!
//! Why: the inside of a closed surface that intersects itself (real data does: the elephant of
//! /work/shared/data crosses itself in 656 places, pcow in up to 546) is where the winding number is
//! >= 1/2. The pseudonormal of the closest feature (exact_sign.hpp) and OpenVDB's own sign both go
//! wrong next to such crossings; the winding number does not, and it degrades gracefully on small holes.
#include <array>
#include <span>
#include <vector>

#include "kernels/mesh/surface_mesh.hpp"

namespace topotrack {

class WindingNumber {
public:
  //! `accuracy` (beta of Barill et al.): a node is replaced by its dipole when the query point is farther
  //! from its centre than accuracy times its radius. 2 keeps the error far below the 1/2 a sign needs.
  //! \throw InvalidInput on an index out of range or accuracy < 1.
  WindingNumber(std::span<const Vec3> positions, std::span<const std::array<Index, 3>> triangles,
                double accuracy = 2.0);

  //! The winding number at p: 1 inside a closed outward-oriented surface, 0 outside, 1/2 on it.
  double operator()(const Vec3& p) const;
  //! The same for many points, parallel (TBB) and deterministic: each value is computed alone.
  std::vector<double> evaluate(std::span<const Vec3> points) const;

private:
  struct Node {
    Vec3 centre = Vec3::Zero();  //!< area-weighted centroid of the triangles below
    Vec3 area = Vec3::Zero();    //!< sum of their area vectors (half the cross products)
    double radius = 0;           //!< of the ball around `centre` holding all their vertices
    std::uint32_t first = 0, count = 0;  //!< triangles order_[first, first + count) when a leaf
    std::uint32_t left = 0, right = 0;   //!< children when an inner node (count == 0)
  };
  std::uint32_t build(std::uint32_t first, std::uint32_t count, std::vector<Vec3>& centroids);

  std::vector<Vec3> positions_;
  std::vector<std::array<Index, 3>> triangles_;
  std::vector<std::uint32_t> order_;
  std::vector<Node> nodes_;
  double accuracy_;
};

//! The solid angle of triangle (a, b, c) seen from p, signed (positive when p sees its back, i.e. is on
//! the side opposite its normal) (Van Oosterom and Strackee 1983).
double solid_angle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);

}  // namespace topotrack
