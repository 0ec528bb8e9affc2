// improve_mesh (§4.1) on real data as the tracker sees it: a frame of a ../shared/data capture re-meshed
// exactly as `topotrack gen resurface --resolution R` does (kernels/gen resurface), at a resolution that
// gives about 100k vertices, and the same mesh improved once more (the already-good case of Algorithm 1,
// lines 7 and 12). Wall time (real time) at 1 and 2 threads, plus the process CPU time of all threads.
// Run: improve_data_bench --benchmark_format=json
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <filesystem>
#include <map>
#include <memory>
#include <string>

#include "bench/improve/improve_bench.hpp"
#include "io/mesh_reader.hpp"
#include "kernels/gen/resurface.hpp"
#include "kernels/improve/improve.hpp"
#include "kernels/mesh/mesh_convert.hpp"

namespace topotrack {
namespace {

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
  const tbb::global_control threads(tbb::global_control::max_allowed_parallelism, std::size_t(state.range(2)));
  const ImproveReport r = bench::time_improve(state, *in);
  bench::improve_counters(state, *in, r);
  state.counters["relaxations"] = double(r.relaxations);
}

void BM_ImproveResurfacedAlreadyGood(benchmark::State& state) {
  const SurfaceMesh* in = resurfaced(int(state.range(0)), int(state.range(1)));
  if (!in) return state.SkipWithError("../shared/data not present");
  state.SetLabel(kCaptures[state.range(0)]);
  bench::time_already_good(state, *in, int(state.range(2)));
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
