// Non-rigid alignment (§4.2) on the real sequences: coarse + fine for frame 1 onto a re-sampled frame
// 1 + gap, gap 1 (consecutive frames, the tracker's case) or 15 (large motion, the registration
// issue's pairs). Sizes: 0 samba (10k vertices), 1 elephant (42k), 2 and 3 the elephant source
// re-meshed by improve_mesh to about 47k and 100k (the targets: coarse + fine <= 2 s and
// <= 4 s on 2 cores), the target stays the re-sampled 42k frame; 4 the samba source re-meshed to about 100k (a
// pair the low-density pass leaves alone, so `align` ends it on the denser graph), its target the 10k frame. Further arguments: graph density (percent of the paper's) and
// the cap on PCG iterations per Gauss–Newton round (100: the former default, 15: the current one), and
// whether the large-motion stages run (rigid pre-alignment, low-density pass and backward matches, by
// their misfit tests, and what `topotrack align` adds: use_large_motion_alignment), and the fine stage's form: vector displacements (0, the paper's) or displacements
// along the vertex normals (1, FineParams::normal_displacement).
// Counters: vertices, nodes, rounds, PCG iterations and the seconds of graph, correspondences,
// assembly, factorisation and solve (coarse) and ray casting, assembly and solve (fine). "CPU" is the
// process CPU time (all threads); the machine's load inflates "Time" (wall clock), so compare rows of
// one run. BM_Factorisation: the two Cholesky backends on the same Gauss–Newton systems (one round of the
// direct solve each). BM_BlockCholeskySolve / BM_BlockCholeskyFactorize: the PCG preconditioner's factor
// (4 x 4 blocks) on the deformation graph, with 1 or 2 threads, "fastest_ms" the least disturbed run;
// BM_CholmodFactorize: CHOLMOD on the same matrices. BM_DeformationGraph(Elephant), BM_GeodesicDistances,
// BM_VertexNormals: the graph, the intrinsic matches' distance fields and the vertex normals alone.
// BM_AlignCoarseFine and BM_TrackerStep set malloc's policy as `topotrack align` and `track` do
// (tools/heap.hpp); it stays for the benchmarks that run after them in the same process.
// Run: registration_bench --benchmark_format=json [--benchmark_filter=...]
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>
#include <string>
#include <tuple>

#include "bench/bench_support.hpp"
#include "tools/heap.hpp"
#include "kernels/gen/synthetic.hpp"
#include "kernels/mesh/edge_graph.hpp"
#include "kernels/mesh/mesh_convert.hpp"
#include "kernels/mesh/mesh_queries.hpp"
#include "kernels/registration/block_cholesky.hpp"
#include "kernels/registration/coarse.hpp"
#include "kernels/registration/deformation_graph.hpp"
#include "kernels/registration/fine.hpp"
#include "kernels/registration/large_motion.hpp"
#include "tests/kernels/registration/real_data.hpp"

