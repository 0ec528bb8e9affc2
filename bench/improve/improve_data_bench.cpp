// improve_mesh (§4.1) on real data as the tracker sees it: a frame of a ../shared/data capture re-meshed
// exactly as `topotrack gen resurface --resolution R` does (kernels/gen resurface), at a resolution that
// gives about 100k vertices, and the same mesh improved once more (the already-good case of Algorithm 1,
// lines 7 and 12). Wall time (real time) at 1 and 2 threads, plus the process CPU time of all threads.
// Run: improve_data_bench --benchmark_format=json
#include <benchmark/benchmark.h>
#include <sys/resource.h>
#include <tbb/global_control.h>

#include <filesystem>
#include <map>
#include <memory>
#include <string>

#include "io/mesh_reader.hpp"
#include "kernels/gen/resurface.hpp"
#include "kernels/improve/improve.hpp"
#include "kernels/mesh/mesh_convert.hpp"

namespace topotrack {
namespace {

double process_cpu_seconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

const char* const kCaptures[] = {"elephant", "samba", "pcow"};

//! Frame 1 of capture `c` re-meshed at `resolution` voxels across its largest side (null when absent).
const SurfaceMesh* resurfaced(int c, int resolution) {
  static std::map<std::pair<int, int>, std::unique_ptr<SurfaceMesh>> cache;
  auto& m = cache[{c, resolution}];
  if (!m) {
    const std::string name = kCaptures[c];
    const auto path = std::filesystem::path(TOPOTRACK_SHARED_DIR) / "data" / name / (name + ".0001.ply");
    if (!std::filesystem::exists(path)) return nullptr;
    const MeshData source = read_mesh(path);
    const BoundingBox box = bounding_box(to_surface_mesh(source));
    m = std::make_unique<SurfaceMesh>(
        to_surface_mesh(resurface(source, {(box.max - box.min).maxCoeff() / resolution, 2.0})));
  }
  return m.get();
}

// Args: capture (0 elephant, 1 samba, 2 pcow), resolution, threads.
void BM_ImproveResurfaced(benchmark::State& state) {
  const SurfaceMesh* in = resurfaced(int(state.range(0)), int(state.range(1)));
  if (!in) return state.SkipWithError("../shared/data not present");
  state.SetLabel(kCaptures[state.range(0)]);
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism, std::size_t(state.range(2)));
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
  state.counters["relaxations"] = double(r.relaxations);
  state.counters["iterations"] = r.iterations;
  state.counters["s_scan"] = r.seconds_scan;
  state.counters["s_split"] = r.seconds_split;
  state.counters["s_collapse"] = r.seconds_collapse;
  state.counters["s_bad"] = r.seconds_bad_triangles;
  state.counters["s_fold"] = r.seconds_folds;
  state.counters["s_finish"] = r.seconds_finish;
}

void BM_ImproveResurfacedAlreadyGood(benchmark::State& state) {
  const SurfaceMesh* in = resurfaced(int(state.range(0)), int(state.range(1)));
  if (!in) return state.SkipWithError("../shared/data not present");
  state.SetLabel(kCaptures[state.range(0)]);
  SurfaceMesh good = in->clone();
  const ImproveReport first = improve_mesh(good);
  ImproveParams params;
  params.measure_quality = false;
  params.target_edge_length = std::sqrt(first.min_edge_length * first.max_edge_length);
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism, std::size_t(state.range(2)));
  double cpu = 0;
  for (auto _ : state) {
    EventList events;
    const double c0 = process_cpu_seconds();
    const ImproveReport r = improve_mesh(good, params, &events);
    cpu += process_cpu_seconds() - c0;
    if (!events.empty() || r.flips + r.relaxations > 0)
      state.SkipWithError("an already-good mesh was changed");
  }
  state.counters["cpu_seconds_all_threads"] = cpu / double(state.iterations());
  state.counters["vertices_in"] = double(good.n_vertices());
}

// About 100k vertices: elephant at 230 voxels, samba at 310, pcow at 250.
BENCHMARK(BM_ImproveResurfaced)
    ->Args({0, 230, 1})
    ->Args({0, 230, 2})
    ->Args({1, 310, 2})
    ->Args({2, 250, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_ImproveResurfacedAlreadyGood)
    ->Args({0, 230, 2})
    ->Args({1, 310, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace topotrack

BENCHMARK_MAIN();
