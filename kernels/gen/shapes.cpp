#include "kernels/gen/shapes.hpp"

#include <algorithm>
#include <cmath>

namespace topotrack::sdf_shapes {

double sphere(const Vec3& p, const Vec3& centre, double radius) { return (p - centre).norm() - radius; }

double capsule(const Vec3& p, const Vec3& a, const Vec3& b, double radius) {
  const Vec3 ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return (p - (a + t * ab)).norm() - radius;
}

double torus_z(const Vec3& p, const Vec3& centre, double R, double r) {
  const Vec3 q = p - centre;
  const double ring = std::hypot(q.x(), q.y()) - R;
  return std::hypot(ring, q.z()) - r;
}

double smooth_min(double a, double b, double k) {
  const double h = std::max(k - std::abs(a - b), 0.0) / k;
  return std::min(a, b) - h * h * k * 0.25;
}

}  // namespace topotrack::sdf_shapes
