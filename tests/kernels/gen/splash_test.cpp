// `gen splash` (kernels/gen/splash.hpp): a drop falling into a pool, with the topology changes of a real
// splash on cue; its field must be a valid input for sample_implicit (1-Lipschitz) and move without pops.
#include <gtest/gtest.h>

#include <random>

#include "kernels/gen/splash.hpp"
#include "kernels/gen/synthetic.hpp"
#include "kernels/mesh/mesh_convert.hpp"
#include "kernels/mesh/mesh_queries.hpp"
#include "kernels/sdf/extraction_grid.hpp"

namespace topotrack {
namespace {

Vec3 random_point(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const Vec3 lo = SplashScene::box_min(), hi = SplashScene::box_max();
  return lo + (hi - lo).cwiseProduct(Vec3(u(rng), u(rng), u(rng)));
}

TEST(Splash, FieldIsOneLipschitzInSpace) {
  const SplashScene scene(3);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0), step(-0.05, 0.05);
  for (int i = 0; i < 20000; ++i) {
    const double t = u(rng);
    const Vec3 x = random_point(rng), y = x + Vec3(step(rng), step(rng), step(rng));
    ASSERT_LE(std::abs(scene.field(t, x) - scene.field(t, y)), (x - y).norm() * (1 + 1e-9) + 1e-12)
        << "t " << t << " x " << x.transpose();
  }
}

TEST(Splash, FieldMovesWithoutPops) {
  // The fastest shape (the falling drop) moves ~5 units per unit t: a field that changes by more than
  // 0.01 over dt = 1e-4 would be a pop (something appearing or vanishing between two frames).
  const SplashScene scene(1);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0 - 1e-4);
  double worst = 0;
  for (int i = 0; i < 40000; ++i) {
    const double t = u(rng);
    const Vec3 x = random_point(rng);
    worst = std::max(worst, std::abs(scene.field(t + 1e-4, x) - scene.field(t, x)));
  }
  EXPECT_LT(worst, 0.01);
  // Phase boundaries exactly, where a shape starts or stops.
  for (const double t : {0.1224, 0.1225, 0.2025, 0.3, 0.45, 0.62, 0.6225, 0.85, 0.9999}) {
    for (int i = 0; i < 4000; ++i) {
      const Vec3 x = random_point(rng);
      ASSERT_LT(std::abs(scene.field(t + 1e-4, x) - scene.field(t, x)), 0.01) << "t " << t << " x " << x.transpose();
    }
  }
}

TEST(Splash, DropsAreLiquid) {
  const SplashScene scene(2);
  for (int n = 0; n <= 100; ++n) {
    const double t = n / 100.0;
    for (const SplashDrop& d : scene.drops(t)) {
      EXPECT_GT(d.radius, 0);
      EXPECT_LT(scene.field(t, d.center), 0) << "t " << t;
      EXPECT_TRUE((d.center.array() > SplashScene::box_min().array()).all());
      EXPECT_TRUE((d.center.array() < SplashScene::box_max().array()).all());
    }
  }
}

Index components_at(const SyntheticScene& scene, int frame) {
  SurfaceMesh s = to_surface_mesh(scene.frame_mesh(frame));
  s.validate(true);  // closed 2-manifold, or throws
  return connected_components(s);
}

TEST(Splash, TopologyChangesOnCue) {
  SyntheticParams p;
  p.kind = SyntheticKind::kSplash;
  p.frames = 101;  // frame n is t = (n - 1) / 100
  p.resolution = 96;
  const SyntheticScene scene(p);
  EXPECT_EQ(components_at(scene, 1), 2);    // the drop above the pool
  EXPECT_EQ(components_at(scene, 15), 1);   // merged (t 0.14)
  EXPECT_GE(components_at(scene, 46), 10);  // rim droplets in flight (t 0.45)
  EXPECT_GE(components_at(scene, 81), 2);   // the jet's drop in flight (t 0.80)
  EXPECT_EQ(components_at(scene, 101), 1);  // everything fell back (t 1)
}

// The tracker finds the grid a frame was extracted on (tracker.extraction_grid) from the coordinates its
// vertices share. The pool's flat walls and floor, off the grid's planes, share theirs far more often than any
// lattice plane does: the spacing must still be found, in the first frame (the drop above a still pool) as in
// the crown's.
TEST(Splash, FramesAreRecognisedAsExtractedOnTheirGrid) {
  SyntheticParams p;
  p.kind = SyntheticKind::kSplash;
  p.frames = 60;
  const SyntheticScene scene(p);
  for (const int frame : {1, 30}) {
    MeshData m = scene.frame_mesh(frame);
    for (auto& q : m.positions)
      for (double& c : q) c = double(float(c));  // as a PLY stores them
    const SurfaceMesh s = to_surface_mesh(m);
    const auto g = extraction_grid(s.positions(), mean_edge_length(s));
    ASSERT_TRUE(g) << "frame " << frame;
    EXPECT_NEAR(g->spacing, scene.voxel_size(), 1e-6 * scene.voxel_size()) << "frame " << frame;
    EXPECT_EQ(g->origin, Vec3::Zero()) << "frame " << frame;
  }
}

}  // namespace
}  // namespace topotrack
