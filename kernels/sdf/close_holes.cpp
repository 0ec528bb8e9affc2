#include "kernels/sdf/close_holes.hpp"

#include <algorithm>
#include <cmath>

#include "io/error.hpp"
#include "kernels/sdf/marching_cubes.hpp"
#include "kernels/sdf/signed_distance.hpp"

namespace topotrack {

std::vector<std::vector<Index>> boundary_loops(std::span<const std::array<Index, 3>> triangles) {
  using DirectedEdge = std::pair<Index, Index>;
  std::vector<DirectedEdge> edges;
  edges.reserve(3 * triangles.size());
  for (const auto& t : triangles)
    for (int k = 0; k < 3; ++k) edges.emplace_back(t[k], t[(k + 1) % 3]);
  std::sort(edges.begin(), edges.end());
  std::vector<DirectedEdge> boundary;  // sorted, as `edges`
  for (const auto& [a, b] : edges)
    if (!std::binary_search(edges.begin(), edges.end(), DirectedEdge(b, a))) boundary.emplace_back(a, b);
  std::vector<char> used(boundary.size(), 0);
  std::vector<std::vector<Index>> loops;
  for (std::size_t s = 0; s < boundary.size(); ++s) {
    if (used[s]) continue;
    std::vector<Index> loop;
    std::size_t e = s;
    for (;;) {
      used[e] = 1;
      loop.push_back(boundary[e].first);
      // Continue with the first unused boundary edge leaving the end vertex.
      const Index to = boundary[e].second;
      auto it = std::lower_bound(boundary.begin(), boundary.end(), DirectedEdge(to, 0));
      while (it != boundary.end() && it->first == to && used[std::size_t(it - boundary.begin())]) ++it;
      if (it == boundary.end() || it->first != to) break;
      e = std::size_t(it - boundary.begin());
    }
    loops.push_back(std::move(loop));
  }
  return loops;
}

double loop_extent(std::span<const Vec3> positions, std::span<const Index> loop) {
  if (loop.empty()) return 0;
  Vec3 lo = positions[loop.front()], hi = lo;
  for (Index i : loop) {
    lo = lo.cwiseMin(positions[i]);
    hi = hi.cwiseMax(positions[i]);
  }
  return (hi - lo).norm();
}

MeshData close_holes(std::span<const Vec3> positions, std::span<const std::array<Index, 3>> triangles,
                     const CloseHolesParams& params, CloseHolesReport* report) {
  if (triangles.empty()) TT_THROW(InvalidInput, "closing holes: no triangles");
  const double h = params.voxel_size;
  if (!(h > 0) || !std::isfinite(h)) TT_THROW(InvalidInput, "closing holes: bad voxel size " << h);
  for (std::size_t f = 0; f < triangles.size(); ++f)
    for (Index v : triangles[f])
      if (v >= positions.size())
        TT_THROW(InvalidInput, "closing holes: triangle " << f << " has vertex index " << v << " out of range");
  const auto loops = boundary_loops(triangles);

  std::vector<Vec3> P(positions.begin(), positions.end());
  std::vector<std::array<Index, 3>> T(triangles.begin(), triangles.end());
  CloseHolesReport rep;
  for (const auto& loop : loops) {
    const double extent = loop_extent(positions, loop);
    if (extent > params.max_hole_voxels * h)
      TT_THROW(InvalidInput, "closing holes: a hole of " << loop.size() << " boundary edges is " << extent
                                                         << " across, larger than " << params.max_hole_voxels
                                                         << " voxels of " << h);
    // The cap: a fan around the loop's centroid, each triangle taking its boundary edge a->b reversed.
    Vec3 c = Vec3::Zero();
    for (Index i : loop) c += positions[i];
    const Index centre = Index(P.size());
    P.push_back(c / double(loop.size()));
    for (std::size_t k = 0; k < loop.size(); ++k) T.push_back({loop[(k + 1) % loop.size()], loop[k], centre});
    rep.hole_boundary_edges += loop.size();
    rep.largest_hole = std::max(rep.largest_hole, extent);
  }
  rep.holes_closed = loops.size();

  // The caps may cross the surface (a ragged hole, a pinched loop): the winding number's sign is the
  // union of what they enclose, and thin parts are kept in one piece (kernels/gen/resurface.hpp).
  SignedDistanceParams sdf;
  sdf.voxel_size = h;
  sdf.min_thickness_voxels = std::max(0.0, params.min_thickness_voxels);
  sdf.half_width_voxels = std::max(2.0, sdf.min_thickness_voxels > 0 ? 0.5 * sdf.min_thickness_voxels + 1.5 : 2.0);
  sdf.exact_sign_band_voxels = sdf.half_width_voxels;
  sdf.sign_method = SignMethod::kWindingNumber;
  SignedDistanceReport sdf_report;
  MeshData closed = marching_cubes(*signed_distance(P, T, sdf, &sdf_report));
  if (closed.triangles.empty())
    TT_THROW(InvalidInput, "closing the holes left no surface at voxel size " << h
                                                                             << " (the surface is thinner than a voxel)");
  rep.signs_flipped = sdf_report.signs_flipped;
  rep.thin_vertices = sdf_report.thin_vertices;
  if (report) *report = rep;
  return closed;
}

}  // namespace topotrack
