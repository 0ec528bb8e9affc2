// ConstrainTopology (§4.3) cost vs size: CalculateSignedDistance + classification + replacement, the work of
// Algorithm 1 lines 8-9 (Θ = φ_M) and 10-11 (Θ = φ_S of the next frame), on `gen metaballs` frames whose
// vertex count grows with the resolution. Voxel size = the mesh's mean edge length (the tracked mesh's
// target edge length). Target (issue 5): 100k vertices in at most 0.4 s on 2 cores.
//   constrain_bench --benchmark_format=json
#include <benchmark/benchmark.h>

#include <map>
#include <memory>

#include "kernels/gen/synthetic.hpp"
#include "kernels/mesh/mesh_convert.hpp"
#include "kernels/mesh/mesh_queries.hpp"
#include "kernels/sdf/signed_distance.hpp"
#include "kernels/topology/classify.hpp"
#include "kernels/topology/constrain.hpp"
#include "kernels/topology/lattice_cut.hpp"

namespace topotrack {
namespace {

struct Pair {
  SurfaceMesh mesh, next;
  double voxel = 0;
};

// Frames 120 and 121 of a 240-frame metaballs scene (consecutive frames close together, as M and S_n are
// after alignment; the balls are splitting apart there), at `resolution` voxels.
const Pair& scene_pair(int resolution) {
  static std::map<int, std::unique_ptr<Pair>> cache;
  auto& p = cache[resolution];
  if (!p) {
    SyntheticParams sp;
    sp.kind = SyntheticKind::kMetaballs;
    sp.frames = 240;
    sp.resolution = resolution;
    const SyntheticScene scene(sp);
    p = std::make_unique<Pair>();
    p->mesh = to_surface_mesh(scene.frame_mesh(120));
    p->next = to_surface_mesh(scene.frame_mesh(121));
    p->voxel = mean_edge_length(p->mesh);
  }
  return *p;
}

void run(benchmark::State& state, bool self, SdfMethod method = SdfMethod::kAuto) {
  const Pair& p = scene_pair(int(state.range(0)));
  ConstrainReport r;
  for (auto _ : state) {
    state.PauseTiming();
    SurfaceMesh m = p.mesh.clone();
    state.ResumeTiming();
    std::vector<Vec3> P;
    std::vector<std::array<Index, 3>> T;
    extract_triangles(self ? m : p.next, P, T);
    SignedDistanceParams sp;
    sp.voxel_size = p.voxel;
    sp.method = method;
    const openvdb::FloatGrid::Ptr theta = signed_distance(P, T, sp);
    EventList events;
    r = constrain_topology(m, *theta, {}, &events);
    benchmark::DoNotOptimize(m.n_vertices());
  }
  state.counters["vertices"] = double(p.mesh.n_vertices());
  state.counters["complex_cells"] = double(r.complex_cells);
  state.counters["classify_s"] = r.seconds_classify;
  state.counters["replace_s"] = r.seconds_replace;
  state.counters["events_s"] = r.seconds_events;
  state.counters["constrain_s"] = r.seconds_total;
}

// The same two parts separately: CalculateSignedDistance alone, ConstrainTopology alone (Θ = φ_M given).
void BM_SignedDistanceOnly(benchmark::State& state) {
  const Pair& p = scene_pair(int(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(signed_distance(p.mesh, p.voxel)->activeVoxelCount());
  state.counters["vertices"] = double(p.mesh.n_vertices());
}
void BM_ConstrainSelfOnly(benchmark::State& state) {
  const Pair& p = scene_pair(int(state.range(0)));
  const openvdb::FloatGrid::Ptr theta = signed_distance(p.mesh, p.voxel);
  ConstrainReport r;
  for (auto _ : state) {
    state.PauseTiming();
    SurfaceMesh m = p.mesh.clone();
    state.ResumeTiming();
    EventList events;
    r = constrain_topology(m, *theta, {}, &events);
  }
  state.counters["vertices"] = double(p.mesh.n_vertices());
  state.counters["complex_cells"] = double(r.complex_cells);
  state.counters["cut_s"] = r.seconds_cut;
  state.counters["index_s"] = r.seconds_index;
  state.counters["classify_s"] = r.seconds_classify - r.seconds_cut - r.seconds_index;
  state.counters["replace_s"] = r.seconds_replace;
  state.counters["assemble_s"] = r.seconds_assemble;
  state.counters["rebuild_s"] = r.seconds_rebuild;
  state.counters["slivers_s"] = r.seconds_slivers;
  state.counters["assemblies"] = r.assemblies;
  state.counters["components_s"] = r.seconds_components;
  state.counters["events_s"] = r.seconds_events;
  state.counters["total_s"] = r.seconds_total;
}
// The steps of ConstrainTopology(M, φ_M) alone: the lattice cut, the cell index, the classification.
void BM_LatticeCut(benchmark::State& state) {
  const Pair& p = scene_pair(int(state.range(0)));
  const openvdb::FloatGrid::Ptr theta = signed_distance(p.mesh, p.voxel);
  std::size_t pieces = 0;
  for (auto _ : state) pieces = topology::cut_by_lattice(p.mesh, theta->transform()).pieces.size();
  state.counters["vertices"] = double(p.mesh.n_vertices());
  state.counters["pieces"] = double(pieces);
}
void BM_IndexCells(benchmark::State& state) {
  const Pair& p = scene_pair(int(state.range(0)));
  const openvdb::FloatGrid::Ptr theta = signed_distance(p.mesh, p.voxel);
  const topology::LatticeCut cut = topology::cut_by_lattice(p.mesh, theta->transform());
  std::size_t n = 0, flipped = 0;
  for (auto _ : state) {
    const topology::CellIndex index = topology::index_cells(cut, *theta);
    n = index.cells.size();
    flipped = index.flipped.size();
  }
  state.counters["vertices"] = double(p.mesh.n_vertices());
  state.counters["cells"] = double(n);
  state.counters["flipped"] = double(flipped);
}
// Second argument: 0 the reference per-cell test, 1 the fast one (the before / after of classify_fast.hpp).
void BM_ClassifyCells(benchmark::State& state) {
  const Pair& p = scene_pair(int(state.range(0)));
  const openvdb::FloatGrid::Ptr theta = signed_distance(p.mesh, p.voxel);
  const topology::LatticeCut cut = topology::cut_by_lattice(p.mesh, theta->transform());
  const topology::CellIndex index = topology::index_cells(cut, *theta);
  const auto path = state.range(1) == 0 ? topology::ClassifyPath::kReference : topology::ClassifyPath::kFast;
  std::size_t n = 0;
  for (auto _ : state) n = topology::complex_cells(p.mesh, cut, index, *theta, path).size();
  state.counters["vertices"] = double(p.mesh.n_vertices());
  state.counters["cells"] = double(index.cells.size());
  state.counters["complex"] = double(n);
}
BENCHMARK(BM_LatticeCut)->Arg(100)->Arg(200)->Arg(300)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();
BENCHMARK(BM_IndexCells)->Arg(100)->Arg(200)->Arg(300)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();
BENCHMARK(BM_ClassifyCells)->ArgsProduct({{100, 200, 300}, {0, 1}})->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();

BENCHMARK(BM_SignedDistanceOnly)->Arg(100)->Arg(200)->Arg(300)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();
BENCHMARK(BM_ConstrainSelfOnly)->Arg(100)->Arg(200)->Arg(300)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();

void BM_ConstrainToNextFrame(benchmark::State& state) { run(state, false); }
void BM_ConstrainSelf(benchmark::State& state) { run(state, true); }

// Θ = φ_M with either signed distance (second argument 0: OpenVDB meshToVolume, 1: the narrow band): the
// before / after of narrow_band.hpp in one run.
void BM_ConstrainSelfMethod(benchmark::State& state) {
  run(state, true, state.range(1) == 0 ? SdfMethod::kOpenVdb : SdfMethod::kNarrowBand);
}
BENCHMARK(BM_ConstrainSelfMethod)->ArgsProduct({{300}, {0, 1}})->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();

BENCHMARK(BM_ConstrainToNextFrame)->Arg(100)->Arg(200)->Arg(300)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();
BENCHMARK(BM_ConstrainSelf)->Arg(100)->Arg(200)->Arg(300)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();

}  // namespace
}  // namespace topotrack

BENCHMARK_MAIN();
