// Global rigid pre-alignment by trimmed ICP (our addition before §4.2's coarse stage).
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <limits>
#include <numbers>

#include "kernels/registration/rigid_icp.hpp"
#include "tests/kernels/registration/blob.hpp"

namespace topotrack {
namespace {

Eigen::Matrix3d rotation(double deg, const Vec3& axis) {
  return Eigen::AngleAxisd(deg * std::numbers::pi / 180, axis.normalized()).toRotationMatrix();
}

// Source: the blob; target: a finer tessellation of it moved by (R, t).
struct Case {
  SurfaceMesh source;
  std::vector<Vec3> truth;
  TargetSurface target;
};

Case make_case(const Eigen::Matrix3d& R, const Vec3& t) {
  const test::Soup src = test::blob(4);
  test::Soup tgt = test::blob(5);
  std::vector<Vec3> truth;
  for (const Vec3& p : src.positions) truth.push_back(R * p + t);
  for (Vec3& p : tgt.positions) p = R * p + t;
  return Case{src.mesh(), truth, TargetSurface(tgt.positions, tgt.triangles)};
}

using test::mean_error;

TEST(RigidIcp, RecoversLargeRigidMotion) {
  const Eigen::Matrix3d R = rotation(60, Vec3(0.3, 1, 0.2));
  const Vec3 t(0.8, -0.4, 0.3);
  Case c = make_case(R, t);
  const double diag = c.target.bbox_diagonal();
  const double before = mean_error(c.source, c.truth);
  const RigidIcpReport r = align_rigid(c.source, c.target);
  EXPECT_TRUE(r.applied);
  EXPECT_GT(r.iterations, 1);
  EXPECT_EQ(r.samples, (c.source.n_vertices() + 2) / 3);  // every third of 2562 vertices: at most max_samples
  EXPECT_LT(r.distance_end, 0.05 * r.distance_start);
  EXPECT_LT((r.rotation - R).norm(), 0.02);
  EXPECT_LT((r.translation - t).norm(), 0.01 * diag);
  EXPECT_LT(mean_error(c.source, c.truth), 0.005 * diag) << "before " << before / diag;
  c.source.validate();
}

// RigidIcpParams::axes_win_ratio: a turn beyond ICP's reach from the identity and the centroids is found from the
// principal axes matched; without those starts it is not; and where the two starts already fit, the axes' end (the
// same pose, about as close) does not replace theirs.
TEST(RigidIcp, PrincipalAxesStartsFindATurnBeyondIcpsReach) {
  const Eigen::Matrix3d R = rotation(160, Vec3(0.3, 1, 0.2));
  const Vec3 t(1.5, -0.8, 0.6);
  // The blob made lopsided along distinct axes (a symmetric shape fits turned as well as in place).
  const auto shape = [](const Vec3& p) { return Vec3(1.8 * p.x() + 0.4 * p.y() * p.y(), p.y() + 0.3 * p.z() * p.z(), 0.6 * p.z()); };
  const test::Soup src = test::blob(4);
  test::Soup tgt = test::blob(5);
  std::vector<Vec3> truth, source_positions;
  for (const Vec3& q : src.positions) {
    source_positions.push_back(shape(q));
    truth.push_back(R * shape(q) + t);
  }
  for (Vec3& q : tgt.positions) q = R * shape(q) + t;
  test::Soup moved = src;
  moved.positions = source_positions;
  Case c{moved.mesh(), truth, TargetSurface(tgt.positions, tgt.triangles)};
  const double diag = c.target.bbox_diagonal();
  RigidIcpParams p;
  p.axes_win_ratio = 0;
  SurfaceMesh without = c.source.clone();
  const RigidIcpReport r0 = align_rigid(without, c.target, p);
  EXPECT_EQ(r0.axes_starts, 0);
  EXPECT_GT(mean_error(without, c.truth), 0.05 * diag);  // the two starts settle on a wrong pose
  const RigidIcpReport r = align_rigid(c.source, c.target);
  EXPECT_EQ(r.axes_starts, 4);
  EXPECT_TRUE(r.axes_won);
  EXPECT_LT(r.distance_end, r0.distance_end);
  EXPECT_LT((r.rotation - R).norm(), 0.02);
  EXPECT_LT(mean_error(c.source, c.truth), 0.005 * diag);
  // A pair the two starts already fit keeps their end, bit for bit.
  Case d = make_case(rotation(60, Vec3(0.3, 1, 0.2)), Vec3(0.8, -0.4, 0.3));
  SurfaceMesh d0 = d.source.clone();
  align_rigid(d0, d.target, p);
  const RigidIcpReport rd = align_rigid(d.source, d.target);
  EXPECT_EQ(rd.axes_starts, 4);
  EXPECT_FALSE(rd.axes_won);
  EXPECT_EQ(d.source.positions(), d0.positions());
  EXPECT_LT(mean_error(d.source, d.truth), 0.005 * c.target.bbox_diagonal());
}

TEST(RigidIcp, AlignedInputIsLeftInPlace) {
  Case c = make_case(Eigen::Matrix3d::Identity(), Vec3::Zero());
  const std::vector<Vec3> start = c.source.positions();
  const RigidIcpReport r = align_rigid(c.source, c.target);
  // The two tessellations differ, so ICP may find a tiny improvement; it never moves far.
  EXPECT_LE(r.distance_end, r.distance_start);
  EXPECT_LT(mean_error(c.source, start), 1e-3 * c.target.bbox_diagonal());
  EXPECT_NEAR(trimmed_mean_distance(c.source, c.target), r.distance_end, 1e-12);
}

TEST(RigidIcp, OneAndTwoThreadsGiveIdenticalResults) {
  auto run = [](int threads) {
    tbb::task_arena arena(threads);
    std::vector<Vec3> out;
    arena.execute([&] {
      Case c = make_case(rotation(40, Vec3(1, 0, 1)), Vec3(0.3, 0.2, -0.5));
      align_rigid(c.source, c.target);
      out = c.source.positions();
    });
    return out;
  };
  const std::vector<Vec3> a = run(1), b = run(2);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) ASSERT_EQ(a[i], b[i]) << "vertex " << i;
}

TEST(RigidIcp, BadInputThrows) {
  Case c = make_case(Eigen::Matrix3d::Identity(), Vec3::Zero());
  RigidIcpParams p;
  p.trim_fraction = 0;
  EXPECT_THROW(align_rigid(c.source, c.target, p), InvalidInput);
  EXPECT_THROW(trimmed_mean_distance(c.source, c.target, p), InvalidInput);
  p = RigidIcpParams{};
  p.trim_fraction = 1.5;
  EXPECT_THROW(align_rigid(c.source, c.target, p), InvalidInput);
  p = RigidIcpParams{};
  p.max_samples = 2;
  EXPECT_THROW(align_rigid(c.source, c.target, p), InvalidInput);
  p = RigidIcpParams{};
  p.tolerance = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(align_rigid(c.source, c.target, p), InvalidInput);
  for (const double ratio : {-0.1, 1.5, std::numeric_limits<double>::quiet_NaN()}) {
    p = RigidIcpParams{};
    p.axes_win_ratio = ratio;
    EXPECT_THROW(align_rigid(c.source, c.target, p), InvalidInput) << ratio;
  }
  SurfaceMesh empty;
  EXPECT_THROW(align_rigid(empty, c.target), InvalidInput);
  c.source.positions()[0] = Vec3(std::nan(""), 0, 0);
  EXPECT_THROW(align_rigid(c.source, c.target), InvalidInput);
}

}  // namespace
}  // namespace topotrack
