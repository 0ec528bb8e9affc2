#pragma once
//! The §4.1 targets of improve_mesh as test assertions, shared by the improvement tests.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "kernels/improve/improve.hpp"
#include "kernels/mesh/mesh_queries.hpp"
#include "tests/kernels/improve/surface_distance.hpp"

namespace topotrack::test {

inline std::string describe(const std::string& name, const SurfaceMesh& in, const SurfaceMesh& out, const ImproveReport& r) {
  const QualityStats q0 = quality_stats(in), q = quality_stats(out);
  char buf[400];
  std::snprintf(buf, sizeof buf,
                "%-22s V %6zu -> %6zu  splits %5zu collapses %5zu flips %5zu it %2d  min angle %5.2f -> %5.2f  "
                "<10: %.4f -> %.4f  dihedral %6.2f -> %6.2f  edges [%.4f %.4f] in [%.4f %.4f]",
                name.c_str(), in.n_vertices(), out.n_vertices(), r.splits, r.collapses, r.flips, r.iterations,
                q0.min_angle_deg, q.min_angle_deg, q0.share_below_10deg, q.share_below_10deg,
                q0.min_dihedral_deg, q.min_dihedral_deg, q.edge_length.min, q.edge_length.max,
                r.min_edge_length, r.max_edge_length);
  return buf;
}

//! The §4.1 targets of the issue.
inline void expect_targets(const SurfaceMesh& in, const SurfaceMesh& out, const ImproveReport& rep, const std::string& name) {
  SCOPED_TRACE(name);
  EXPECT_NO_THROW(out.validate());
  const QualityStats q = quality_stats(out);
  EXPECT_LE(q.share_below_10deg, 0.005);
  EXPECT_EQ(q.below_2deg, 0u);
  EXPECT_EQ(q.dihedral_below_45deg, 0u);
  EXPECT_GE(q.edge_length.min, rep.min_edge_length * (1 - 1e-9));
  EXPECT_LE(q.edge_length.max, rep.max_edge_length * (1 + 1e-9));
  EXPECT_EQ(genus(out), genus(in));
  EXPECT_EQ(connected_components(out), connected_components(in));
  const double diag = bounding_box(in).diagonal();
  const double hd = hausdorff_distance(in, out, 0.01 * diag);
  std::printf("%s  hausdorff %.5f diag\n", describe(name, in, out, rep).c_str(), hd / diag);
  EXPECT_LE(hd, 0.002 * diag);
}

}  // namespace topotrack::test
