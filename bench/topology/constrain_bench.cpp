// ConstrainTopology (§4.3) cost vs size: CalculateSignedDistance + classification + replacement, the work of
// Algorithm 1 lines 8-9 (Θ = φ_M) and 10-11 (Θ = φ_S of the next frame), on `gen metaballs` frames whose
// vertex count grows with the resolution. Voxel size = the mesh's mean edge length (the tracked mesh's
// target edge length). Target (issue 5): 100k vertices in at most 0.4 s on 2 cores.
//   constrain_bench --benchmark_format=json
#include <benchmark/benchmark.h>

#include <chrono>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <utility>

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
  SurfaceMesh mesh, next;  // M and the surface it is constrained to
  double voxel = 0;        // M's mean edge length (the tracked mesh's target edge length)
};

// The pair `make` picks from a `frames`-frame synthetic scene of `kind` at `resolution` voxels, built once.
const Pair& cached_pair(SyntheticKind kind, int frames, int resolution,
                        const std::function<std::pair<MeshData, MeshData>(const SyntheticScene&)>& make) {
  static std::map<std::pair<int, int>, std::unique_ptr<Pair>> cache;
  auto& p = cache[{int(kind), resolution}];
  if (!p) {
    SyntheticParams sp;
    sp.kind = kind;
    sp.frames = frames;
    sp.resolution = resolution;
    const auto [mesh, next] = make(SyntheticScene(sp));
    p = std::make_unique<Pair>();
    p->mesh = to_surface_mesh(mesh);
    p->next = to_surface_mesh(next);
    p->voxel = mean_edge_length(p->mesh);
  }
  return *p;
}

// Frames 120 and 121 of a 240-frame metaballs scene (consecutive frames close together, as M and S_n are
// after alignment; the balls are splitting apart there), at `resolution` voxels.
const Pair& scene_pair(int resolution) {
  return cached_pair(SyntheticKind::kMetaballs, 240, resolution, [](const SyntheticScene& scene) {
    return std::pair(scene.frame_mesh(120), scene.frame_mesh(121));
  });
}

// ConstrainTopology's steps, from its last run, as counters `prefix`<step> (classify_s: the classification
// alone, without cut and index).
void step_counters(benchmark::State& state, const ConstrainReport& r, const std::string& prefix = "") {
  const std::pair<const char*, double> steps[] = {
      {"complex_cells", double(r.complex_cells)},
      {"cut_s", r.seconds_cut},
      {"index_s", r.seconds_index},
      {"classify_s", r.seconds_classify - r.seconds_cut - r.seconds_index},
      {"replace_s", r.seconds_replace},
      {"assemble_s", r.seconds_assemble},
      {"rebuild_s", r.seconds_rebuild},
      {"slivers_s", r.seconds_slivers},
      {"assemblies", double(r.assemblies)},
      {"components_s", r.seconds_components},
      {"events_s", r.seconds_events},
      {"total_s", r.seconds_total}};
  for (const auto& [name, value] : steps) state.counters[prefix + name] = value;
}

// ConstrainTopology's parameters as the tracker passes them (engine/tracker.cpp: no component counts).
ConstrainParams tracker_constrain_params() {
  ConstrainParams cp;
  cp.count_components = false;
  return cp;
}

