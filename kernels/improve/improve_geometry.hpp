#pragma once
//! Small geometric predicates of the mesh improvement (§4.1), shared by its passes.
#include <algorithm>
#include <cmath>

#include "kernels/mesh/mesh_queries.hpp"

namespace topotrack::improve_detail {

//! sin of the smallest interior angle of triangle (p0, p1, p2) (mesh_queries' min_angle_sin): monotone in
//! that angle, which is at most 60°, so it orders triangles like the angle does without a trigonometric
//! call. 0 for a degenerate triangle.
inline double triangle_quality(const Vec3& p0, const Vec3& p1, const Vec3& p2) { return min_angle_sin(p0, p1, p2); }

//! Distance between segments [p0,p1] and [q0,q1] (Ericson, Real-Time Collision Detection, 5.1.9).
inline double segment_distance(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1) {
  const Vec3 d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  double s = 0, t = 0;
  if (a <= 0 && e <= 0) return r.norm();
  if (a <= 0) {
    t = std::clamp(f / e, 0.0, 1.0);
  } else {
    const double c = d1.dot(r);
    if (e <= 0) {
      s = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const double b = d1.dot(d2), den = a * e - b * b;
      s = den > 0 ? std::clamp((b * f - c * e) / den, 0.0, 1.0) : 0.0;
      t = (b * s + f) / e;
      if (t < 0) {
        t = 0;
        s = std::clamp(-c / a, 0.0, 1.0);
      } else if (t > 1) {
        t = 1;
        s = std::clamp((b - c) / a, 0.0, 1.0);
      }
    }
  }
  return ((p0 + s * d1) - (q0 + t * d2)).norm();
}

//! Whether the angle between (unnormalised) normals n and m is at most acos(cos_max):
//! n.m >= cos_max |n| |m|, false when either vanishes.
inline bool normals_within(const Vec3& n, const Vec3& m, double cos_max) {
  const double d = n.dot(m), nn = n.squaredNorm() * m.squaredNorm();
  if (!(nn > 0)) return false;
  if (cos_max >= 0) return d >= 0 && d * d >= cos_max * cos_max * nn;
  return d >= 0 || d * d <= cos_max * cos_max * nn;
}

//! Cosine of the angle between (unnormalised) normals n and m; 1 when either vanishes (a degenerate face
//! has no normal and creases nothing).
inline double normal_cos(const Vec3& n, const Vec3& m) {
  const double nn = n.squaredNorm() * m.squaredNorm();
  return nn > 0 ? n.dot(m) / std::sqrt(nn) : 1.0;
}

}  // namespace topotrack::improve_detail
