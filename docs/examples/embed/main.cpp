// A simulation post-processor embedding topotrack through its installed CMake package
// (find_package(topotrack); target_link_libraries(... topotrack::engine)); the whole program is this file
// and CMakeLists.txt beside it, built and run by the test suite (tests/install).
//
// "The simulation" here is two blobs of liquid that start as one and drift apart, given as OpenVDB
// narrow-band level sets (negative inside), one per frame, as a solver hands them over. Each frame goes
// straight into a Tracker; back come the tracked mesh (vertex i is the same surface point as vertex i of
// the frame before, unless an event says otherwise), the per-vertex velocities and that frame's event
// list. No files are read or written.
#include <openvdb/tools/Composite.h>
#include <openvdb/tools/LevelSetSphere.h>

#include <algorithm>
#include <cstdio>
#include <string>

#include "engine/profile.hpp"
#include "engine/tracker.hpp"
#include "kernels/mesh/mesh_queries.hpp"

namespace {

// Frame n of the simulation: two spheres of radius 0.5 whose centres move apart along x.
openvdb::FloatGrid::Ptr simulation_frame(int n) {
  const float voxel = 0.04f, gap = 0.35f + 0.06f * float(n);
  auto a = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(0.5f, openvdb::Vec3f(-gap, 0, 0), voxel, 3.0f);
  auto b = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(0.5f, openvdb::Vec3f(gap, 0.1f, 0), voxel, 3.0f);
  openvdb::tools::csgUnion(*a, *b);  // the union is left in a
  return a;
}

}  // namespace

int main() {
  using namespace topotrack;
  openvdb::initialize();
  // A bundled profile (profiles/fluid.json, installed with the package); apply_setting(params, "name=value")
  // overrides one parameter as `topotrack track --set` does.
  Tracker tracker(load_profile("fluid"));
  std::size_t components_before = 0;
  for (int n = 1; n <= 8; ++n) {
    const FrameReport& r = tracker.add_frame(*simulation_frame(n), "frame " + std::to_string(n));
    const SurfaceMesh& m = tracker.mesh();
    m.validate(/*require_closed=*/true);
    double fastest = 0;
    for (const Vec3& v : tracker.velocities()) fastest = std::max(fastest, v.norm());
    const EventList events = tracker.take_events();  // this frame's events, handed over
    std::printf("consumer: frame %d: %zu vertices, %zu components, euler %ld, %zu events (%zu patch creations), "
                "fastest vertex %.3f per frame, %.3f s\n",
                n, m.n_vertices(), r.components, euler_characteristic(m), events.size(),
                r.events_by_kind[int(EventKind::PatchCreate) - 1], fastest, r.seconds.total);
    if (r.components != connected_components(m)) return 1;
    if (n > 1 && r.components < components_before) return 1;  // the blobs only ever part
    components_before = r.components;
  }
  if (components_before != 2) return 1;
  std::printf("consumer: one blob became two, tracked\n");
  return 0;
}
