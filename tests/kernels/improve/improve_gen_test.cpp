// improve_mesh (§4.1) on `gen` marching-cubes output (kernels/gen synthetic kinds, as `topotrack gen`
// writes them): the targets hold with no exemption, and improving the result again changes nothing.
#include <gtest/gtest.h>

#include <string>

#include "kernels/gen/synthetic.hpp"
#include "kernels/improve/improve.hpp"
#include "kernels/mesh/mesh_convert.hpp"
#include "tests/kernels/improve/improve_targets.hpp"

namespace topotrack {
namespace {

// The synthetic kinds at their default resolution (10k-20k vertices), first and middle frame.
TEST(ImproveGen, SyntheticFramesMeetTargets) {
  for (const SyntheticKind kind : {SyntheticKind::kBlobs, SyntheticKind::kMorph, SyntheticKind::kMetaballs}) {
    SyntheticParams params;
    params.kind = kind;
    const SyntheticScene scene(params);
    for (const int frame : {1, scene.frames() / 2}) {
      const std::string name = std::string(synthetic_kind_name(kind)) + "." + std::to_string(frame);
      const SurfaceMesh in = to_surface_mesh(scene.frame_mesh(frame));
      SurfaceMesh out = in.clone();
      const ImproveReport rep = improve_mesh(out);
      test::expect_targets(in, out, rep, name);
      ImproveParams again;
      again.target_edge_length = std::sqrt(rep.min_edge_length * rep.max_edge_length);
      EventList events;
      const ImproveReport rep2 = improve_mesh(out, again, &events);
      EXPECT_EQ(events.size() + rep2.flips + rep2.relaxations, 0u) << name;
    }
  }
}

}  // namespace
}  // namespace topotrack
