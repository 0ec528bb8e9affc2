#pragma once
//! The registration tests' asymmetric closed shape (a bumpy ellipsoid), so that rotations are observable.
#include <cmath>

#include "tests/support/test_meshes.hpp"

namespace topotrack::test {

inline Soup blob(int subdivisions = 4) {
  Soup s = icosphere(subdivisions);
  for (Vec3& p : s.positions) {
    const double bump = 1 + 0.25 * std::exp(-8 * (p - Vec3(0.6, 0.6, 0.5).normalized()).squaredNorm()) +
                        0.15 * std::exp(-10 * (p - Vec3(-0.7, 0.1, -0.7).normalized()).squaredNorm());
    p = Vec3(1.0 * p.x(), 0.7 * p.y(), 0.5 * p.z()) * bump;
  }
  return s;
}

}  // namespace topotrack::test
