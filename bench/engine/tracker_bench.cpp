// The tracker per frame (Algorithm 1, lines 4-14) through the library API, issue #6's speed target: a
// 100k-vertex frame in at most 2 s on 2 cores. The input is `gen blobs` (100 frames per turn) at
// resolution 140 (about 25k vertices) and 280 (about 100k, the target's size); each iteration tracks
// frames 2-4 after frame 1 (frame 1, lines 1-2, is set-up, not timed). Second argument: 0 one frame at a
// time (add_frame), 1 pipelined as `topotrack track` does it (frame n+1 prepared, Tracker::prepare, in a
// TBB task while frame n is tracked). Third: threads (1 or 2).
// Counters: seconds_per_frame (wall clock, the target's measure), cpu_per_frame (CPU seconds of all the
// process's threads: on a shared machine wall time also counts waiting, so compare rows of one run),
// vertices. Files are not written here: the CLI's reading and writing overlap is measured with
// `/usr/bin/time topotrack track` (docs/results.md).
// Run: tracker_bench --benchmark_format=json [--benchmark_filter=...]
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>
#include <tbb/task_group.h>

#include <chrono>
#include <map>
#include <memory>
#include <vector>

#include "bench/bench_support.hpp"
#include "engine/tracker.hpp"
#include "kernels/gen/synthetic.hpp"
#include "kernels/mesh/mesh_convert.hpp"

namespace topotrack {
namespace {

constexpr int kFrames = 4;

//! Frames 1..kFrames of `gen blobs --frames 100 --resolution r`, built once per resolution.
const std::vector<SurfaceMesh>& blobs(int resolution) {
  static std::map<int, std::unique_ptr<std::vector<SurfaceMesh>>> cache;
  auto& frames = cache[resolution];
  if (!frames) {
    SyntheticParams p;
    p.frames = 100;
    p.resolution = resolution;
    const SyntheticScene scene(p);
    frames = std::make_unique<std::vector<SurfaceMesh>>();
    for (int n = 1; n <= kFrames; ++n) frames->push_back(to_surface_mesh(scene.frame_mesh(n)));
  }
  return *frames;
}

using bench::process_cpu_seconds;

void BM_TrackFrame(benchmark::State& state) {
  const auto& frames = blobs(int(state.range(0)));
  const bool pipelined = state.range(1) != 0;
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism, std::size_t(state.range(2)));
  double wall = 0, cpu = 0;
  std::size_t tracked = 0, vertices = 0;
  for (auto _ : state) {
    state.PauseTiming();
    Tracker tracker;
    tracker.add_frame(frames[0]);
    state.ResumeTiming();
    const auto t0 = std::chrono::steady_clock::now();
    const double c0 = process_cpu_seconds();
    if (pipelined) {
      PreparedFrame next = tracker.prepare(frames[1].clone());
      for (std::size_t i = 1; i < frames.size(); ++i) {
        PreparedFrame cur = std::move(next);
        tbb::task_group ahead;
        if (i + 1 < frames.size()) ahead.run([&] { next = tracker.prepare(frames[i + 1].clone()); });
        tbb::this_task_arena::isolate([&] { vertices = tracker.add_frame(std::move(cur)).vertices; });
        ahead.wait();
      }
    } else {
      for (std::size_t i = 1; i < frames.size(); ++i) vertices = tracker.add_frame(frames[i]).vertices;
    }
    wall += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    cpu += process_cpu_seconds() - c0;
    tracked += frames.size() - 1;
  }
  state.counters["seconds_per_frame"] = wall / double(tracked);
  state.counters["cpu_per_frame"] = cpu / double(tracked);
  state.counters["vertices"] = double(vertices);
}

BENCHMARK(BM_TrackFrame)
    ->ArgNames({"resolution", "pipelined", "threads"})
    ->Args({140, 0, 2})
    ->Args({140, 1, 2})
    ->Args({280, 0, 2})
    ->Args({280, 1, 2})
    ->Args({280, 1, 1})
    ->Iterations(1)
    ->Unit(benchmark::kSecond)
    ->UseRealTime();

}  // namespace
}  // namespace topotrack

BENCHMARK_MAIN();
