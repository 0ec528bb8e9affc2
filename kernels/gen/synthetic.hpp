#pragma once
//! Synthetic input sequences with ground truth (issue 2 item 7): each frame is the marching-cubes
//! surface of an implicit field on a fixed voxel grid, so the connectivity differs every frame while the
//! shape moves smoothly (an incoherent sequence, as the tracker's input S_n of Algorithm 1).
//!  - blobs:     three blended blobs rotating rigidly about the origin, one full turn over the sequence
//!               (after Stam and Schmidt 2011); ground truth is the rotation of every frame;
//!  - morph:     a linear blend of signed distance functions of shapes of different genus: torus (genus 1)
//!               -> two spheres (mid-way) -> one sphere (last frame);
//!  - metaballs: four balls that start merged, fly apart (splitting into up to four components) and merge
//!               again while the group turns;
//!  - splash:    a drop falling into a pool: merge, crown, rim droplets pinching off and falling back, a
//!               jet shedding a drop (kernels/gen/splash.hpp); ground truth is the free drops of each frame.
#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "io/mesh_data.hpp"
#include "kernels/gen/implicit_grid.hpp"
#include "kernels/gen/splash.hpp"

namespace topotrack {

enum class SyntheticKind { kBlobs, kMorph, kMetaballs, kSplash };
//! "blobs", "morph", "metaballs", "splash". \throw UsageError for any other name.
SyntheticKind synthetic_kind_from_name(const std::string& name);
const char* synthetic_kind_name(SyntheticKind kind);

struct SyntheticParams {
  SyntheticKind kind = SyntheticKind::kBlobs;
  int frames = 60;
  //! Voxels across the scene's bounding box; 0 picks the kind's default (about 10k-20k vertices per frame).
  //! Vertex counts grow with its square: 4x the default gives 150k-300k.
  int resolution = 0;
  unsigned seed = 1;  //!< perturbs the shapes' sizes and placements (deterministically)
};

//! x_n = rotation * (x_1 - center) + center.
struct RigidMotion {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Vec3 center = Vec3::Zero();
};

//! One ball of the metaballs scene in one frame.
struct Ball {
  Vec3 center;
  double radius = 0;
};

class SyntheticScene {
public:
  //! \throw InvalidInput on frames < 1 or resolution not in [8, 4096] (0 = default).
  explicit SyntheticScene(const SyntheticParams& params);

  int frames() const { return params_.frames; }
  int resolution() const { return resolution_; }
  SyntheticKind kind() const { return params_.kind; }
  //! The box every frame's surface lies in (with a margin), the same for all frames.
  const BoundingBox& box() const { return box_; }
  double voxel_size() const { return voxel_size_; }

  //! The implicit function of frame n (1-based), negative inside, 1-Lipschitz.
  double field(int frame, const Vec3& x) const;
  //! The surface of frame n: a closed 2-manifold. \throw InvalidInput for a frame out of range.
  MeshData frame_mesh(int frame) const;

  //! blobs: the rigid motion taking frame 1 onto frame n.
  RigidMotion blobs_motion(int frame) const;
  //! morph: the blend stage (0: torus -> two spheres, 1: two spheres -> sphere) and weight in [0, 1].
  std::pair<int, double> morph_blend(int frame) const;
  //! metaballs: the balls of frame n.
  std::vector<Ball> metaballs(int frame) const;
  //! splash: the scene (its drops(t) at t = (n - 1) / (frames - 1)).
  const SplashScene& splash() const { return splash_; }

  //! Everything needed to check a result: blobs {"frames": [{"frame", "rotation" (3x3 rows), "center"}]},
  //! morph {"frames": [{"frame", "stage", "weight"}]}, metaballs {"frames": [{"frame", "balls": [{center, radius}]}]},
  //! splash {"frames": [{"frame", "time", "drops": [{center, radius}]}]}.
  nlohmann::json ground_truth() const;

private:
  double time(int frame) const;  // 0 at frame 1, 1 at the last frame
  void check_frame(int frame) const;

  SyntheticParams params_;
  int resolution_ = 0;
  BoundingBox box_;
  double voxel_size_ = 0;
  struct Capsule {
    Vec3 a, b;
    double r;
  };
  std::vector<Capsule> blobs_;
  Vec3 axis_ = Vec3::UnitZ();
  std::vector<Vec3> ball_dirs_;
  std::vector<double> ball_radii_;
  SplashScene splash_;
};

}  // namespace topotrack
