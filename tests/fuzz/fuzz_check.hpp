#pragma once
// Shared by the fuzz targets: what a reader's successful result must satisfy, and the one way a fuzz target
// reports a broken promise (abort, which libFuzzer records as a crash with the input).
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "io/mesh_data.hpp"
#include "kernels/mesh/mesh_convert.hpp"

namespace topotrack::fuzz {

[[noreturn]] inline void broken(const char* what) {
  std::fprintf(stderr, "fuzz: broken promise: %s\n", what);
  std::abort();
}

//! The readers' documented guarantees for a MeshData they return: vertices present, finite coordinates,
//! every index in range, ids and attributes one per vertex.
inline void check_mesh_data(const MeshData& d) {
  const auto n = std::int64_t(d.positions.size());
  if (n == 0) broken("no vertices");
  for (const auto& p : d.positions)
    for (double c : p)
      if (!std::isfinite(c)) broken("non-finite coordinate");
  for (const auto& t : d.triangles)
    for (auto i : t)
      if (i < 0 || i >= n) broken("index out of range");
  if (d.ids && std::int64_t(d.ids->size()) != n) broken("ids not one per vertex");
  for (const auto& a : d.attributes)
    if (a.width < 1 || a.values.size() != std::size_t(a.width) * std::size_t(n)) broken("attribute size");
}

//! What the frame loader does next: the half-edge mesh and its closed-manifold check, which may reject
//! (InvalidInput, TopologyError) but must not crash.
inline void build_mesh(const MeshData& d) {
  try {
    SurfaceMesh m = to_surface_mesh(d);
    m.validate(/*require_closed=*/false);
  } catch (const Error&) {
  }
}

}  // namespace topotrack::fuzz
