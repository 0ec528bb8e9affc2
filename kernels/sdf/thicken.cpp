#include "kernels/sdf/thicken.hpp"

#include <openvdb/tree/LeafManager.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "kernels/raycast/target_surface.hpp"

namespace topotrack {
namespace {

//! Per vertex how much the surface must move out there: max(0, (min_thickness - thickness) / 2), the
//! thickness measured by a ray along the inward area-weighted normal.
std::vector<double> vertex_offsets(const TargetSurface& surface, std::span<const Vec3> P,
                                   std::span<const std::array<Index, 3>> T, double min_thickness,
                                   std::size_t& thin) {
  std::vector<Vec3> normal(P.size(), Vec3::Zero());
  for (const auto& t : T) {
    const Vec3 n = (P[t[1]] - P[t[0]]).cross(P[t[2]] - P[t[0]]);
    for (Index v : t) normal[v] += n;
  }
  std::vector<double> offset(P.size(), 0.0);
  // The ray starts a little inside so that it does not hit the triangles around its own vertex.
  const double eps = 1e-3 * min_thickness;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, P.size(), 256), [&](const auto& r) {
    for (std::size_t v = r.begin(); v < r.end(); ++v) {
      const double len = normal[v].norm();
      if (!(len > 0)) continue;
      const Vec3 in = -normal[v] / len;
      const auto hit = surface.cast(P[v] + eps * in, in, min_thickness);
      // Only a hit from behind is the other side of the part; a hit from the front means the ray left the
      // solid at once (a vertex on a sharp crease, e.g. where a hole's cap meets the surface).
      if (hit.hit && hit.normal.dot(in) > 0) offset[v] = std::max(0.0, 0.5 * (min_thickness - (hit.distance + eps)));
    }
  });
  thin = std::size_t(std::count_if(offset.begin(), offset.end(), [](double o) { return o > 0; }));
  return offset;
}

}  // namespace

ThickenReport thicken_thin_parts(openvdb::FloatGrid& phi, std::span<const Vec3> P,
                                 std::span<const std::array<Index, 3>> T, const ThickenParams& params) {
  ThickenReport report;
  if (T.empty() || !(params.min_thickness > 0)) return report;
  const TargetSurface surface(P, T);
  const std::vector<double> offset = vertex_offsets(surface, P, T, params.min_thickness, report.thin_vertices);
  if (report.thin_vertices == 0) return report;

  openvdb::tree::LeafManager<openvdb::FloatTree> leaves(phi.tree());
  std::vector<std::size_t> count(leaves.leafCount() + 1, 0);
  leaves.foreach([&](const openvdb::FloatTree::LeafNodeType& leaf, std::size_t i) { count[i + 1] = leaf.onVoxelCount(); });
  for (std::size_t i = 1; i < count.size(); ++i) count[i] += count[i - 1];
  std::vector<Vec3> points(count.back());
  const openvdb::math::Transform& xform = phi.transform();
  leaves.foreach([&](const openvdb::FloatTree::LeafNodeType& leaf, std::size_t i) {
    std::size_t k = count[i];
    for (auto it = leaf.cbeginValueOn(); it; ++it) {
      const openvdb::Vec3d w = xform.indexToWorld(it.getCoord());
      points[k++] = Vec3(w.x(), w.y(), w.z());
    }
  });
  const auto hits = surface.closest_points(points);

  std::vector<std::size_t> changed(leaves.leafCount(), 0);
  leaves.foreach([&](openvdb::FloatTree::LeafNodeType& leaf, std::size_t i) {
    std::size_t k = count[i];
    for (auto it = leaf.beginValueOn(); it; ++it) {
      const auto& h = hits[k++];
      if (!h.hit) continue;
      const auto& tri = T[h.face];
      const double o0 = offset[tri[0]], o1 = offset[tri[1]], o2 = offset[tri[2]];
      if (o0 == 0 && o1 == 0 && o2 == 0) continue;
      // Barycentric interpolation of the offsets at the closest point (the face average if degenerate).
      const Vec3 v0 = P[tri[1]] - P[tri[0]], v1 = P[tri[2]] - P[tri[0]], v2 = h.point - P[tri[0]];
      const double d00 = v0.dot(v0), d01 = v0.dot(v1), d11 = v1.dot(v1), d20 = v2.dot(v0), d21 = v2.dot(v1);
      const double den = d00 * d11 - d01 * d01;
      double t = (o0 + o1 + o2) / 3;
      if (den > 0) {
        const double wb = std::clamp((d11 * d20 - d01 * d21) / den, 0.0, 1.0);
        const double wc = std::clamp((d00 * d21 - d01 * d20) / den, 0.0, 1.0 - wb);
        t = (1 - wb - wc) * o0 + wb * o1 + wc * o2;
      }
      const float v = *it;
      const float thick = float(std::abs(double(v)) - t);
      if (thick < v) {
        it.setValue(thick);
        ++changed[i];
      }
    }
  });
  for (std::size_t c : changed) report.voxels_changed += c;
  return report;
}

}  // namespace topotrack
