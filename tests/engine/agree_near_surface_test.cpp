// The tracker's topology tolerance: φ_S takes φ_M's sign near both surfaces, but never as a component of
// its own (a sub-voxel crumb or bubble of M stays a topology difference for ConstrainTopology(M, φ_S)).
#include "engine/agree_near_surface.hpp"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <array>
#include <cstdlib>
#include <functional>
#include <random>
#include <set>
#include <vector>

namespace topotrack {
namespace {

constexpr float kFieldVoxel = 0.1f;
constexpr double kTolerance = 0.5 * kFieldVoxel;
const openvdb::CoordBBox kBox(openvdb::Coord(-6), openvdb::Coord(6));

openvdb::FloatGrid::Ptr field(const std::function<float(const openvdb::Coord&)>& f) {
  openvdb::initialize();
  auto grid = openvdb::FloatGrid::create(3 * kFieldVoxel);
  grid->setTransform(openvdb::math::Transform::createLinearTransform(kFieldVoxel));
  grid->setGridClass(openvdb::GRID_LEVEL_SET);
  auto acc = grid->getAccessor();
  for (auto it = kBox.begin(); it; ++it) acc.setValue(*it, f(*it));
  return grid;
}

float at(const openvdb::FloatGrid& g, int x, int y, int z) {
  return g.tree().getValue(openvdb::Coord(x, y, z));
}

TEST(AgreeNearSurface, AlignedSurfacesTakeMsSignsNearBoth) {
  // Two parallel planes 0.6 voxels apart: the nodes between them flip, the others keep their values.
  auto s = field([](const openvdb::Coord& c) { return (float(c.z()) - 0.3f) * kFieldVoxel; });
  const auto m = field([](const openvdb::Coord& c) { return (float(c.z()) + 0.3f) * kFieldVoxel; });
  agree_near_surface(*s, *m, kTolerance);
  for (int x = -5; x <= 5; ++x)
    for (int y = -5; y <= 5; ++y) {
      EXPECT_FLOAT_EQ(at(*s, x, y, 0), 0.3f * kFieldVoxel);  // was -0.3 voxel: takes φ_M's value
      EXPECT_FLOAT_EQ(at(*s, x, y, 1), 0.7f * kFieldVoxel);
      EXPECT_FLOAT_EQ(at(*s, x, y, -1), -1.3f * kFieldVoxel);
    }
}

TEST(AgreeNearSurface, ASlabSeveralNodesThickFlipsWhole) {
  // Planes five voxels apart (a finer lattice's view of M and S one coarse voxel apart): the nodes between
  // them are simple only once those nearer M's side have flipped, and all of them flip.
  auto s = field([](const openvdb::Coord& c) { return (float(c.z()) - 2.5f) * kFieldVoxel; });
  const auto m = field([](const openvdb::Coord& c) { return (float(c.z()) + 2.5f) * kFieldVoxel; });
  agree_near_surface(*s, *m, 5 * kFieldVoxel);
  for (int x = -4; x <= 4; ++x)
    for (int y = -4; y <= 4; ++y)
      for (int z = -4; z <= 4; ++z) {
        const float want = z >= -2 && z <= 2 ? (float(z) + 2.5f) * kFieldVoxel : (float(z) - 2.5f) * kFieldVoxel;
        EXPECT_FLOAT_EQ(at(*s, x, y, z), want) << x << " " << y << " " << z;
      }
}

TEST(AgreeNearSurface, IsolatedNodesOfMStayADifference) {
  // φ_S is outside (but near its surface) everywhere; φ_M has a one-node and a two-node crumb inside.
  const auto outside = [](const openvdb::Coord&) { return 0.4f * kFieldVoxel; };
  auto s = field(outside);
  const auto m = field([](const openvdb::Coord& c) {
    if (c == openvdb::Coord(0, 0, 0) || c == openvdb::Coord(3, 3, 3) || c == openvdb::Coord(4, 3, 3))
      return -0.2f * kFieldVoxel;
    return 0.4f * kFieldVoxel;
  });
  agree_near_surface(*s, *m, kTolerance);
  for (auto it = kBox.begin(); it; ++it) EXPECT_FLOAT_EQ(s->tree().getValue(*it), 0.4f * kFieldVoxel) << *it;

  // The same for a bubble: an outside node of φ_M where φ_S is inside all around.
  auto s_in = field([](const openvdb::Coord&) { return -0.4f * kFieldVoxel; });
  const auto m_bubble = field(
      [](const openvdb::Coord& c) { return c == openvdb::Coord(1, 2, 3) ? 0.1f * kFieldVoxel : -0.4f * kFieldVoxel; });
  agree_near_surface(*s_in, *m_bubble, kTolerance);
  EXPECT_FLOAT_EQ(at(*s_in, 1, 2, 3), -0.4f * kFieldVoxel);
}

TEST(AgreeNearSurface, ThinPartIsNeitherCutNorPierced) {
  // φ_S: a sheet one node thick (z = 0). φ_M has the sheet but outside on the ring of 8 nodes around the
  // origin, as where M's fold lies half a voxel off: taking every flip would leave the origin a crumb, and
  // each single flip would pierce the sheet (a handle). None is taken; the 2-thick sheet's flips are.
  auto s = field([](const openvdb::Coord& c) { return c.z() == 0 ? -0.2f * kFieldVoxel : 0.8f * kFieldVoxel; });
  const auto m = field([](const openvdb::Coord& c) {
    const bool ring = c.z() == 0 && std::abs(c.x()) <= 1 && std::abs(c.y()) <= 1 && c != openvdb::Coord(0);
    return ring ? 0.2f * kFieldVoxel : (c.z() == 0 ? -0.2f * kFieldVoxel : 0.8f * kFieldVoxel);
  });
  agree_near_surface(*s, *m, kTolerance);
  int flipped = 0;
  for (int x = -1; x <= 1; ++x)
    for (int y = -1; y <= 1; ++y) flipped += at(*s, x, y, 0) > 0;
  EXPECT_EQ(flipped, 0);
  // The inside stays one 6-connected sheet: flood it from a far corner and reach the origin.
  std::set<std::array<int, 2>> seen{{-6, -6}};
  std::vector<std::array<int, 2>> todo{{-6, -6}};
  while (!todo.empty()) {
    const auto [x, y] = todo.back();
    todo.pop_back();
    for (const auto& [dx, dy] : {std::array<int, 2>{1, 0}, {-1, 0}, {0, 1}, {0, -1}}) {
      const std::array<int, 2> q{x + dx, y + dy};
      if (std::abs(q[0]) > 6 || std::abs(q[1]) > 6 || seen.count(q) || at(*s, q[0], q[1], 0) >= 0) continue;
      seen.insert(q);
      todo.push_back(q);
    }
  }
  EXPECT_TRUE(seen.count({0, 0}));
  EXPECT_EQ(int(seen.size()), 13 * 13);

  auto thick = field(
      [](const openvdb::Coord& c) { return c.z() == 0 || c.z() == 1 ? -0.2f * kFieldVoxel : 0.8f * kFieldVoxel; });
  agree_near_surface(*thick, *m, kTolerance);
  for (int x = -1; x <= 1; ++x)
    for (int y = -1; y <= 1; ++y) EXPECT_EQ(at(*thick, x, y, 0) > 0, x != 0 || y != 0);  // a dent, no crumb
}

TEST(AgreeNearSurface, NodeNextToSsOwnSignIsTaken) {
  // The crumb's node touches a region of φ_S with its sign: the flip only moves S's surface by a node.
  auto s = field(
      [](const openvdb::Coord& c) { return c == openvdb::Coord(-1, 0, 0) ? -0.1f * kFieldVoxel : 0.4f * kFieldVoxel; });
  const auto m = field([](const openvdb::Coord& c) {
    if (c == openvdb::Coord(0, 0, 0)) return -0.2f * kFieldVoxel;
    return c == openvdb::Coord(-1, 0, 0) ? -0.1f * kFieldVoxel : 0.4f * kFieldVoxel;
  });
  agree_near_surface(*s, *m, kTolerance);
  EXPECT_FLOAT_EQ(at(*s, 0, 0, 0), -0.2f * kFieldVoxel);
  EXPECT_FLOAT_EQ(at(*s, -1, 0, 0), -0.1f * kFieldVoxel);

  // An isolated inside node of φ_S (an input part thinner than a voxel) that φ_M has outside stays: taking
  // φ_M's sign there would remove a component of S.
  auto s2 = field(
      [](const openvdb::Coord& c) { return c == openvdb::Coord(-1, 0, 0) ? -0.1f * kFieldVoxel : 0.4f * kFieldVoxel; });
  const auto m2 = field([](const openvdb::Coord&) { return 0.4f * kFieldVoxel; });
  agree_near_surface(*s2, *m2, kTolerance);
  EXPECT_FLOAT_EQ(at(*s2, -1, 0, 0), -0.1f * kFieldVoxel);
}

TEST(AgreeNearSurface, DifferencesBeyondTheToleranceAreUntouched) {
  auto s = field([](const openvdb::Coord& c) { return (float(c.z()) - 0.3f) * kFieldVoxel; });
  const auto m = field([](const openvdb::Coord& c) { return (float(c.z()) + 0.6f) * kFieldVoxel; });
  agree_near_surface(*s, *m, kTolerance);  // φ_M at z = 0 is 0.6 voxel: beyond 0.5
  EXPECT_FLOAT_EQ(at(*s, 0, 0, 0), -0.3f * kFieldVoxel);
  EXPECT_FLOAT_EQ(at(*s, 0, 0, -1), -1.3f * kFieldVoxel);
}

TEST(AgreeNearSurface, DeterministicAcrossThreadCounts) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-kFieldVoxel, kFieldVoxel);
  std::vector<float> vs, vm;
  for (auto it = kBox.begin(); it; ++it) {
    vs.push_back(u(rng));
    vm.push_back(u(rng));
  }
  auto run = [&](int threads) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    std::size_t i = 0, j = 0;
    auto s = field([&](const openvdb::Coord&) { return vs[i++]; });
    const auto m = field([&](const openvdb::Coord&) { return vm[j++]; });
    agree_near_surface(*s, *m, kTolerance);
    std::vector<float> out;
    for (auto it = kBox.begin(); it; ++it) out.push_back(s->tree().getValue(*it));
    return out;
  };
  const auto one = run(1), two = run(2);
  EXPECT_EQ(one, two);
  std::size_t changed = 0;
  for (std::size_t k = 0; k < one.size(); ++k) changed += one[k] != vs[k];
  EXPECT_GT(changed, 0u);  // the random fields do exercise the rule
}

}  // namespace
}  // namespace topotrack
