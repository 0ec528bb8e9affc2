// The winding-number sign (exact_sign.hpp with SignMethod::kWindingNumber) and the thickening of thin parts
// (thicken.hpp), on meshes built in code.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include "kernels/mesh/mesh_convert.hpp"
#include "kernels/mesh/mesh_queries.hpp"
#include "kernels/sdf/marching_cubes.hpp"
#include "kernels/sdf/signed_distance.hpp"
#include "kernels/sdf/thicken.hpp"
#include "kernels/sdf/winding_number.hpp"
#include "tests/support/test_meshes.hpp"

namespace topotrack {
namespace {

struct Topo {
  Index components;
  long euler;
  std::size_t vertices;
};
Topo topo_of(const MeshData& m) {
  const SurfaceMesh s = to_surface_mesh(m);
  s.validate(/*require_closed=*/true);
  return {connected_components(s), euler_characteristic(s), s.n_vertices()};
}

TEST(WindingNumber, InsideOutsideAndUnion) {
  const test::Soup a = test::icosphere(4, 1.0), both = test::merge(a, test::icosphere(4, 1.0, Vec3(1.2, 0, 0)));
  const WindingNumber w(a.positions, a.triangles), w2(both.positions, both.triangles);
  EXPECT_NEAR(w(Vec3(0, 0, 0)), 1.0, 0.05);  // far from every triangle: all dipoles
  EXPECT_NEAR(w(Vec3(0.9, 0.1, 0)), 1.0, 0.05);
  EXPECT_NEAR(w(Vec3(3, 1, 0)), 0.0, 0.05);
  EXPECT_NEAR(w(Vec3(1.02, 0, 0)), 0.0, 0.05);
  EXPECT_NEAR(w2(Vec3(0.6, 0, 0)), 2.0, 0.05);  // inside both: the overlap counts twice
  EXPECT_NEAR(w2(Vec3(-0.5, 0, 0)), 1.0, 0.05);
  // The dipole approximation agrees with the exact sum (accuracy so large that no node is approximated).
  const WindingNumber exact(both.positions, both.triangles, 1e12);
  std::vector<Vec3> q;
  for (int i = 0; i < 400; ++i) q.push_back(Vec3(-1.5 + 0.01 * i, 0.3 * std::sin(i), 0.2 * std::cos(3 * i)));
  const auto fast = w2.evaluate(q), slow = exact.evaluate(q);
  for (std::size_t i = 0; i < q.size(); ++i) EXPECT_NEAR(fast[i], slow[i], 0.2) << q[i].transpose();
  EXPECT_THROW(WindingNumber(a.positions, a.triangles, 0.5), InvalidInput);
  auto bad = a;
  bad.triangles[3][1] = 999999;
  EXPECT_THROW(WindingNumber(bad.positions, bad.triangles), InvalidInput);
}

// Two interpenetrating spheres as one self-intersecting mesh: the level set of their union (one component,
// genus 0), whatever OpenVDB's own sign makes of the inner surfaces.
TEST(ExactSign, WindingNumberSignGivesTheUnionOfOverlappingParts) {
  const test::Soup both = test::merge(test::icosphere(4, 0.5), test::icosphere(4, 0.5, Vec3(0.6, 0.1, 0)));
  SignedDistanceParams p;
  p.voxel_size = 0.03;
  p.exact_sign_band_voxels = 3;
  p.sign_method = SignMethod::kWindingNumber;
  SignedDistanceReport r;
  const auto grid = signed_distance(both.positions, both.triangles, p, &r);
  const Topo t = topo_of(marching_cubes(*grid));
  EXPECT_EQ(t.components, 1u);
  EXPECT_EQ(t.euler, 2);
  // Inside the overlap, where the inner surfaces are: negative.
  auto acc = grid->getConstAccessor();
  EXPECT_LT(acc.getValue(openvdb::Coord(10, 0, 0)), 0);
  EXPECT_LT(acc.getValue(openvdb::Coord(7, 3, 0)), 0);
}

// A disc 0.4 voxel thick at its centre (a flattened sphere, tilted against the lattice): as it is, marching
// cubes sees it only where lattice nodes fall inside it; thickened to 2 voxels it is one sphere-like component.
TEST(Thicken, ThinDiscBecomesOneComponent) {
  test::Soup disc = test::icosphere(5, 1.0);
  const double c = std::cos(0.3), s = std::sin(0.3);
  for (Vec3& v : disc.positions) v = Vec3(v.x(), c * v.y() - s * 0.01 * v.z(), s * v.y() + c * 0.01 * v.z());
  SignedDistanceParams p;
  p.voxel_size = 0.05;
  p.exact_sign_band_voxels = 3;
  p.sign_method = SignMethod::kWindingNumber;
  const MeshData plain = marching_cubes(*signed_distance(disc.positions, disc.triangles, p));
  const bool plain_is_a_sphere = !plain.triangles.empty() && topo_of(plain).components == 1 && topo_of(plain).euler == 2;
  EXPECT_FALSE(plain_is_a_sphere);  // what the thickening is for
  p.min_thickness_voxels = 2;
  SignedDistanceReport r;
  const auto grid = signed_distance(disc.positions, disc.triangles, p, &r);
  EXPECT_GT(r.thin_vertices, disc.positions.size() * 9 / 10);
  EXPECT_GT(r.thickened_voxels, 1000u);
  const Topo thick = topo_of(marching_cubes(*grid));
  EXPECT_EQ(thick.components, 1u);
  EXPECT_EQ(thick.euler, 2);
  // Not enough band for the thickening: refused.
  p.half_width_voxels = 2;
  EXPECT_THROW(signed_distance(disc.positions, disc.triangles, p), InvalidInput);
}

// Where the disc is 0.02 thick the surface moves out by (2 voxels - 0.02) / 2 on each side: to z = +-h.
TEST(Thicken, SurfaceMovesOutByHalfWhatIsMissing) {
  test::Soup disc = test::icosphere(5, 1.0);
  for (Vec3& v : disc.positions) v.z() *= 0.01;
  const double h = 0.05;
  SignedDistanceParams p;
  p.voxel_size = h;
  p.exact_sign_band_voxels = 3;
  p.sign_method = SignMethod::kWindingNumber;
  p.min_thickness_voxels = 2;
  const auto grid = signed_distance(disc.positions, disc.triangles, p);
  auto acc = grid->getConstAccessor();
  EXPECT_NEAR(acc.getValue(openvdb::Coord(0, 0, 0)), 0.01 - (2 * h - 0.02) / 2, 1e-3);
  EXPECT_NEAR(acc.getValue(openvdb::Coord(0, 0, 1)), 0.0, 1e-3);
  EXPECT_NEAR(acc.getValue(openvdb::Coord(0, 0, -2)), h, 1e-3);
}

TEST(Thicken, ThickPartsAreLeftAsTheyAre) {
  const test::Soup s = test::torus(96, 48, 1.0, 0.35);
  openvdb::FloatGrid::Ptr before = signed_distance(s.positions, s.triangles, 0.04, 3.0);
  openvdb::FloatGrid::Ptr after = before->deepCopy();
  const ThickenReport r = thicken_thin_parts(*after, s.positions, s.triangles, {2 * 0.04});
  EXPECT_EQ(r.thin_vertices, 0u);
  EXPECT_EQ(r.voxels_changed, 0u);
  auto acc = after->getConstAccessor();
  for (auto it = before->cbeginValueOn(); it; ++it) ASSERT_EQ(*it, acc.getValue(it.getCoord()));
}

TEST(Thicken, DeterministicAcrossThreadCounts) {
  test::Soup disc = test::icosphere(4, 1.0);
  for (Vec3& v : disc.positions) v.z() *= 0.02;
  SignedDistanceParams p;
  p.voxel_size = 0.05;
  p.exact_sign_band_voxels = 3;
  p.sign_method = SignMethod::kWindingNumber;
  p.min_thickness_voxels = 2;
  openvdb::FloatGrid::Ptr one, two;
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
    one = signed_distance(disc.positions, disc.triangles, p);
  }
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 2);
    two = signed_distance(disc.positions, disc.triangles, p);
  }
  ASSERT_EQ(one->activeVoxelCount(), two->activeVoxelCount());
  auto acc = two->getConstAccessor();
  for (auto it = one->cbeginValueOn(); it; ++it) ASSERT_EQ(*it, acc.getValue(it.getCoord()));
}

}  // namespace
}  // namespace topotrack
