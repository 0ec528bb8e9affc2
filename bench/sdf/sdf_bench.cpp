// signed_distance and marching_cubes on closed meshes of 10k..400k vertices (the §4.3 topology step
// runs both on the tracked mesh every frame). Input: a bumpy torus with about N vertices; the voxel size
// is its mean edge length, so marching cubes returns a mesh of comparable size.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstring>
#include <numbers>

#include "kernels/gen/synthetic.hpp"
#include "kernels/sdf/marching_cubes.hpp"
#include "kernels/sdf/narrow_band.hpp"
#include "kernels/sdf/signed_distance.hpp"

namespace topotrack {
namespace {

struct Input {
  std::vector<Vec3> positions;
  std::vector<std::array<Index, 3>> triangles;
  double edge = 0;
};

Input bumpy_torus(std::int64_t vertices) {
  const int m = std::max(8, int(std::sqrt(double(vertices) / 3.0)));
  const int n = int(vertices / m);
  Input in;
  const double two_pi = 2 * std::numbers::pi;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < m; ++j) {
      const double u = two_pi * i / n, v = two_pi * j / m;
      const double r = 0.35 + 0.03 * std::sin(7 * u) * std::sin(5 * v);
      in.positions.emplace_back((1 + r * std::cos(v)) * std::cos(u), (1 + r * std::cos(v)) * std::sin(u), r * std::sin(v));
    }
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < m; ++j) {
      const Index a = Index(i * m + j), b = Index(((i + 1) % n) * m + j), c = Index(((i + 1) % n) * m + (j + 1) % m),
                  d = Index(i * m + (j + 1) % m);
      in.triangles.push_back({a, b, c});
      in.triangles.push_back({a, c, d});
    }
  double sum = 0;
  for (const auto& t : in.triangles) sum += (in.positions[t[0]] - in.positions[t[1]]).norm();
  in.edge = sum / double(in.triangles.size());
  return in;
}

void BM_SignedDistance(benchmark::State& state) {
  const Input in = bumpy_torus(state.range(0));
  std::size_t voxels = 0;
  for (auto _ : state) {
    auto grid = signed_distance(in.positions, in.triangles, in.edge);
    voxels = grid->activeVoxelCount();
    benchmark::DoNotOptimize(grid);
  }
  state.counters["vertices"] = double(in.positions.size());
  state.counters["active_voxels"] = double(voxels);
}

// Times signed_distance with `p` (its voxel size set to the input's edge length) and reports the split.
void run_signed_distance(benchmark::State& state, SignedDistanceParams p) {
  const Input in = bumpy_torus(state.range(0));
  p.voxel_size = in.edge;
  SignedDistanceReport r;
  for (auto _ : state) {
    auto grid = signed_distance(in.positions, in.triangles, p, &r);
    benchmark::DoNotOptimize(grid);
  }
  state.counters["vertices"] = double(in.positions.size());
  state.counters["active_voxels"] = double(r.active_voxels);
  state.counters["seconds_volume"] = r.seconds_volume;
  state.counters["seconds_sign"] = r.seconds_sign;
  state.counters["seconds_thicken"] = r.seconds_thicken;
}

// The tracker's configuration (profiles/default.json: half width 3, exact sign within 0.25 voxel, §4.3),
// with the half width as the second argument in tenths of a voxel (what the consumers need is measured
// against it).
void BM_SignedDistanceTracker(benchmark::State& state) {
  SignedDistanceParams p;
  p.half_width_voxels = double(state.range(1)) / 10;
  p.exact_sign_band_voxels = 0.25;
  run_signed_distance(state, p);
}

// The two methods side by side at the tracker's configuration: second argument 0 = OpenVDB meshToVolume with
// the exact-sign pass (the method before narrow_band.hpp), 1 = the hand-written narrow band; third argument
// the half width in tenths of a voxel.
void BM_SignedDistanceMethod(benchmark::State& state) {
  SignedDistanceParams p;
  p.method = state.range(1) == 0 ? SdfMethod::kOpenVdb : SdfMethod::kNarrowBand;
  p.half_width_voxels = double(state.range(2)) / 10;
  p.exact_sign_band_voxels = 0.25;
  run_signed_distance(state, p);
}

