// Read and write throughput of the io layer on generated closed meshes of 10k to 1M triangles (files written
// once per size into a temporary folder), plus a real frame of ../shared/data when present.
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <numbers>

#include "io/mesh_reader.hpp"
#include "io/obj_reader.hpp"
#include "io/obj_writer.hpp"
#include "io/ply_reader.hpp"
#include "io/ply_writer.hpp"

namespace topotrack {
namespace {

namespace fs = std::filesystem;

// A closed UV sphere with about `triangles` triangles (2 * rings * segments).
MeshData sphere(std::int64_t triangles) {
  const int rings = std::max(2, static_cast<int>(std::sqrt(static_cast<double>(triangles) / 4.0)));
  const int segments = std::max(3, static_cast<int>(triangles / (2 * rings)));
  MeshData m;
  m.positions.push_back({0, 0, 1});
  for (int r = 1; r < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      const double t = std::numbers::pi * r / rings, p = 2 * std::numbers::pi * s / segments;
      m.positions.push_back({std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t)});
    }
  m.positions.push_back({0, 0, -1});
  const auto at = [&](int r, int s) -> std::int64_t { return 1 + (r - 1) * segments + s % segments; };
  const auto south = static_cast<std::int64_t>(m.positions.size() - 1);
  for (int s = 0; s < segments; ++s) m.triangles.push_back({0, at(1, s), at(1, s + 1)});
  for (int r = 1; r + 1 < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      m.triangles.push_back({at(r, s), at(r + 1, s), at(r + 1, s + 1)});
      m.triangles.push_back({at(r, s), at(r + 1, s + 1), at(r, s + 1)});
    }
  for (int s = 0; s < segments; ++s) m.triangles.push_back({south, at(rings - 1, s + 1), at(rings - 1, s)});
  return m;
}

// Generated meshes and their files, made once per size and removed at exit.
class Files {
 public:
  static Files& get() {
    static Files f;
    return f;
  }
  ~Files() {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  const MeshData& mesh(std::int64_t n) {
    auto it = meshes_.find(n);
    if (it == meshes_.end()) it = meshes_.emplace(n, sphere(n)).first;
    return it->second;
  }
  fs::path file(std::int64_t n, const std::string& kind) {
    const fs::path p = dir_ / (kind + "_" + std::to_string(n) + (kind == "obj" ? ".obj" : ".ply"));
    if (!fs::exists(p)) {
      if (kind == "obj")
        write_obj(p, mesh(n));
      else
        write_ply(p, mesh(n), PlyWriteOptions{kind == "ascii"});
    }
    return p;
  }

 private:
  Files() : dir_(fs::temp_directory_path() / ("topotrack_io_bench_" + std::to_string(::getpid()))) {
    fs::create_directories(dir_);
  }
  fs::path dir_;
  std::map<std::int64_t, MeshData> meshes_;
};

void count(benchmark::State& state, const MeshData& m, std::size_t bytes) {
  state.counters["triangles"] = static_cast<double>(m.triangle_count());
  state.counters["vertices"] = static_cast<double>(m.vertex_count());
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * m.triangle_count()));
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * bytes));
}

void read_bench(benchmark::State& state, const std::string& kind) {
  const fs::path p = Files::get().file(state.range(0), kind);
  MeshData m;
  for (auto _ : state) {
    m = read_mesh(p);
    benchmark::DoNotOptimize(m.positions.data());
  }
  count(state, m, fs::file_size(p));
}

void BM_ReadPlyBinary(benchmark::State& state) { read_bench(state, "binary"); }
void BM_ReadPlyAscii(benchmark::State& state) { read_bench(state, "ascii"); }
void BM_ReadObj(benchmark::State& state) { read_bench(state, "obj"); }

void write_bench(benchmark::State& state, const std::string& kind) {
  const MeshData& m = Files::get().mesh(state.range(0));
  const fs::path p =
      Files::get().file(state.range(0), kind).replace_extension(kind == "obj" ? ".w.obj" : ".w.ply");
  for (auto _ : state) {
    if (kind == "obj")
      write_obj(p, m);
    else
      write_ply(p, m, PlyWriteOptions{kind == "ascii"});
  }
  count(state, m, fs::file_size(p));
}

void BM_WritePlyBinary(benchmark::State& state) { write_bench(state, "binary"); }
void BM_WritePlyAscii(benchmark::State& state) { write_bench(state, "ascii"); }
void BM_WriteObj(benchmark::State& state) { write_bench(state, "obj"); }

// Encoding alone, without the file system (write_* add the fsync of the atomic write).
void BM_EncodePlyBinary(benchmark::State& state) {
  const MeshData& m = Files::get().mesh(state.range(0));
  std::size_t bytes = 0;
  for (auto _ : state) {
    const std::string s = encode_ply(m);
    bytes = s.size();
    benchmark::DoNotOptimize(s.data());
  }
  count(state, m, bytes);
}

// The largest real frame: elephant, 42k vertices.
void BM_ReadRealFrame(benchmark::State& state) {
  const fs::path p = fs::path(TOPOTRACK_SHARED_DIR) / "data" / "elephant" / "elephant.0001.ply";
  if (!fs::exists(p)) {
    state.SkipWithError("../shared/data/elephant is absent");
    return;
  }
  MeshData m;
  for (auto _ : state) {
    m = read_ply(p);
    benchmark::DoNotOptimize(m.positions.data());
  }
  count(state, m, fs::file_size(p));
}

constexpr std::int64_t kMin = 10'000, kMax = 1'000'000;
BENCHMARK(BM_ReadPlyBinary)
    ->RangeMultiplier(10)
    ->Range(kMin, kMax)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_ReadPlyAscii)
    ->RangeMultiplier(10)
    ->Range(kMin, kMax)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_ReadObj)->RangeMultiplier(10)->Range(kMin, kMax)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_WritePlyBinary)
    ->RangeMultiplier(10)
    ->Range(kMin, kMax)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_WritePlyAscii)
    ->RangeMultiplier(10)
    ->Range(kMin, kMax)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_WriteObj)->RangeMultiplier(10)->Range(kMin, kMax)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_EncodePlyBinary)
    ->RangeMultiplier(10)
    ->Range(kMin, kMax)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_ReadRealFrame)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace topotrack

BENCHMARK_MAIN();
