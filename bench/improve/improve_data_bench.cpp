// improve_mesh (§4.1) on marching-cubes output of real data: an elephant frame re-meshed through its
// signed distance (kernels/sdf), about 100k vertices, as the tracker's first ImproveMesh sees it, and the
// same mesh improved once more (the already-good case of Algorithm 1, lines 7 and 12).
// Run: improve_data_bench --benchmark_format=json
#include <benchmark/benchmark.h>
#include <sys/resource.h>
#include <tbb/global_control.h>

#include <filesystem>
#include <memory>

#include "io/mesh_reader.hpp"
#include "kernels/improve/improve.hpp"
#include "kernels/mesh/mesh_convert.hpp"
#include "kernels/sdf/marching_cubes.hpp"
#include "kernels/sdf/signed_distance.hpp"

namespace topotrack {
namespace {

double process_cpu_seconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) + 1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

//! The elephant's first frame re-meshed at voxel size diag / cells (null when the data is absent).
const SurfaceMesh* resurfaced_elephant(int cells) {
  static std::unique_ptr<SurfaceMesh> mesh;
  static int made = 0;
  if (made != cells) {
    const auto path = std::filesystem::path(TOPOTRACK_SHARED_DIR) / "data/elephant/elephant.0001.ply";
    if (!std::filesystem::exists(path)) return nullptr;
    const SurfaceMesh frame = to_surface_mesh(read_mesh(path));
    const double voxel = bounding_box(frame).diagonal() / cells;
    mesh = std::make_unique<SurfaceMesh>(to_surface_mesh(marching_cubes(*signed_distance(frame, voxel))));
    made = cells;
  }
  return mesh.get();
}

void BM_ImproveResurfacedElephant(benchmark::State& state) {
  const SurfaceMesh* in = resurfaced_elephant(int(state.range(0)));
  if (!in) return state.SkipWithError("../shared/data/elephant not present");
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism, std::size_t(state.range(1)));
  ImproveParams params;
  params.measure_quality = false;
  ImproveReport r;
  double cpu = 0;
  for (auto _ : state) {
    state.PauseTiming();
    SurfaceMesh m = in->clone();
    EventList events;
    const double c0 = process_cpu_seconds();
    state.ResumeTiming();
    r = improve_mesh(m, params, &events);
    cpu += process_cpu_seconds() - c0;
    state.PauseTiming();
    m = SurfaceMesh();
    state.ResumeTiming();
  }
  state.counters["cpu_seconds_all_threads"] = cpu / double(state.iterations());
  state.counters["vertices_in"] = double(in->n_vertices());
  state.counters["splits"] = double(r.splits);
  state.counters["collapses"] = double(r.collapses);
  state.counters["flips"] = double(r.flips);
}

void BM_ImproveResurfacedElephantAlreadyGood(benchmark::State& state) {
  const SurfaceMesh* in = resurfaced_elephant(int(state.range(0)));
  if (!in) return state.SkipWithError("../shared/data/elephant not present");
  SurfaceMesh good = in->clone();
  const ImproveReport first = improve_mesh(good);
  ImproveParams params;
  params.measure_quality = false;
  params.target_edge_length = std::sqrt(first.min_edge_length * first.max_edge_length);
  // The elephant's specks (slivers of the level set of a self-intersecting input) still change in a second
  // call; samba and pcow frames do not (tests/kernels/improve/improve_fixed_point_test.cpp).
  for (int i = 0; i < 3; ++i) improve_mesh(good, params);
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism, std::size_t(state.range(1)));
  double cpu = 0;
  for (auto _ : state) {
    EventList events;
    const double c0 = process_cpu_seconds();
    const ImproveReport r = improve_mesh(good, params, &events);
    cpu += process_cpu_seconds() - c0;
    if (!events.empty() || r.flips > 0) state.SkipWithError("an already-good mesh was changed");
  }
  state.counters["cpu_seconds_all_threads"] = cpu / double(state.iterations());
  state.counters["vertices_in"] = double(good.n_vertices());
}

// Args: cells across the bounding-box diagonal, threads.
BENCHMARK(BM_ImproveResurfacedElephant)->Args({300, 1})->Args({300, 2})->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_ImproveResurfacedElephantAlreadyGood)
    ->Args({300, 1})
    ->Args({300, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace topotrack

BENCHMARK_MAIN();
