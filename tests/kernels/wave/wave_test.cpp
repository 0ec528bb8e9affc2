// Tests of the cotangent Laplacian and the wave simulation of §5 (kernels/wave).
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <numbers>

#include "io/error.hpp"
#include "kernels/improve/improve.hpp"
#include "kernels/mesh/mesh_convert.hpp"
#include "kernels/wave/laplacian.hpp"
#include "kernels/wave/wave.hpp"
#include "tests/support/test_meshes.hpp"

namespace topotrack {
namespace {

std::vector<VertexId> sequential_ids(std::size_t n) {
  std::vector<VertexId> ids(n);
  for (std::size_t i = 0; i < n; ++i) ids[i] = i;
  return ids;
}

// A smooth bump of height `a` around the north pole.
WaveState bump_state(const test::Soup& s, double a) {
  WaveState st = zero_wave_state(sequential_ids(s.positions.size()));
  for (std::size_t i = 0; i < s.positions.size(); ++i) {
    const double d = (s.positions[i] - Vec3(0, 0, 1)).norm();
    st.h[i] = a * std::exp(-d * d / 0.1);
  }
  return st;
}

TEST(CotanLaplacian, ConstantsLinearAndSphereEigenvalue) {
  const test::Soup s = test::icosphere(4);
  const CotanLaplacian L = cotan_laplacian(s.positions, s.triangles);
  ASSERT_EQ(L.size(), s.positions.size());
  double area = 0;
  for (double m : L.mass) area += m;
  EXPECT_NEAR(area, 4 * std::numbers::pi, 0.02 * 4 * std::numbers::pi);
  std::vector<double> one(L.size(), 1.0), out(L.size());
  L.apply(one, out);
  for (double v : out) EXPECT_NEAR(v, 0.0, 1e-9);
  // z is a first spherical harmonic: -laplace z = 2 z on the unit sphere, so z^T C z / z^T M z = 2.
  std::vector<double> z(L.size());
  double zmz = 0;
  for (std::size_t i = 0; i < z.size(); ++i) {
    z[i] = s.positions[i].z();
    zmz += L.mass[i] * z[i] * z[i];
  }
  EXPECT_NEAR(L.dirichlet(z) / zmz, 2.0, 0.02);
  // Symmetric weights.
  for (std::size_t i = 0; i < L.size(); ++i)
    for (std::size_t k = L.row_begin[i]; k < L.row_begin[i + 1]; ++k) {
      const Index j = L.col[k];
      bool found = false;
      for (std::size_t q = L.row_begin[j]; q < L.row_begin[j + 1]; ++q)
        if (L.col[q] == i) {
          EXPECT_DOUBLE_EQ(L.weight[q], L.weight[k]);
          found = true;
        }
      EXPECT_TRUE(found);
    }
  std::vector<std::array<Index, 3>> bad = s.triangles;
  bad[3][2] = Index(s.positions.size());
  EXPECT_THROW(cotan_laplacian(s.positions, bad), InvalidInput);
}

TEST(CotanLaplacian, SliversKeepItPositiveAndStable) {
  // Pull a vertex almost onto its neighbour: its triangles become slivers with huge cotangents.
  test::Soup s = test::icosphere(3);
  const auto t0 = s.triangles[0];
  s.positions[t0[0]] = s.positions[t0[1]] + 1e-7 * (s.positions[t0[2]] - s.positions[t0[1]]);
  const CotanLaplacian L = cotan_laplacian(s.positions, s.triangles);
  std::vector<double> h(L.size());
  for (int trial = 0; trial < 20; ++trial) {
    for (std::size_t i = 0; i < h.size(); ++i) h[i] = std::sin(12.9898 * (i + 1) * (trial + 1));
    EXPECT_GE(L.dirichlet(h), -1e-9);
  }
  WaveParams p;
  EXPECT_LT(stable_substeps(L, p), 400);
  WaveState st = bump_state(s, 0.05);
  const double e0 = wave_energy(L, st, p.speed);
  WaveReport rep;
  for (int f = 0; f < 30; ++f) integrate_waves(L, st, p, &rep);
  EXPECT_LT(std::abs(rep.energy_after - e0) / e0, 0.05);
}

TEST(Wave, EnergyConservedWithoutDamping) {
  const test::Soup s = test::icosphere(3);
  const CotanLaplacian L = cotan_laplacian(s.positions, s.triangles);
  WaveState st = bump_state(s, 0.05);
  WaveParams p;
  p.speed = 1.0;
  p.frame_time = 1.0 / 30;
  p.cfl_safety = 0.02;  // small dt
  const double e0 = wave_energy(L, st, p.speed);
  ASSERT_GT(e0, 0);
  double worst = 0;
  WaveReport rep;
  for (int frame = 0; frame < 60; ++frame) {
    integrate_waves(L, st, p, &rep);
    worst = std::max(worst, std::abs(rep.energy_after - e0) / e0);
  }
  EXPECT_GT(rep.substeps, 1);
  EXPECT_LT(worst, 0.01) << "relative energy drift " << worst;
  RecordProperty("energy_drift", std::to_string(worst));
  std::printf("[ wave ] relative energy drift over 60 frames (%d sub-steps each): %.3e\n", rep.substeps, worst);
  // The wave has moved: the bump spread out.
  EXPECT_LT(rep.max_abs_height, 0.05);
  // Damping removes energy.
  WaveState damped = st;
  p.damping = 0.01;
  const double before = wave_energy(L, damped, p.speed);
  for (int frame = 0; frame < 10; ++frame) integrate_waves(L, damped, p, &rep);
  EXPECT_LT(rep.energy_after, 0.5 * before);
}

TEST(Wave, ZeroEverywhereWithoutTopologyEvents) {
  // Real re-sampling events from mesh improvement (splits and collapses, no topology patches).
  test::Soup s = test::icosphere(2);
  test::jitter(s, 0.02, 3);
  SurfaceMesh mesh = s.mesh();
  WaveState st = zero_wave_state(mesh.ids());
  EventList events;
  ImproveParams ip;
  ip.target_edge_length = 0.5 * mean_edge_length(mesh);
  const ImproveReport ir = improve_mesh(mesh, ip, &events);
  ASSERT_GT(ir.splits, 0u);
  ASSERT_GT(events.size(), 0u);
  WaveParams p;
  p.inject_height = 0.1;
  p.inject_velocity = 1.0;
  WaveReport rep;
  st = transfer_wave_state(st, events, mesh.ids(), p, &rep);
  EXPECT_EQ(rep.injected, 0u);
  EXPECT_EQ(rep.missing, 0u);
  std::vector<Vec3> pos;
  std::vector<std::array<Index, 3>> tris;
  extract_triangles(mesh, pos, tris);
  for (int f = 0; f < 5; ++f) integrate_waves(pos, tris, st, p, &rep);
  for (double h : st.h) EXPECT_EQ(h, 0.0);
  for (double v : st.v) EXPECT_EQ(v, 0.0);
}

TEST(Wave, EnergyInjectedAtTopologyPatchesOnly) {
  // Frame n-1: an icosphere with ids 0..n-1. Event: a patch deleting vertex 0 and re-creating it as a new
  // vertex (id n) from its one-ring, as the topology stage of §4.3 records it.
  const test::Soup s = test::icosphere(3);
  const std::size_t n = s.positions.size();
  const WaveState st = zero_wave_state(sequential_ids(n));
  std::vector<Index> ring;
  for (const auto& t : s.triangles)
    for (int k = 0; k < 3; ++k)
      if (t[k] == 0) ring.push_back(t[(k + 1) % 3]);
  EventList ev;
  ev.begin_event(EventKind::PatchDelete);
  ev.add_in(0);
  for (Index r : ring) ev.add_in(r);
  for (Index r : ring) ev.add_out(r);
  std::vector<RuleTerm> terms;
  for (Index r : ring) terms.push_back({r, 1.0 / ring.size()});
  ev.add_backward_rule(0, terms);
  ev.end_event();
  ev.begin_event(EventKind::PatchCreate);
  for (Index r : ring) ev.add_in(r);
  for (Index r : ring) ev.add_out(r);
  ev.add_out(n);
  ev.add_forward_rule(n, terms);
  ev.end_event();
  std::vector<VertexId> next = sequential_ids(n);
  next[0] = n;  // same geometry, the vertex at index 0 is the new one
  WaveParams p;
  p.inject_height = 0.02;
  WaveReport rep;
  WaveState out = transfer_wave_state(st, ev, next, p, &rep);
  EXPECT_EQ(rep.injected, 1u);
  EXPECT_EQ(rep.missing, 0u);
  EXPECT_FLOAT_EQ(float(out.h[0]), 0.02f);
  for (std::size_t i = 1; i < n; ++i) EXPECT_EQ(out.h[i], 0.0);
  integrate_waves(s.positions, s.triangles, out, p, &rep);
  EXPECT_GT(rep.energy_before, 0);
  // The wave spreads to the neighbours.
  for (Index r : ring) EXPECT_NE(out.h[r], 0.0);
  // Without injection the same events carry zeros.
  p.inject_height = 0;
  out = transfer_wave_state(st, ev, next, p, &rep);
  for (double h : out.h) EXPECT_EQ(h, 0.0);
}

TEST(Wave, DeterministicAcrossThreadCounts) {
  const test::Soup s = test::icosphere(5);
  const WaveState start = bump_state(s, 0.05);
  auto run = [&](int threads) {
    WaveState st = start;
    tbb::task_arena arena(threads);
    arena.execute([&] {
      for (int f = 0; f < 3; ++f) integrate_waves(s.positions, s.triangles, st, {});
    });
    return st;
  };
  const WaveState a = run(1), b = run(2);
  EXPECT_EQ(a.h, b.h);
  EXPECT_EQ(a.v, b.v);
}

TEST(Wave, RejectsBadInput) {
  const test::Soup s = test::icosphere(1);
  WaveState st = zero_wave_state(sequential_ids(s.positions.size()));
  WaveParams p;
  p.damping = 1.5;
  EXPECT_THROW(integrate_waves(s.positions, s.triangles, st, p), InvalidInput);
  p = {};
  p.speed = -1;
  EXPECT_THROW(integrate_waves(s.positions, s.triangles, st, p), InvalidInput);
  WaveState wrong = st;
  wrong.h.pop_back();
  EXPECT_THROW(integrate_waves(s.positions, s.triangles, wrong, {}), InvalidInput);
  WaveState shorter = zero_wave_state(sequential_ids(5));
  EXPECT_THROW(integrate_waves(s.positions, s.triangles, shorter, {}), InvalidInput);
  WaveState dup = st;
  dup.ids[1] = dup.ids[0];
  EXPECT_THROW(transfer_wave_state(dup, EventList{}, st.ids, {}), InvalidInput);
  std::vector<double> h(s.positions.size() - 1, 0.0);
  EXPECT_THROW(displace_along_normals(s.positions, s.triangles, h), InvalidInput);
}

TEST(Wave, DisplacementAlongNormals) {
  const test::Soup s = test::icosphere(3);
  std::vector<double> h(s.positions.size(), 0.1);
  const std::vector<Vec3> out = displace_along_normals(s.positions, s.triangles, h, 2.0);
  for (const Vec3& q : out) EXPECT_NEAR(q.norm(), 1.2, 0.01);
}

}  // namespace
}  // namespace topotrack