// The narrow band alone with its phases; second argument the half width in tenths of a voxel, third 0 for the
// scalar distance loop, 1 for the AVX2 one (the before / after in one run: the checksum must not change).
void BM_NarrowBand(benchmark::State& state) {
  const Input in = bumpy_torus(state.range(0));
  NarrowBandReport r;
  openvdb::FloatGrid::Ptr grid;
  for (auto _ : state) {
    NarrowBandParams p{in.edge, double(state.range(1)) / 10};
    p.vectorized = state.range(2) != 0;
    grid = narrow_band_signed_distance(in.positions, in.triangles, p, &r);
    benchmark::DoNotOptimize(grid);
  }
  // A checksum of the active values (bits and coordinates), so that a faster version can show it is unchanged.
  std::uint64_t sum = 0;
  for (auto it = grid->cbeginValueOn(); it; ++it) {
    std::uint32_t bits = 0;
    const float v = *it;
    std::memcpy(&bits, &v, sizeof bits);
    const openvdb::Coord c = it.getCoord();
    sum = sum * 1000003u + (bits ^ std::uint64_t(std::uint32_t(c.x() * 73856093 ^ c.y() * 19349663 ^ c.z() * 83492791)) << 20);
  }
  state.counters["checksum"] = double(sum % (std::uint64_t(1) << 50));
  state.counters["vertices"] = double(in.positions.size());
  state.counters["active_voxels"] = double(r.active_voxels);
  state.counters["pairs"] = double(r.triangle_blocks);
  state.counters["blocks"] = double(r.blocks);
  state.counters["vectorized"] = r.vectorized;
  state.counters["bin_s"] = r.seconds_bin;
  state.counters["crossings_s"] = r.seconds_crossings;
  state.counters["blocks_s"] = r.seconds_blocks;
  state.counters["tree_s"] = r.seconds_tree;
}

// Resurfacing's configuration (kernels/gen/resurface.hpp): winding-number sign within 3 voxels and
// thin parts thickened to 1.75 voxels (ResurfaceParams' defaults).
void BM_SignedDistanceResurface(benchmark::State& state) {
  SignedDistanceParams p;
  p.half_width_voxels = 3;
  p.exact_sign_band_voxels = 3;
  p.sign_method = SignMethod::kWindingNumber;
  p.min_thickness_voxels = 1.75;
  run_signed_distance(state, p);
}

void BM_MarchingCubes(benchmark::State& state) {
  const Input in = bumpy_torus(state.range(0));
  auto grid = signed_distance(in.positions, in.triangles, in.edge);
  std::size_t out_vertices = 0;
  for (auto _ : state) {
    MeshData m = marching_cubes(*grid);
    out_vertices = m.vertex_count();
    benchmark::DoNotOptimize(m);
  }
  state.counters["vertices"] = double(in.positions.size());
  state.counters["mc_vertices"] = double(out_vertices);
}

// One frame of the blobs sequence (field sampling + marching cubes) at 1x, 2x, 4x the default resolution.
void BM_GenBlobsFrame(benchmark::State& state) {
  SyntheticParams p;
  p.kind = SyntheticKind::kBlobs;
  p.frames = 60;
  p.resolution = int(state.range(0));
  const SyntheticScene scene(p);
  std::size_t vertices = 0;
  for (auto _ : state) {
    MeshData m = scene.frame_mesh(7);
    vertices = m.vertex_count();
    benchmark::DoNotOptimize(m);
  }
  state.counters["mc_vertices"] = double(vertices);
}

BENCHMARK(BM_GenBlobsFrame)->Arg(96)->Arg(192)->Arg(384)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_SignedDistance)->Arg(10000)->Arg(40000)->Arg(100000)->Arg(400000)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_SignedDistanceTracker)
    ->ArgsProduct({{10000, 40000, 100000, 400000}, {30}})
    ->Args({100000, 20})
    ->Args({100000, 15})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_SignedDistanceMethod)
    ->ArgsProduct({{10000, 100000, 400000}, {0, 1}, {30}})
    ->ArgsProduct({{100000}, {0, 1}, {20}})
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()
    ->UseRealTime();
BENCHMARK(BM_NarrowBand)->ArgsProduct({{100000}, {15, 18, 20, 30}, {0, 1}})->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();
BENCHMARK(BM_SignedDistanceResurface)->Arg(10000)->Arg(100000)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_MarchingCubes)->Arg(10000)->Arg(40000)->Arg(100000)->Arg(400000)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace topotrack

BENCHMARK_MAIN();
