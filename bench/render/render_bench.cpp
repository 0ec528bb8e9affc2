// Speed of the Embree ray tracer (kernels/render): target a 1024x1024 render of 100k triangles in <= 1 s on
// 2 cores. Mesh: a bumpy torus of the given triangle count, camera fitted to it, 1 ray per pixel.
#include <benchmark/benchmark.h>

#include <cmath>
#include <numbers>

#include "kernels/render/raytracer.hpp"

namespace topotrack {
namespace {

RenderMesh bumpy_torus(int triangles) {
  const int m = std::max(8, int(std::sqrt(triangles / 2.0 / 2.5)));
  const int n = std::max(8, triangles / (2 * m));
  RenderMesh mesh;
  const double R = 1.0, r = 0.4, pi = std::numbers::pi;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < m; ++j) {
      const double u = 2 * pi * i / n, v = 2 * pi * j / m;
      const double rr = r * (1 + 0.08 * std::sin(7 * u) * std::sin(5 * v));
      mesh.positions.emplace_back((R + rr * std::cos(v)) * std::cos(u), (R + rr * std::cos(v)) * std::sin(u),
                                  rr * std::sin(v));
      mesh.colors.push_back(float(0.5 + 0.5 * std::sin(3 * u)));
      mesh.colors.push_back(float(0.5 + 0.5 * std::cos(2 * v)));
      mesh.colors.push_back(0.6f);
    }
  auto id = [&](int i, int j) { return Index(((i + n) % n) * m + (j + m) % m); };
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < m; ++j) {
      mesh.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      mesh.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return mesh;
}

Camera camera_for(const RenderMesh& mesh) {
  BoundingBox b;
  for (const Vec3& p : mesh.positions) b.extend(p);
  return fit_camera(b, {.azimuth_deg = 30, .elevation_deg = 35});
}

// Scene build + trace + shade, as `topotrack render` does per frame.
void BM_Render(benchmark::State& state) {
  const RenderMesh mesh = bumpy_torus(int(state.range(0)));
  const Camera cam = camera_for(mesh);
  RenderParams p;
  p.width = p.height = int(state.range(1));
  p.samples_per_axis = int(state.range(2));
  p.wireframe = state.range(3) != 0;
  double covered = 0;
  for (auto _ : state) {
    RenderReport rep;
    Image im = render(RenderMesh(mesh), cam, p, &rep);
    benchmark::DoNotOptimize(im.rgb.data());
    covered = rep.covered_pixels;
  }
  state.counters["triangles"] = double(mesh.triangles.size());
  state.counters["covered_px"] = covered;
  state.counters["rays_per_s"] =
      benchmark::Counter(double(p.width) * p.height * p.samples_per_axis * p.samples_per_axis,
                         benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_Render)
    ->ArgNames({"tris", "px", "spp_axis", "wire"})
    ->Args({10000, 1024, 1, 0})
    ->Args({100000, 1024, 1, 0})
    ->Args({400000, 1024, 1, 0})
    ->Args({100000, 1024, 1, 1})
    ->Args({100000, 1024, 2, 0})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// BVH build alone.
void BM_BuildScene(benchmark::State& state) {
  const RenderMesh mesh = bumpy_torus(int(state.range(0)));
  for (auto _ : state) {
    RenderScene scene{RenderMesh(mesh)};
    benchmark::DoNotOptimize(&scene);
  }
  state.counters["triangles"] = double(mesh.triangles.size());
}
BENCHMARK(BM_BuildScene)->Arg(10000)->Arg(100000)->Arg(400000)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace topotrack

BENCHMARK_MAIN();
