// Fine linear alignment (§4.2) with displacements along the vertex normals (FineParams::normal_displacement):
// no tangential slide, the target reached as closely as with vector displacements, deterministic.
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <cmath>

#include "kernels/mesh/mesh_queries.hpp"
#include "kernels/registration/fine.hpp"
#include "tests/kernels/registration/blob.hpp"
#include "tests/support/test_meshes.hpp"

namespace topotrack {
namespace {

using test::blob;
using test::mean_error;

// The blob pushed outwards by `offset` along its vertex normals and a target of the blob itself (a finer
// triangulation of the same shape): vertex i belongs at truth[i] = x_i - offset n_i, straight down its
// normal, so every tangential component of a fine step is slide.
struct OffsetCase {
  SurfaceMesh source;
  std::vector<Vec3> truth;
  TargetSurface target;
};

OffsetCase offset_case(double offset) {
  test::Soup src = blob(4);
  const SurfaceMesh exact = src.mesh();
  const std::vector<Vec3> n = vertex_normals(exact);
  std::vector<Vec3> truth = src.positions;
  for (std::size_t i = 0; i < src.positions.size(); ++i) src.positions[i] += offset * n[i];
  const test::Soup tgt = blob(5);
  return OffsetCase{src.mesh(), truth, TargetSurface(tgt.positions, tgt.triangles)};
}

double mean_distance(const SurfaceMesh& m, const TargetSurface& t) {
  double e = 0;
  for (const Vec3& p : m.positions()) e += t.closest_point(p).distance;
  return e / double(m.n_vertices());
}

FineParams normal_params() {
  FineParams p;
  p.normal_displacement = true;
  return p;
}

TEST(FineNormal, MovesOnlyAlongTheNormals) {
  OffsetCase c = offset_case(0.03);
  const std::vector<Vec3> before = c.source.positions();
  const std::vector<Vec3> n = vertex_normals(c.source);
  const FineReport r = align_fine(c.source, c.target, normal_params());
  EXPECT_EQ(r.pruned, 0u);
  EXPECT_LT(r.energy_end, r.energy_start);
  EXPECT_LT(r.residual, 1e-6);
  double moved = 0;
  for (std::size_t i = 0; i < before.size(); ++i) {
    const Vec3 step = c.source.positions()[i] - before[i];
    moved += step.norm();
    EXPECT_LT(step.cross(n[i]).norm(), 1e-12 * (1 + step.norm())) << "vertex " << i;
  }
  EXPECT_GT(moved / double(before.size()), 0.02);  // it did move (offset 0.03)
  c.source.validate();
}

// The vector form slides the vertices of the curved bumps sideways (the smoothness term averages neighbours'
// displacements of different directions); the normal form brings each vertex back where it belongs.
TEST(FineNormal, LessSlideThanVectorDisplacements) {
  OffsetCase vec = offset_case(0.03), nor = offset_case(0.03);
  const double diag = vec.target.bbox_diagonal();
  const double before = mean_error(vec.source, vec.truth);
  align_fine(vec.source, vec.target);
  align_fine(nor.source, nor.target, normal_params());
  const double e_vec = mean_error(vec.source, vec.truth), e_nor = mean_error(nor.source, nor.truth);
  EXPECT_LT(e_nor, 0.1 * before);
  EXPECT_LT(e_nor, 0.5 * e_vec) << "vector " << e_vec / diag << " normal " << e_nor / diag;
  // As close to the target as the vector form.
  EXPECT_LT(mean_distance(nor.source, nor.target), 1e-3 * diag);
  EXPECT_LT(mean_distance(nor.source, nor.target), 1.5 * mean_distance(vec.source, vec.target) + 1e-5 * diag);
}

// A rigid translation has a tangential part that normal rays cannot see: the normal form still reaches
// the target surface (the coarse stage, not this one, is there for tangential motion).
TEST(FineNormal, ReachesATranslatedTarget) {
  test::Soup src = blob(4);
  test::Soup tgt = blob(5);
  for (Vec3& p : tgt.positions) p += Vec3(0.02, -0.01, 0.015);
  SurfaceMesh mesh = src.mesh();
  const TargetSurface target(tgt.positions, tgt.triangles);
  const double diag = target.bbox_diagonal();
  const double before = mean_distance(mesh, target);
  const FineReport r = align_fine(mesh, target, normal_params());
  EXPECT_GT(r.correspondences, 0u);
  EXPECT_LT(mean_distance(mesh, target), 0.1 * before);
  EXPECT_LT(mean_distance(mesh, target), 1e-3 * diag);
}

TEST(FineNormal, OneAndTwoThreadsGiveIdenticalResults) {
  auto run = [](int threads, int rounds) {
    tbb::task_arena arena(threads);
    OffsetCase c = offset_case(0.03);
    FineParams p = normal_params();
    p.rounds = rounds;
    arena.execute([&] { align_fine(c.source, c.target, p); });
    return c.source.positions();
  };
  for (int rounds : {1, 2}) {
    const auto a = run(1, rounds), b = run(2, rounds);
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t i = 0; i < a.size(); ++i) ASSERT_EQ(a[i], b[i]) << "vertex " << i << " rounds " << rounds;
  }
}

TEST(FineNormal, PrunedComponentStays) {
  // A second sphere beyond sigma gets no correspondence and no displacement, as with vector displacements.
  test::FarSphereCase c = test::far_sphere_case();
  const std::vector<Vec3> before = c.mesh.positions();
  const FineReport r = align_fine(c.mesh, c.target, normal_params());
  test::expect_far_sphere_kept(c, before, r.pruned);
}

}  // namespace
}  // namespace topotrack
