#include "kernels/registration/projection.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace topotrack {

void project_to_closest(SurfaceMesh& mesh, const TargetSurface& target) {
  auto& pos = mesh.positions();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, pos.size(), 256), [&](const auto& r) {
    for (std::size_t v = r.begin(); v != r.end(); ++v) {
      if (mesh.is_deleted(Vertex(Index(v)))) continue;
      const TargetSurface::Hit h = target.closest_point(pos[v]);
      if (h.hit) pos[v] = h.point;
    }
  });
}

}  // namespace topotrack
