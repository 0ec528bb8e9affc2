#pragma once
//! The improve_mesh (§4.1) benchmarks' shared runs, for the generated meshes (improve_bench.cpp) and the
//! resurfaced real frames (improve_data_bench.cpp): the same timing and the same counters for both.
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <cmath>

#include "bench/bench_support.hpp"
#include "kernels/improve/improve.hpp"

namespace topotrack::bench {

//! Times improve_mesh on copies of `in`, the copy outside the timing (the caller limits the threads);
//! counter cpu_seconds_all_threads. Returns the last run's report.
inline ImproveReport time_improve(benchmark::State& state, const SurfaceMesh& in) {
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
  return r;
}

//! The operation counts and seconds per phase of `r`, an improvement of `in`.
inline void improve_counters(benchmark::State& state, const SurfaceMesh& in, const ImproveReport& r) {
  state.counters["vertices_in"] = double(in.n_vertices());
  state.counters["splits"] = double(r.splits);
  state.counters["collapses"] = double(r.collapses);
  state.counters["flips"] = double(r.flips);
  state.counters["iterations"] = r.iterations;
  state.counters["s_scan"] = r.seconds_scan;
  state.counters["s_split"] = r.seconds_split;
  state.counters["s_collapse"] = r.seconds_collapse;
  state.counters["s_bad"] = r.seconds_bad_triangles;
  state.counters["s_fold"] = r.seconds_folds;
  state.counters["s_finish"] = r.seconds_finish;
}

//! The case the tracker hits most (Algorithm 1, lines 7 and 12): `in` improved once, then improved again at
//! the edge length it reached, which must change nothing (a parallel scan and nothing else); the timed runs
//! with `threads` threads.
inline void time_already_good(benchmark::State& state, const SurfaceMesh& in, int threads) {
  SurfaceMesh good = in.clone();
  const ImproveReport first = improve_mesh(good);
  ImproveParams params;
  params.measure_quality = false;
  params.target_edge_length = std::sqrt(first.min_edge_length * first.max_edge_length);
  const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
  double cpu = 0;
  for (auto _ : state) {
    EventList events;
    const double c0 = process_cpu_seconds();
    const ImproveReport r = improve_mesh(good, params, &events);
    cpu += process_cpu_seconds() - c0;
    if (!events.empty() || r.splits + r.collapses + r.flips + r.relaxations > 0)
      state.SkipWithError("an already-good mesh was changed");
  }
  state.counters["cpu_seconds_all_threads"] = cpu / double(state.iterations());
  state.counters["vertices_in"] = double(good.n_vertices());
}

}  // namespace topotrack::bench
