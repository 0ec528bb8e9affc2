#pragma once
//! Signed distance functions of simple shapes and their blends (all 1-Lipschitz, negative inside), the
//! building blocks of the synthetic sequences.
#include "kernels/mesh/surface_mesh.hpp"

namespace topotrack::sdf_shapes {

double sphere(const Vec3& p, const Vec3& centre, double radius);
//! The points within `radius` of the segment a-b.
double capsule(const Vec3& p, const Vec3& a, const Vec3& b, double radius);
//! Torus about the axis through `centre` along z: major radius R, minor radius r.
double torus_z(const Vec3& p, const Vec3& centre, double R, double r);
//! Polynomial smooth minimum (blend width k > 0): <= min(a, b), equal to it when |a - b| >= k. Its
//! gradient is a convex combination of the gradients of a and b, so it keeps a Lipschitz bound of 1.
double smooth_min(double a, double b, double k);

}  // namespace topotrack::sdf_shapes
