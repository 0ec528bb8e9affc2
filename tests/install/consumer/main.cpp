// An example simulation post-processor embedding topotrack through its installed CMake package
// (find_package(topotrack); target_link_libraries(... topotrack::engine)). It streams level sets
// straight from "the simulation" (here: a sphere moving along x, made by OpenVDB) into a Tracker, one
// frame at a time, and reads back the tracked mesh and that frame's events. No files involved.
#include <openvdb/tools/LevelSetSphere.h>

#include <cstdio>

#include "engine/tracker.hpp"
#include "kernels/mesh/mesh_queries.hpp"

int main() {
  using namespace topotrack;
  openvdb::initialize();
  Tracker tracker;  // the paper's parameters (profiles/default.json)
  const float voxel = 0.05f;
  for (int frame = 1; frame <= 3; ++frame) {
    // A "simulation" output: a narrow-band level set, negative inside.
    const auto phi = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(
        0.5f, openvdb::Vec3f(0.04f * float(frame), 0.0f, 0.0f), voxel, 3.0f);
    const FrameReport& r = tracker.add_frame(*phi, "frame " + std::to_string(frame));
    const SurfaceMesh& m = tracker.mesh();
    m.validate(/*require_closed=*/true);
    std::printf("consumer: frame %d: %zu vertices, %zu components, euler %ld, %zu events, %.3f s\n", frame,
                m.n_vertices(), r.components, euler_characteristic(m), tracker.events().size(), r.seconds.total);
    if (r.components != 1 || euler_characteristic(m) != 2) return 1;
  }
  std::printf("consumer: tracked sphere euler 2\n");
  return 0;
}
