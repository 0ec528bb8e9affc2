// The relaxation on the target (kernels/registration/relax.hpp): a mesh slid along the surface slides back towards its
// rest shape and stays on the target; a mesh at rest stays; deterministic; bad input refused.
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <Eigen/Geometry>
#include <cmath>

#include "io/error.hpp"
#include "kernels/registration/fine.hpp"
#include "kernels/registration/relax.hpp"
#include "tests/kernels/registration/blob.hpp"
#include "tests/support/test_meshes.hpp"

namespace topotrack {
namespace {

using test::blob;
using test::mean_error;

double mean_distance(const SurfaceMesh& m, const TargetSurface& t) {
  double e = 0;
  for (const Vec3& p : m.positions()) e += t.closest_point(p).distance;
  return e / double(m.n_vertices());
}

// The blob (its rest shape and ground truth) twisted about its long axis by up to `turn` radians at its ends, each
// vertex then put on its closest point of the target, a finer triangulation of the same blob: every vertex lies on
// the surface, slid along it, and belongs where it was.
struct SlideCase {
  SurfaceMesh mesh;
  std::vector<Vec3> rest;
  TargetSurface target;
};

SlideCase slide_case(double turn) {
  const test::Soup src = blob(4);
  const test::Soup tgt = blob(5);
  TargetSurface target(tgt.positions, tgt.triangles);
  SurfaceMesh mesh = src.mesh();
  const std::vector<Vec3> rest = mesh.positions();
  for (Vec3& p : mesh.positions()) {
    const Vec3 turned = Eigen::AngleAxisd(turn * p.x(), Vec3::UnitX()) * p;
    p = target.closest_point(turned).point;
  }
  return {std::move(mesh), rest, std::move(target)};
}

RelaxParams relax(int iterations) {
  RelaxParams p;
  p.iterations = iterations;
  return p;
}

TEST(Relax, SlidesASlidMeshBackAlongTheTarget) {
  SlideCase c = slide_case(0.4);
  const double before = mean_error(c.mesh, c.rest);
  const RelaxReport r = relax_on_target(c.mesh, c.rest, c.target, relax(kLargeMotionRelaxIterations));
  const double after = mean_error(c.mesh, c.rest);
  std::printf("slid blob: error %.5f -> %.5f, distance to the target %.6f, %d cg, %.3f s\n", before, after,
              mean_distance(c.mesh, c.target), r.cg_iterations, r.seconds_total);
  EXPECT_EQ(r.iterations, kLargeMotionRelaxIterations);
  EXPECT_LT(after, 0.3 * before);
  EXPECT_LT(r.energy_end, r.energy_start);
  EXPECT_LT(mean_distance(c.mesh, c.target), 1e-3);  // on the surface (the blob's diagonal is about 2.8)
  // More iterations slide it further back.
  SlideCase more = slide_case(0.4);
  relax_on_target(more.mesh, more.rest, more.target, relax(40));
  EXPECT_LT(mean_error(more.mesh, more.rest), after);
}

TEST(Relax, AMeshAtRestStays) {
  const test::Soup s = blob(4);
  SurfaceMesh mesh = s.mesh();
  const std::vector<Vec3> rest = mesh.positions();
  const TargetSurface target(s.positions, s.triangles);
  relax_on_target(mesh, rest, target, relax(5));
  EXPECT_LT(mean_error(mesh, rest), 1e-9);
}

TEST(Relax, SameResultWithOneAndTwoThreads) {
  std::vector<Vec3> out[2];
  for (int threads = 1; threads <= 2; ++threads) {
    SlideCase c = slide_case(0.4);
    tbb::task_arena arena(threads);
    arena.execute([&] { relax_on_target(c.mesh, c.rest, c.target, relax(6)); });
    out[threads - 1] = c.mesh.positions();
  }
  ASSERT_EQ(out[0].size(), out[1].size());
  for (std::size_t i = 0; i < out[0].size(); ++i) ASSERT_EQ(out[0][i], out[1][i]) << "vertex " << i;
}

TEST(Relax, AnOpenMeshRelaxesWithoutLeavingTheTarget) {
  // A box without its lid: boundary edges have one triangle's cotangent.
  const test::Soup box = test::open_box();
  SurfaceMesh mesh = box.mesh();
  const std::vector<Vec3> rest = mesh.positions();
  const TargetSurface target(box.positions, box.triangles);
  for (Vec3& p : mesh.positions()) p = target.closest_point(p + Vec3(0.02, 0.01, 0)).point;
  const double before = mean_error(mesh, rest);
  const RelaxReport r = relax_on_target(mesh, rest, target, relax(10));
  for (const Vec3& p : mesh.positions()) ASSERT_TRUE(p.allFinite());
  EXPECT_LT(mean_error(mesh, rest), before);
  EXPECT_LT(mean_distance(mesh, target), 1e-3);
  EXPECT_EQ(r.iterations, 10);
}

TEST(Relax, RefusesBadInputAndDoesNothingWithoutIterations) {
  SlideCase c = slide_case(0.2);
  const std::vector<Vec3> before = c.mesh.positions();
  const RelaxReport none = relax_on_target(c.mesh, c.rest, c.target, relax(0));
  EXPECT_EQ(none.iterations, 0);
  EXPECT_EQ(c.mesh.positions(), before);
  std::vector<Vec3> short_rest(c.rest.begin(), c.rest.end() - 1);
  EXPECT_THROW(relax_on_target(c.mesh, short_rest, c.target, relax(1)), InvalidInput);
  RelaxParams bad = relax(1);
  bad.plane_weight = 0;
  EXPECT_THROW(relax_on_target(c.mesh, c.rest, c.target, bad), InvalidInput);
  bad = relax(-1);
  EXPECT_THROW(relax_on_target(c.mesh, c.rest, c.target, bad), InvalidInput);
  bad = relax(1);
  bad.cg_iterations = 0;
  EXPECT_THROW(relax_on_target(c.mesh, c.rest, c.target, bad), InvalidInput);
  bad = relax(1);
  bad.max_distance = 0;
  EXPECT_THROW(relax_on_target(c.mesh, c.rest, c.target, bad), InvalidInput);
  std::vector<Vec3> not_finite = c.rest;
  not_finite[3].x() = std::nan("");
  EXPECT_THROW(relax_on_target(c.mesh, not_finite, c.target, relax(1)), InvalidInput);
}

// A component with no counterpart in the target (beyond max_distance) stays where it is, as the fine stage leaves it;
// the one on the target is fitted.
TEST(Relax, AComponentBeyondReachStays) {
  test::FarSphereCase c = test::far_sphere_case();
  std::vector<Vec3> rest = c.mesh.positions();
  for (std::size_t i = 0; i < c.near_vertices; ++i) rest[i] *= 1.02;  // the near sphere's rest shape a little larger
  const std::vector<Vec3> before = c.mesh.positions();
  RelaxParams p = relax(5);
  p.max_distance = 0.3;  // of the target's diagonal (2.06): the far sphere, 3 away, is beyond it
  const RelaxReport r = relax_on_target(c.mesh, rest, c.target, p);
  for (std::size_t i = c.near_vertices; i < before.size(); ++i) ASSERT_EQ(c.mesh.positions()[i], before[i]);
  EXPECT_EQ(r.fitted, c.near_vertices);
  for (std::size_t i = 0; i < c.near_vertices; ++i) EXPECT_NEAR(c.mesh.positions()[i].norm(), 1.03, 2e-3);
}

// align_fine runs the relaxation after its rounds where it is given the rest shape, and only then.
TEST(Relax, AlignFineRelaxesOnlyWithARestShape) {
  FineParams p;
  p.relax.iterations = 4;
  SlideCase with = slide_case(0.4), without = slide_case(0.4);
  const FineReport a = align_fine(with.mesh, with.target, p, with.rest);
  const FineReport b = align_fine(without.mesh, without.target, p);
  EXPECT_EQ(a.relax.iterations, 4);
  EXPECT_EQ(b.relax.iterations, 0);
  EXPECT_LT(mean_error(with.mesh, with.rest), mean_error(without.mesh, without.rest));
}

}  // namespace
}  // namespace topotrack