namespace topotrack {
namespace {

struct Fixture {
  SurfaceMesh source;
  std::unique_ptr<TargetSurface> target;
  std::vector<Vec3> truth;  //!< where each source vertex belongs on the target (test::refine_source for the re-meshed sizes)
  double diagonal = 1;
};

const Fixture& fixture(int size, int gap) {
  static std::map<std::pair<int, int>, std::unique_ptr<Fixture>> cache;
  auto& f = cache[{size, gap}];
  if (!f) {
    f = std::make_unique<Fixture>();
    test::AlignmentPair pair = test::make_pair(size == 0 || size == 4 ? "samba" : "elephant", 1, gap);
    const double refine[] = {1.0, 1.0, 0.85, 0.563, 0.24};  // edge length factors of the re-meshed sizes
    if (size >= 2) test::refine_source(pair, refine[size]);
    f->source = std::move(pair.source);
    f->truth = std::move(pair.truth);
    f->diagonal = pair.diagonal;
    f->target = std::make_unique<TargetSurface>(TargetSurface::from_mesh(pair.target_mesh));
  }
  return *f;
}

// The counters both alignment benchmarks report: the coarse stage's graph, rounds and seconds per phase, the
// fine stage's total.
void alignment_counters(benchmark::State& state, const CoarseReport& c, const FineReport& fr) {
  state.counters["nodes"] = c.nodes;
  state.counters["rounds"] = c.iterations;
  state.counters["coarse_pass_rounds"] = c.coarse_pass_iterations;
  state.counters["backward"] = c.backward + c.backward_all;  // 0 off, 1 pruned nodes, 2 every node
  state.counters["pcg_iterations"] = c.pcg_iterations;
  state.counters["coarse_s"] = c.seconds_total;
  state.counters["coarse_prealign_s"] = c.seconds_prealign;
  state.counters["coarse_graph_s"] = c.seconds_graph;
  state.counters["coarse_corr_s"] = c.seconds_correspondences;
  state.counters["coarse_assembly_s"] = c.seconds_assembly;
  state.counters["coarse_factor_s"] = c.seconds_factorisation;
  state.counters["coarse_solve_s"] = c.seconds_solve;
  state.counters["fine_s"] = fr.seconds_total;
  // The low-density passes' own split (within coarse_prealign_s).
  state.counters["pass_s"] = c.low_density.seconds_total;
  state.counters["pass_graph_s"] = c.low_density.seconds_graph;
  state.counters["pass_corr_s"] = c.low_density.seconds_correspondences;
  state.counters["pass_assembly_s"] = c.low_density.seconds_assembly;
  state.counters["pass_factor_s"] = c.low_density.seconds_factorisation;
  state.counters["pass_solve_s"] = c.low_density.seconds_solve;
  state.counters["pass_pcg_iterations"] = c.low_density.pcg_iterations;
  state.counters["pass_nodes"] = c.low_density.nodes;
  // The denser graph's own split (after the full graph's, not within its figures).
  state.counters["dense_s"] = c.dense.seconds_total;
  state.counters["dense_graph_s"] = c.dense.seconds_graph;
  state.counters["dense_corr_s"] = c.dense.seconds_correspondences;
  state.counters["dense_assembly_s"] = c.dense.seconds_assembly;
  state.counters["dense_factor_s"] = c.dense.seconds_factorisation;
  state.counters["dense_solve_s"] = c.dense.seconds_solve;
  state.counters["dense_pcg_iterations"] = c.dense.pcg_iterations;
  state.counters["dense_rounds"] = c.dense.rounds;
  state.counters["dense_nodes"] = c.dense.nodes;
}

// Comparisons without rebuilding: TOPOTRACK_BENCH_COARSE="name=value,..." overrides CoarseParams
// fields of BM_AlignCoarseFine and BM_TrackerStep (retract_rotations, check_fit_first, fit_tolerance, step_tolerance,
// convergence_tolerance, max_iterations_per_level, max_pcg_iterations, coarse_pass_density,
// coarse_pass_alpha_reg_min, coarse_pass_misfit, max_iterations_per_level_after_pass).
void override_params(CoarseParams& p) {
  const char* env = std::getenv("TOPOTRACK_BENCH_COARSE");
  if (!env) return;
  const std::string all(env);
  std::size_t at = 0;
  while (at < all.size()) {
    const std::size_t end = std::min(all.find(',', at), all.size()), eq = all.find('=', at);
    if (eq < end) {
      const std::string name = all.substr(at, eq - at);
      const double v = std::atof(all.substr(eq + 1, end - eq - 1).c_str());
      if (name == "retract_rotations") p.retract_rotations = v != 0;
      else if (name == "check_fit_first") p.check_fit_first = v != 0;
      else if (name == "fit_tolerance") p.fit_tolerance = v;
      else if (name == "step_tolerance") p.step_tolerance = v;
      else if (name == "convergence_tolerance") p.convergence_tolerance = v;
      else if (name == "max_iterations_per_level") p.max_iterations_per_level = int(v);
      else if (name == "max_pcg_iterations") p.max_pcg_iterations = int(v);
      else if (name == "coarse_pass_density") p.coarse_pass_density = v;
      else if (name == "coarse_pass_alpha_reg_min") p.coarse_pass_alpha_reg_min = v;
      else if (name == "near_pass_density") p.near_pass_density = v;
      else if (name == "near_pass_min_spacing") p.near_pass_min_spacing = v;
      else if (name == "near_pass_max_iterations_per_level") p.near_pass_max_iterations_per_level = int(v);
      else if (name == "coarse_pass_misfit") p.coarse_pass_misfit = v;
      else if (name == "max_iterations_per_level_after_pass") p.max_iterations_per_level_after_pass = int(v);
      else if (name == "node_spacing_factor") p.node_spacing_factor = v;
      else if (name == "alpha_reg_min") p.alpha_reg_min = v;
      else if (name == "alpha_reg_start_after_pass") p.alpha_reg_start_after_pass = v;
      else if (name == "alpha_reg_start_without_pass") p.alpha_reg_start_without_pass = v;
      else if (name == "intrinsic_passes") p.intrinsic_passes = int(v);
      else if (name == "intrinsic_full_graph") p.intrinsic_full_graph = v != 0;
      else if (name == "dense_spacing_factor") p.dense_spacing_factor = v;
      else if (name == "min_nodes") p.min_nodes = int(v);
      else if (name == "vertex_fit_weight") p.vertex_fit_weight = v;
      else if (name == "vertex_fit_spacing") p.vertex_fit_spacing = v;
      else std::fprintf(stderr, "TOPOTRACK_BENCH_COARSE: unknown field %s\n", name.c_str());
    }
    at = end + 1;
  }
}

void BM_AlignCoarseFine(benchmark::State& state) {
  cli::keep_freed_memory();  // as topotrack align (tools/heap.hpp)
  const Fixture& f = fixture(int(state.range(0)), int(state.range(2)));
  CoarseParams params;
  params.graph_density = double(state.range(1)) / 100.0;
  params.max_pcg_iterations = int(state.range(3));
  if (state.range(4) == 0) {  // the paper's scheme alone: no rigid pre-alignment, no low-density pass, no backward matches
    params.prealign_misfit = 0;
    params.coarse_pass_misfit = 0;
    params.backward_weight = 0;
  }
  FineParams fine;
  fine.normal_displacement = state.range(5) != 0;
  if (state.range(4) != 0) use_large_motion_alignment(params, fine);  // as topotrack align runs it
  override_params(params);
  if (const char* e = std::getenv("TOPOTRACK_BENCH_RELAX")) fine.relax.iterations = std::atoi(e);  // 0: no relaxation
  CoarseReport c;
  FineReport fr;
  double truth = 0;
  for (auto _ : state) {
    state.PauseTiming();
    SurfaceMesh mesh = f.source.clone();
    state.ResumeTiming();
    c = align_coarse(mesh, *f.target, params);
    fr = align_fine(mesh, *f.target, fine, f.source.positions());
    benchmark::DoNotOptimize(mesh.positions().data());
    state.PauseTiming();
    double sum = 0;
    for (const double e : test::truth_errors(mesh.positions(), f.truth, f.diagonal)) sum += e;
    truth = 100 * sum / double(std::max<std::size_t>(1, f.truth.size()));
    state.ResumeTiming();
  }
  alignment_counters(state, c, fr);
  state.counters["truth_pct"] = truth;  // mean ground-truth error, % of the target's bounding-box diagonal
  state.counters["relax_s"] = fr.relax.seconds_total;
  state.counters["relax_setup_s"] = fr.relax.seconds_setup;
  state.counters["relax_closest_s"] = fr.relax.seconds_closest;
  state.counters["relax_rotations_s"] = fr.relax.seconds_rotations;
  state.counters["relax_solve_s"] = fr.relax.seconds_solve;
  state.counters["vertices"] = double(f.source.n_vertices());
  state.counters["levels"] = c.levels;
  state.counters["factor_nnz"] = double(c.factor_nonzeros);
  state.counters["fine_raycast_s"] = fr.seconds_raycast;
  state.counters["fine_assembly_s"] = fr.seconds_assembly;
  state.counters["fine_solve_s"] = fr.seconds_solve;
  state.counters["fine_rounds"] = fr.rounds;
  state.counters["intrinsic_passes"] = c.intrinsic_passes;
  state.counters["intrinsic_misplaced"] = double(c.intrinsic_full_graph_misplaced);
  state.counters["intrinsic_s"] = c.seconds_intrinsic;
  state.counters["coarse_fine_s"] = c.seconds_total + fr.seconds_total;
}
// {size, density %, gap, PCG cap, large-motion stages (0: off, 1: the defaults), fine displacements (0: vector,
// 1: normal)}
BENCHMARK(BM_AlignCoarseFine)
    ->ArgsProduct({{2, 3}, {100}, {1, 15}, {15, 100}, {0, 1}, {0}})
    ->ArgsProduct({{2, 3}, {100}, {1, 15}, {15}, {1}, {1}})
    ->Args({0, 100, 1, 15, 1, 0})
    ->Args({0, 100, 15, 15, 1, 0})
    ->Args({4, 100, 15, 15, 1, 0})
    ->Args({1, 100, 15, 15, 1, 0})
    ->Args({2, 25, 15, 15, 1, 0})
    ->ArgNames({"size", "density", "gap", "pcg", "large", "normal"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MeasureProcessCPUTime()
    ->Iterations(1);

// The tracker's case (issue 6): consecutive frames of `gen blobs` (100 frames per turn) at a given grid
// resolution (140: about 25k vertices, 280: about 100k), the source being frame 97 re-meshed by
// improve_mesh at its own mean edge length (the tracker's M), the target frame 98 as marching cubes gives
// it. The ground truth is the blobs' rotation: "truth_pct" is the mean distance of the source vertices to
// where the rotation takes them after coarse + fine, "coarse_truth_pct" after coarse alone, in percent of
// the target's bounding-box diagonal. The fourth argument: the fine stage's displacements (0 vector, 1 normal).
struct BlobsStep {
  SurfaceMesh source;
  std::vector<Vec3> truth;
  std::unique_ptr<TargetSurface> target;
  double diagonal = 0;
};

const BlobsStep& blobs_step(int resolution) {
  static std::map<int, std::unique_ptr<BlobsStep>> cache;
  auto& f = cache[resolution];
  if (!f) {
    f = std::make_unique<BlobsStep>();
    SyntheticParams p;
    p.kind = SyntheticKind::kBlobs;
    p.frames = 100;
    p.resolution = resolution;
    const SyntheticScene scene(p);
    const int k = 97;
    f->source = test::resample(to_surface_mesh(scene.frame_mesh(k)), 1.0);
    const SurfaceMesh target = to_surface_mesh(scene.frame_mesh(k + 1));
    f->target = std::make_unique<TargetSurface>(TargetSurface::from_mesh(target));
    f->diagonal = bounding_box(target).diagonal();
    const RigidMotion a = scene.blobs_motion(k), b = scene.blobs_motion(k + 1);
    const Eigen::Matrix3d R = b.rotation * a.rotation.transpose();
    f->truth = f->source.positions();
    for (Vec3& x : f->truth) x = R * (x - a.center) + b.center;
  }
  return *f;
}

double truth_error(const SurfaceMesh& mesh, const BlobsStep& f) {
  double sum = 0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < f.truth.size(); ++i)
    if (!mesh.is_deleted(Vertex(Index(i)))) {
      sum += (mesh.positions()[i] - f.truth[i]).norm();
      ++n;
    }
  return n ? 100 * sum / (double(n) * f.diagonal) : 0;
}

void BM_TrackerStep(benchmark::State& state) {
  cli::keep_large_blocks_unpooled();  // as topotrack track (tools/heap.hpp)
  const BlobsStep& f = blobs_step(int(state.range(0)));
  CoarseParams params;
  params.graph_density = double(state.range(2)) / 100.0;
  if (state.range(1) == 0) {
    params.prealign_misfit = 0;
    params.coarse_pass_misfit = 0;
  }
  override_params(params);
  FineParams fine;
  fine.normal_displacement = state.range(3) != 0;
  CoarseReport c;
  FineReport fr;
  double coarse_truth = 0, truth = 0;
  for (auto _ : state) {
    state.PauseTiming();
    SurfaceMesh mesh = f.source.clone();
    state.ResumeTiming();
    c = align_coarse(mesh, *f.target, params);
    state.PauseTiming();
    coarse_truth = truth_error(mesh, f);
    state.ResumeTiming();
    fr = align_fine(mesh, *f.target, fine);
    benchmark::DoNotOptimize(mesh.positions().data());
    state.PauseTiming();
    truth = truth_error(mesh, f);
    state.ResumeTiming();
  }
  state.counters["vertices"] = double(f.source.n_vertices());
  state.counters["unaligned_truth_pct"] = truth_error(f.source, f);
  state.counters["coarse_truth_pct"] = coarse_truth;
  state.counters["truth_pct"] = truth;
  state.counters["misfit_pct"] = 100 * c.misfit_start;
  alignment_counters(state, c, fr);
  if (std::getenv("TOPOTRACK_BENCH_ROUNDS"))  // per-round figures, for profiling the schedule
    for (const CoarseRound& r : c.rounds)
      std::fprintf(stderr, "round alpha_reg %g step %g motion %.3f fit %.3f pcg %d energy %.4g -> %.4g\n", r.alpha_reg,
                   r.step, r.motion, r.fit_distance, r.pcg_iterations, r.energy_before, r.energy);
}
// {grid resolution, large-motion stages (0: off, 1: the defaults), graph density in percent, fine
// displacements (0 vector, 1 normal)}; density 25 without the large-motion stages is the defaults' low-density
// pass alone.
BENCHMARK(BM_TrackerStep)
    ->ArgsProduct({{140, 280}, {0, 1}, {100}, {0}})
    ->ArgsProduct({{140, 280}, {1}, {100}, {1}})
    ->Args({280, 0, 25, 0})
    ->ArgNames({"resolution", "large", "density", "normal"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MeasureProcessCPUTime()
    ->Iterations(1);

// The deformation graph alone (§4.2: geodesic node sampling, k nearest nodes, edges) on the tracker's
// M of BM_TrackerStep, at the full and the quarter node density (the low-density pass); "sample_ms" is
// the node sampling alone (all that the full density costs when its nodes are found fitted).
void BM_DeformationGraph(benchmark::State& state) {
  const BlobsStep& f = blobs_step(int(state.range(0)));
  const double spacing = 4 * mean_edge_length(f.source) / std::sqrt(double(state.range(1)) / 100.0);
  double fastest = 1e30;
  std::size_t nodes = 0;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    const DeformationGraph g = build_deformation_graph(f.source, spacing, 4);
    fastest = std::min(fastest, bench::milliseconds_since(t0));
    nodes = g.n_nodes();
  }
  const auto t0 = std::chrono::steady_clock::now();
  benchmark::DoNotOptimize(sample_graph_nodes(f.source, spacing).data());
  state.counters["sample_ms"] = bench::milliseconds_since(t0);
  state.counters["fastest_ms"] = fastest;
  state.counters["nodes"] = double(nodes);
  state.counters["vertices"] = double(f.source.n_vertices());
}
// {grid resolution, density in percent}
BENCHMARK(BM_DeformationGraph)
    ->ArgsProduct({{280}, {100, 25}})
    ->ArgNames({"resolution", "density"})
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()
    ->Iterations(5);

// The same on the elephant's source re-meshed to 98k vertices (size 3; its numbering puts an edge's ends a
// mean 32k indices apart), full and quarter density.
void BM_DeformationGraphElephant(benchmark::State& state) {
  const Fixture& f = fixture(3, 15);
  const double spacing = 4 * mean_edge_length(f.source) / std::sqrt(double(state.range(0)) / 100.0);
  std::size_t nodes = 0;
  for (auto _ : state) nodes = build_deformation_graph(f.source, spacing, 4).n_nodes();
  const auto t0 = std::chrono::steady_clock::now();
  benchmark::DoNotOptimize(sample_graph_nodes(f.source, spacing).data());
  state.counters["sample_ms"] = bench::milliseconds_since(t0);
  state.counters["nodes"] = double(nodes);
}
BENCHMARK(BM_DeformationGraphElephant)->Arg(100)->Arg(25)->ArgName("density")->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime()->Iterations(5);

// The intrinsic matches' distance fields (kernels/registration/intrinsic_matches.*): 32 Dijkstras over
// the whole edge graph of the elephant's source at 47k and 98k vertices, from sources spread by index,
// as one batch (an alignment runs one on each surface), on 1 or 2 threads.
void BM_GeodesicDistances(benchmark::State& state) {
  const Fixture& f = fixture(int(state.range(0)), 15);
  const tbb::global_control threads(tbb::global_control::max_allowed_parallelism, std::size_t(state.range(1)));
  const EdgeGraph graph = edge_graph(f.source);
  std::vector<Index> sources;
  for (std::size_t a = 0; a < 32; ++a) sources.push_back(Index(a * graph.n_vertices() / 32));
  for (auto _ : state) benchmark::DoNotOptimize(geodesic_distances(graph, sources).data());
  state.counters["vertices"] = double(graph.n_vertices());
}
BENCHMARK(BM_GeodesicDistances)
    ->ArgsProduct({{2, 3}, {1, 2}})
    ->ArgNames({"size", "threads"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MeasureProcessCPUTime();

// Angle-weighted vertex normals of the elephant's source at 47k and 98k vertices (each fine round, the
// rigid pre-alignment and the tracker's every frame compute them), on 1 or 2 threads.
void BM_VertexNormals(benchmark::State& state) {
  const Fixture& f = fixture(int(state.range(0)), 15);
  const tbb::global_control threads(tbb::global_control::max_allowed_parallelism, std::size_t(state.range(1)));
  for (auto _ : state) benchmark::DoNotOptimize(vertex_normals(f.source).data());
  state.counters["vertices"] = double(f.source.n_vertices());
}
BENCHMARK(BM_VertexNormals)
    ->ArgsProduct({{2, 3}, {1, 2}})
    ->ArgNames({"size", "threads"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MeasureProcessCPUTime();

// One Gauss–Newton round with either backend: the time of one numeric factorisation.
void BM_Factorisation(benchmark::State& state) {
  const Fixture& f = fixture(int(state.range(0)), 15);
  CoarseParams p;
  p.solver = state.range(1) ? CholeskyBackend::Cholmod : CholeskyBackend::EigenLDLT;
  p.linear_solver = CoarseLinearSolver::Direct;  // the backend serves the direct solve only
  p.max_iterations = 1;
  CoarseReport c;
  for (auto _ : state) {
    state.PauseTiming();
    SurfaceMesh mesh = f.source.clone();
    state.ResumeTiming();
    c = align_coarse(mesh, *f.target, p);
  }
  state.SetLabel(state.range(1) ? "cholmod" : "eigen_ldlt");
  state.counters["nodes"] = c.nodes;
  state.counters["factor_s"] = c.seconds_factorisation / std::max(1, c.factorisations);
}
BENCHMARK(BM_Factorisation)
    ->Args({0, 0})
    ->Args({0, 1})
    ->Args({1, 0})
    ->Args({1, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1)
    ->Repetitions(3)
    ->ReportAggregatesOnly(true);

// One preconditioner solve (4N x 3, the per-coordinate factor of the PCG path) on the deformation graph
// of the source mesh, for a graph Laplacian plus a diagonal shift in 4 x 4 blocks (the pattern is what
// matters for the cost).
struct BlockSystem {
  DeformationGraph graph;
  BlockCholesky::Matrix lower;
};

BlockSystem block_system(int size) {
  const Fixture& f = fixture(size, 15);
  DeformationGraph g = build_deformation_graph(f.source, 4 * mean_edge_length(f.source), 4);
  const int N = int(g.n_nodes());
  std::vector<Eigen::Triplet<double, int>> t;
  for (int j = 0; j < N; ++j) {
    const double deg = double(g.neighbor_offset[std::size_t(j) + 1] - g.neighbor_offset[std::size_t(j)]);
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c <= r; ++c) t.emplace_back(4 * j + r, 4 * j + c, r == c ? deg + 1 : 0.1);
    for (Index q = g.neighbor_offset[std::size_t(j)]; q < g.neighbor_offset[std::size_t(j) + 1]; ++q)
      if (int(g.neighbors[q]) > j)
        for (int r = 0; r < 4; ++r) t.emplace_back(4 * int(g.neighbors[q]) + r, 4 * j + r, -1.0);
  }
  BlockCholesky::Matrix lower(4 * N, 4 * N);
  lower.setFromTriplets(t.begin(), t.end());
  return {std::move(g), std::move(lower)};
}

void BM_BlockCholeskySolve(benchmark::State& state) {
  const BlockSystem sys = block_system(int(state.range(0)));
  const tbb::global_control threads(tbb::global_control::max_allowed_parallelism, std::size_t(state.range(1)));
  const int N = int(sys.graph.n_nodes());
  BlockCholesky chol;
  chol.analyze(sys.graph.neighbor_offset, sys.graph.neighbors);
  chol.factorize(sys.lower);
  std::vector<double> x(std::size_t(12) * std::size_t(N), 1.0);
  double fastest = 1e30;  // the least disturbed run: robust when the machine is shared
  for (auto _ : state) {
    std::fill(x.begin(), x.end(), 1.0);
    const auto t0 = std::chrono::steady_clock::now();
    chol.solve3(x.data());
    benchmark::DoNotOptimize(x.data());
    fastest = std::min(fastest, bench::milliseconds_since(t0));
  }
  state.counters["fastest_ms"] = fastest;
  state.counters["nodes"] = N;
  state.counters["factor_nnz"] = double(chol.factor_nonzeros());
}
// {size, threads}
BENCHMARK(BM_BlockCholeskySolve)->ArgsProduct({{0, 2, 3}, {1, 2}})->ArgNames({"size", "threads"})->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime();

// One numeric factorisation of the same systems (the symbolic analysis is done once per graph).
void BM_BlockCholeskyFactorize(benchmark::State& state) {
  const BlockSystem sys = block_system(int(state.range(0)));
  const tbb::global_control threads(tbb::global_control::max_allowed_parallelism, std::size_t(state.range(1)));
  BlockCholesky chol;
  chol.analyze(sys.graph.neighbor_offset, sys.graph.neighbors);
  double fastest = 1e30;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    chol.factorize(sys.lower);
    fastest = std::min(fastest, bench::milliseconds_since(t0));
  }
  state.counters["fastest_ms"] = fastest;
  state.counters["nodes"] = double(sys.graph.n_nodes());
  state.counters["factor_nnz"] = double(chol.factor_nonzeros());
}
BENCHMARK(BM_BlockCholeskyFactorize)->ArgsProduct({{0, 2, 3}, {1, 2}})->ArgNames({"size", "threads"})->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime();

// CHOLMOD (supernodal, its own ordering) on the same systems, for comparison.
void BM_CholmodFactorize(benchmark::State& state) {
  const BlockSystem sys = block_system(int(state.range(0)));
  SparseCholesky chol(CholeskyBackend::Cholmod);
  chol.analyze(sys.lower);
  for (auto _ : state) chol.factorize(sys.lower);
  state.counters["factor_nnz"] = double(chol.factor_nonzeros());
  const Eigen::MatrixXd b = Eigen::MatrixXd::Ones(sys.lower.rows(), 3);
  const auto t0 = std::chrono::steady_clock::now();
  for (int i = 0; i < 10; ++i) benchmark::DoNotOptimize(chol.solve(b).data());
  state.counters["solve_ms"] = bench::milliseconds_since(t0) / 10;
}
BENCHMARK(BM_CholmodFactorize)->Arg(0)->Arg(2)->Arg(3)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime();

// The coarse stage's 12 x 12 block products (coarse.cpp: apply_system and the PCG's block Jacobi), 2,000 blocks as
// at 47k vertices, one thread: argument 0 is Eigen's `*` (its general matrix-vector kernel), 1 `lazyProduct` (an
// unrolled product, what coarse.cpp uses). "sum" is the result's sum: the same to the bit for both.
void BM_Block12Product(benchmark::State& state) {
  using Mat12 = Eigen::Matrix<double, 12, 12>;
  using Vec12 = Eigen::Matrix<double, 12, 1>;
  constexpr int kBlocks = 2000;
  std::vector<Mat12> blocks(kBlocks);
  std::srand(1);
  for (Mat12& b : blocks) b.setRandom();
  const Eigen::VectorXd x = Eigen::VectorXd::Random(12 * kBlocks);
  Eigen::VectorXd y(12 * kBlocks);
  const bool lazy = state.range(0) != 0;
  for (auto _ : state) {
    for (int j = 0; j < kBlocks; ++j)
      y.segment<12>(12 * j) = lazy ? Vec12(blocks[j].lazyProduct(x.segment<12>(12 * j))) : Vec12(blocks[j] * x.segment<12>(12 * j));
    benchmark::DoNotOptimize(y.data());
  }
  state.counters["sum"] = y.sum();
}
BENCHMARK(BM_Block12Product)->Arg(0)->Arg(1)->ArgName("lazy")->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace topotrack

BENCHMARK_MAIN();
