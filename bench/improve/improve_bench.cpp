// Benchmarks of improve_mesh (§4.1): a marching-tetrahedra torus (slivers, needles and near-zero edges
// as iso-surface extraction makes them) at several sizes, a marching-cubes torus (kernels/gen, what `gen`
// and the tracker's resurfacing make), and the already-good case the tracker hits most (a mesh that
// improve_mesh produced, improved again: a parallel scan and nothing else).
// Run: improve_bench --benchmark_format=json
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <map>
#include <memory>

#include "bench/improve/improve_bench.hpp"
#include "kernels/gen/implicit_grid.hpp"
#include "kernels/improve/improve.hpp"
#include "kernels/mesh/mesh_convert.hpp"
#include "tests/kernels/improve/implicit_mesh.hpp"

namespace topotrack {
namespace {

//! The torus mesh on an n^3 grid (about 7.4 n^2 vertices), built once per size.
const SurfaceMesh& torus(int n) {
  static std::map<int, std::unique_ptr<SurfaceMesh>> cache;
  auto& m = cache[n];
  if (!m) m = std::make_unique<SurfaceMesh>(test::mt_torus(n).mesh());
  return *m;
}

//! The torus (R = 1, r = 0.4) by marching cubes at voxel size 1.65 / n (n = 100: about 100k vertices).
const SurfaceMesh& mc_torus(int n) {
  static std::map<int, std::unique_ptr<SurfaceMesh>> cache;
  auto& m = cache[n];
  if (!m) {
    const auto f = [](const Vec3& p) {
      const double q = std::sqrt(p.x() * p.x() + p.y() * p.y()) - 1.0;
      return std::sqrt(q * q + p.z() * p.z()) - 0.4;
    };
    m = std::make_unique<SurfaceMesh>(
        to_surface_mesh(mesh_implicit(f, {Vec3(-1.5, -1.5, -0.5), Vec3(1.5, 1.5, 0.5)}, 1.65 / n)));
  }
  return *m;
}

void run_improve(benchmark::State& state, const SurfaceMesh& in) {
  const tbb::global_control threads(tbb::global_control::max_allowed_parallelism, std::size_t(state.range(1)));
  bench::time_improve(state, in);
  SurfaceMesh m = in.clone();
  ImproveParams params;
  params.measure_quality = true;
  const ImproveReport r = improve_mesh(m, params);
  bench::improve_counters(state, in, r);
  state.counters["min_angle_deg"] = r.quality.min_angle_deg;
  state.counters["share_below_10deg"] = r.quality.share_below_10deg;
  state.counters["below_2deg"] = double(r.quality.below_2deg);
}

void BM_ImproveMarchingTets(benchmark::State& state) { run_improve(state, torus(int(state.range(0)))); }
void BM_ImproveMarchingCubes(benchmark::State& state) { run_improve(state, mc_torus(int(state.range(0)))); }
void BM_ImproveAlreadyGood(benchmark::State& state) {
  bench::time_already_good(state, torus(int(state.range(0))), int(state.range(1)));
}

// Args: grid size n (n = 116: 100k vertices), threads.
BENCHMARK(BM_ImproveMarchingTets)
    ->Args({30, 2})
    ->Args({60, 2})
    ->Args({116, 1})
    ->Args({116, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
// Args: n (voxel size 1.65 / n; n = 100: 100k vertices), threads.
BENCHMARK(BM_ImproveMarchingCubes)->Args({100, 1})->Args({100, 2})->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_ImproveAlreadyGood)->Args({60, 2})->Args({116, 1})->Args({116, 2})->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace topotrack

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
