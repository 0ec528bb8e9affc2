// Benchmarks of improve_mesh (§4.1): a marching-tetrahedra torus (slivers, needles and near-zero edges
// as iso-surface extraction makes them) at several sizes, a marching-cubes torus (kernels/gen, what `gen`
// and the tracker's resurfacing make), and the already-good case the tracker hits most (a mesh that
// improve_mesh produced, improved again: a parallel scan and nothing else).
// Run: improve_bench --benchmark_format=json
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <sys/resource.h>

#include <map>
#include <memory>

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

//! CPU seconds of all threads of the process so far: on a shared machine wall time also counts waiting.
double process_cpu_seconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) + 1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

void set_counters(benchmark::State& state, const SurfaceMesh& in, const ImproveReport& r) {
  state.counters["vertices_in"] = double(in.n_vertices());
  state.counters["splits"] = double(r.splits);
  state.counters["collapses"] = double(r.collapses);
  state.counters["flips"] = double(r.flips);
  state.counters["iterations"] = r.iterations;
  state.counters["min_angle_deg"] = r.quality.min_angle_deg;
  state.counters["share_below_10deg"] = r.quality.share_below_10deg;
  state.counters["below_2deg"] = double(r.quality.below_2deg);
  state.counters["s_scan"] = r.seconds_scan;
  state.counters["s_split"] = r.seconds_split;
  state.counters["s_collapse"] = r.seconds_collapse;
  state.counters["s_bad"] = r.seconds_bad_triangles;
  state.counters["s_fold"] = r.seconds_folds;
  state.counters["s_finish"] = r.seconds_finish;
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
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism, std::size_t(state.range(1)));
  ImproveParams params;
  params.measure_quality = false;
  ImproveReport r;
  double cpu = 0;
  for (auto _ : state) {
    state.PauseTiming();
    SurfaceMesh m = in.clone();
    EventList events;
    const double c0 = process_cpu_seconds();
    state.ResumeTiming();
    r = improve_mesh(m, params, &events);
    cpu += process_cpu_seconds() - c0;
    benchmark::DoNotOptimize(events.size());
    state.PauseTiming();
    m = SurfaceMesh();
    state.ResumeTiming();
  }
  state.counters["cpu_seconds_all_threads"] = cpu / double(state.iterations());
  SurfaceMesh m = in.clone();
  params.measure_quality = true;
  set_counters(state, in, improve_mesh(m, params));
}

void BM_ImproveMarchingTets(benchmark::State& state) { run_improve(state, torus(int(state.range(0)))); }
void BM_ImproveMarchingCubes(benchmark::State& state) { run_improve(state, mc_torus(int(state.range(0)))); }

void BM_ImproveAlreadyGood(benchmark::State& state) {
  SurfaceMesh good = torus(int(state.range(0))).clone();
  const ImproveReport first = improve_mesh(good);
  ImproveParams params;
  params.measure_quality = false;
  params.target_edge_length = std::sqrt(first.min_edge_length * first.max_edge_length);
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism, std::size_t(state.range(1)));
  double cpu = 0;
  for (auto _ : state) {
    EventList events;
    const double c0 = process_cpu_seconds();
    const ImproveReport r = improve_mesh(good, params, &events);
    cpu += process_cpu_seconds() - c0;
    if (!events.empty() || r.splits + r.collapses + r.flips > 0) state.SkipWithError("an already-good mesh was changed");
  }
  state.counters["cpu_seconds_all_threads"] = cpu / double(state.iterations());
  state.counters["vertices_in"] = double(good.n_vertices());
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