void run(benchmark::State& state, bool self, SdfMethod method = SdfMethod::kAuto, double half_width = 3.0,
         const ConstrainParams& cp = {}) {
  const Pair& p = scene_pair(int(state.range(0)));
  ConstrainReport r;
  double sdf_s = 0;
  for (auto _ : state) {
    state.PauseTiming();
    SurfaceMesh m = p.mesh.clone();
    state.ResumeTiming();
    const auto t0 = std::chrono::steady_clock::now();
    std::vector<Vec3> P;
    std::vector<std::array<Index, 3>> T;
    extract_triangles(self ? m : p.next, P, T);
    SignedDistanceParams sp;
    sp.voxel_size = p.voxel;
    sp.half_width_voxels = half_width;
    sp.method = method;
    const openvdb::FloatGrid::Ptr theta = signed_distance(P, T, sp);
    sdf_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    EventList events;
    r = constrain_topology(m, *theta, cp, &events);
    benchmark::DoNotOptimize(m.n_vertices());
  }
  state.counters["vertices"] = double(p.mesh.n_vertices());
  step_counters(state, r);
  state.counters["sdf_s"] = sdf_s;
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
  step_counters(state, r);
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
// The rebuild of ConstrainTopology's replacement: SurfaceMesh::from_triangles of a whole closed mesh.
void BM_FromTriangles(benchmark::State& state) {
  const Pair& p = scene_pair(int(state.range(0)));
  std::vector<Vec3> P;
  std::vector<std::array<Index, 3>> T;
  extract_triangles(p.mesh, P, T);
  for (auto _ : state) benchmark::DoNotOptimize(SurfaceMesh::from_triangles(P, T, {}, true).n_edges());
  state.counters["vertices"] = double(p.mesh.n_vertices());
}
BENCHMARK(BM_FromTriangles)->Arg(100)->Arg(300)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();
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
// The same as the tracker runs it (issue 5's target): its half width (second argument, hundredths of a voxel:
// 175 the profile's, enough for what ConstrainTopology reads; 200 the profile's before 2026-11-23) and its
// ConstrainParams; BM_ConstrainSelfMethod keeps signed_distance's default of 3 and counts components.
void BM_ConstrainSelfTracker(benchmark::State& state) {
  run(state, true, SdfMethod::kAuto, double(state.range(1)) / 100, tracker_constrain_params());
}
BENCHMARK(BM_ConstrainSelfTracker)->ArgsProduct({{300}, {175, 200}})->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();

// The tracker's common case (Algorithm 1 lines 8-11 after alignment, issue 6's 100k frame): M is blobs frame 2
// moved by the ground-truth rotation onto frame 3, S is frame 3 (another triangulation of the same shape), with
// the tracker's default parameters (profiles/default.json: half width 2, exact-sign band 0.25 voxel), and a half
// width of 1.75. Almost every cell is simple: what is measured is the cost of finding that out. Resolution 240:
// 100k vertices.
const Pair& matched_pair(int resolution) {
  return cached_pair(SyntheticKind::kBlobs, 100, resolution, [](const SyntheticScene& scene) {
    MeshData m = scene.frame_mesh(2);
    const RigidMotion a = scene.blobs_motion(2), b = scene.blobs_motion(3);
    const Eigen::Matrix3d R = b.rotation * a.rotation.transpose();
    for (auto& x : m.positions) {
      const Vec3 y = R * (Vec3(x[0], x[1], x[2]) - a.center) + b.center;
      x = {y.x(), y.y(), y.z()};
    }
    return std::pair(std::move(m), scene.frame_mesh(3));
  });
}
void BM_TrackerTopology(benchmark::State& state) {
  const Pair& p = matched_pair(int(state.range(0)));
  // Second argument: the half width in hundredths of a voxel (200: the profile's 2.0; 175: enough for what
  // ConstrainTopology reads, corners of cells within sqrt(3) voxels of the surface).
  const double kHalfWidth = double(state.range(1)) / 100, kExactSignBand = 0.25;
  ConstrainReport self, target;
  double sdf_s = 0;
  for (auto _ : state) {
    state.PauseTiming();
    SurfaceMesh m = p.mesh.clone();
    state.ResumeTiming();
    EventList events;
    const auto t0 = std::chrono::steady_clock::now();
    const openvdb::FloatGrid::Ptr phi_m = signed_distance(m, p.voxel, kHalfWidth, kExactSignBand);
    const auto t1 = std::chrono::steady_clock::now();
    self = constrain_topology(m, *phi_m, tracker_constrain_params(), &events);
    const auto t2 = std::chrono::steady_clock::now();
    const openvdb::FloatGrid::Ptr phi_s = signed_distance(p.next, p.voxel, kHalfWidth, kExactSignBand);
    const auto t3 = std::chrono::steady_clock::now();
    target = constrain_topology(m, *phi_s, tracker_constrain_params(), &events);
    sdf_s = std::chrono::duration<double>((t1 - t0) + (t3 - t2)).count();
    benchmark::DoNotOptimize(m.n_vertices());
  }
  state.counters["vertices"] = double(p.mesh.n_vertices());
  state.counters["sdf_s"] = sdf_s;
  state.counters["self_s"] = self.seconds_total;
  state.counters["target_s"] = target.seconds_total;
  // The split of ConstrainTopology(M, φ_M) (the call with complex cells in the common case).
  step_counters(state, self, "self_");
  state.counters["complex_self"] = double(self.complex_cells);
  state.counters["complex_target"] = double(target.complex_cells);
}
BENCHMARK(BM_TrackerTopology)->Args({120, 175})->Args({240, 175})->Args({240, 200})->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();

BENCHMARK(BM_ConstrainToNextFrame)->Arg(100)->Arg(200)->Arg(300)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();
BENCHMARK(BM_ConstrainSelf)->Arg(100)->Arg(200)->Arg(300)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();

}  // namespace
}  // namespace topotrack

BENCHMARK_MAIN();
