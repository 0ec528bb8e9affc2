// The spatial queries of the alignment (§4.2), over 10k..400k vertices so their growth with size is visible:
// kd-tree build and nearest-point queries (nanoflann), Embree BVH build, undirected normal ray casts and
// closest-point queries onto a target surface. The target is a slightly perturbed copy of the source torus,
// as between consecutive frames of a sequence.
#include <benchmark/benchmark.h>

#include <cmath>

#include "kernels/raycast/target_surface.hpp"
#include "kernels/spatial/point_index.hpp"
#include "tests/support/test_meshes.hpp"

namespace topotrack {
namespace {

// A torus of about `vertices` vertices (n x m grid, n = 3m) and vertex normals of the ideal torus.
struct Scene {
  test::Soup source, target;
  std::vector<Vec3> normals;
  double diagonal = 0;
};

Scene make_scene(std::int64_t vertices) {
  const int m = std::max(8, int(std::sqrt(double(vertices) / 3.0)));
  const int n = int(vertices / m);
  Scene s;
  s.source = test::torus(n, m);
  s.target = s.source;
  test::jitter(s.target, 0.2 * 2 * 3.14159 * 0.35 / m, /*seed=*/7);
  for (const Vec3& p : s.source.positions) {
    const Vec3 ring = Vec3(p.x(), p.y(), 0).normalized();
    s.normals.push_back((p - ring).normalized());
  }
  s.diagonal = std::sqrt(2.7 * 2.7 + 2.7 * 2.7 + 0.7 * 0.7);
  return s;
}

void counters(benchmark::State& state, const Scene& s) {
  state.counters["vertices"] = double(s.source.positions.size());
  state.SetItemsProcessed(std::int64_t(state.iterations()) * std::int64_t(s.source.positions.size()));
}

void BM_KdTreeBuild(benchmark::State& state) {
  const Scene s = make_scene(state.range(0));
  for (auto _ : state) {
    PointIndex index(s.target.positions);
    benchmark::DoNotOptimize(index);
  }
  counters(state, s);
}

void BM_KdTreeNearest(benchmark::State& state) {
  const Scene s = make_scene(state.range(0));
  const PointIndex index(s.target.positions);
  for (auto _ : state) benchmark::DoNotOptimize(index.nearest(s.source.positions));
  counters(state, s);
}

void BM_EmbreeBuild(benchmark::State& state) {
  const Scene s = make_scene(state.range(0));
  for (auto _ : state) {
    TargetSurface target(s.target.positions, s.target.triangles);
    benchmark::DoNotOptimize(target);
  }
  counters(state, s);
}

void BM_EmbreeUndirectedRays(benchmark::State& state) {
  const Scene s = make_scene(state.range(0));
  const TargetSurface target(s.target.positions, s.target.triangles);
  for (auto _ : state)
    benchmark::DoNotOptimize(target.cast_undirected(s.source.positions, s.normals, 0.1 * s.diagonal));
  counters(state, s);
}

void BM_EmbreeClosestPoints(benchmark::State& state) {
  const Scene s = make_scene(state.range(0));
  const TargetSurface target(s.target.positions, s.target.triangles);
  for (auto _ : state) benchmark::DoNotOptimize(target.closest_points(s.source.positions));
  counters(state, s);
}

#define TT_SIZES ->Arg(10000)->Arg(40000)->Arg(100000)->Arg(400000)->Unit(benchmark::kMillisecond)->UseRealTime()
BENCHMARK(BM_KdTreeBuild) TT_SIZES;
BENCHMARK(BM_KdTreeNearest) TT_SIZES;
BENCHMARK(BM_EmbreeBuild) TT_SIZES;
BENCHMARK(BM_EmbreeUndirectedRays) TT_SIZES;
BENCHMARK(BM_EmbreeClosestPoints) TT_SIZES;
#undef TT_SIZES

}  // namespace
}  // namespace topotrack

BENCHMARK_MAIN();
