#pragma once
//! A drop splashing into a pool (`topotrack gen splash`, issue 7: "a checker texture stuck to ... a splash"):
//! the classic milk-drop sequence as an implicit function of time, so every topology change a fluid
//! simulation produces happens on cue, at any resolution, reproducibly:
//!   t 0.00-0.13  a drop falls onto a pool (two components), merges with it (one);
//!   t 0.13-0.60  a crater opens and a crown wall rises around it; droplets grow out of the crown's rim and
//!                pinch off (splits), fly outward and fall back into the pool (merges) by t ~0.85;
//!   t 0.50-1.00  the crown sinks back, a Worthington jet rises in the middle, sheds a drop from its tip
//!                (split), sinks, and the drop falls back (merge).
//! Not a simulation: shapes are signed distance functions of spheres, capsules and a wall of revolution,
//! blended by smooth minima (1-Lipschitz, as sample_implicit requires). Units: the pool is 1.7 wide.
#include <vector>

#include "kernels/mesh/surface_mesh.hpp"

namespace topotrack {

struct SplashDrop {
  Vec3 center;
  double radius = 0;
};

class SplashScene {
public:
  //! `seed` jitters the rim droplets' directions, sizes and speeds (deterministically).
  explicit SplashScene(unsigned seed = 1);

  //! Negative inside the liquid at normalised time t in [0, 1].
  double field(double t, const Vec3& x) const;
  //! The free-flying spherical drops at time t (the falling drop, rim droplets, the jet's drop), those
  //! that exist at t, whether or not they have pinched off yet: for ground truth and tests.
  std::vector<SplashDrop> drops(double t) const;
  //! min and max corners of a box holding the liquid at every t (with a margin).
  static Vec3 box_min();
  static Vec3 box_max();

private:
  struct Droplet {
    double angle = 0, radius = 0, speed_out = 0, speed_up = 0;
  };
  std::vector<Droplet> droplets_;
};

}  // namespace topotrack
