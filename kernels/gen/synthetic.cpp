#include "kernels/gen/synthetic.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>
#include <random>

#include "kernels/gen/shapes.hpp"

namespace topotrack {
namespace {

using namespace sdf_shapes;
constexpr double kBlobBlend = 0.25, kBallBlend = 0.15;

// Default resolutions: about 10k-20k vertices per frame.
int default_resolution(SyntheticKind kind) {
  switch (kind) {
    case SyntheticKind::kBlobs: return 96;
    case SyntheticKind::kMorph: return 96;
    case SyntheticKind::kMetaballs: return 128;
    case SyntheticKind::kSplash: return 96;
  }
  return 96;
}

nlohmann::json vec_json(const Vec3& v) { return {v.x(), v.y(), v.z()}; }

// Morph shapes (§ issue 2 item 7): torus, two spheres, one sphere.
double morph_torus(const Vec3& p) { return torus_z(p, Vec3::Zero(), 0.6, 0.25); }
double morph_two(const Vec3& p, double dx) {
  return std::min(sphere(p, Vec3(-0.55 - dx, 0, 0), 0.35), sphere(p, Vec3(0.55 + dx, 0, 0), 0.35));
}
double morph_one(const Vec3& p) { return sphere(p, Vec3::Zero(), 0.6); }

}  // namespace

SyntheticKind synthetic_kind_from_name(const std::string& name) {
  if (name == "blobs") return SyntheticKind::kBlobs;
  if (name == "morph") return SyntheticKind::kMorph;
  if (name == "metaballs") return SyntheticKind::kMetaballs;
  if (name == "splash") return SyntheticKind::kSplash;
  TT_THROW(UsageError, "unknown sequence kind '" << name << "' (blobs, morph, metaballs, splash)");
}

const char* synthetic_kind_name(SyntheticKind kind) {
  switch (kind) {
    case SyntheticKind::kBlobs: return "blobs";
    case SyntheticKind::kMorph: return "morph";
    case SyntheticKind::kMetaballs: return "metaballs";
    case SyntheticKind::kSplash: return "splash";
  }
  return "?";
}

SyntheticScene::SyntheticScene(const SyntheticParams& params) : params_(params), splash_(params.seed) {
  if (params.frames < 1) TT_THROW(InvalidInput, "synthetic sequence: frames must be >= 1, got " << params.frames);
  resolution_ = params.resolution == 0 ? default_resolution(params.kind) : params.resolution;
  if (resolution_ < 8 || resolution_ > 4096)
    TT_THROW(InvalidInput, "synthetic sequence: resolution must be in [8, 4096], got " << params.resolution);
  std::mt19937 rng(params.seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  switch (params.kind) {
    case SyntheticKind::kBlobs: {
      // Three lobes from a common core: one component of genus 0.
      blobs_ = {{Vec3(0.15, 0.0, 0.0), Vec3(0.7, 0.15, 0.1), 0.3},
                {Vec3(-0.1, 0.15, 0.05), Vec3(-0.45, 0.6, -0.2), 0.27},
                {Vec3(-0.05, -0.15, -0.1), Vec3(0.05, -0.65, 0.25), 0.28}};
      double rho = 0;
      for (auto& c : blobs_) {
        c.a += 0.05 * Vec3(u(rng), u(rng), u(rng));
        c.b += 0.05 * Vec3(u(rng), u(rng), u(rng));
        c.r += 0.03 * u(rng);
        rho = std::max(rho, std::max(c.a.norm(), c.b.norm()) + c.r);
      }
      axis_ = Vec3(0.2, 0.3, 1.0).normalized();
      rho += 0.1;
      box_.extend(Vec3::Constant(-rho));
      box_.extend(Vec3::Constant(rho));
      break;
    }
    case SyntheticKind::kMorph:
      box_.extend(Vec3(-1.0, -1.0, -0.75));
      box_.extend(Vec3(1.0, 1.0, 0.75));
      break;
    case SyntheticKind::kMetaballs: {
      const Eigen::Quaterniond q = Eigen::Quaterniond(u(rng), u(rng), u(rng), u(rng) + 2.0).normalized();
      for (const Vec3& d : {Vec3(1, 1, 1), Vec3(1, -1, -1), Vec3(-1, 1, -1), Vec3(-1, -1, 1)}) {
        ball_dirs_.push_back(q * d.normalized());
        ball_radii_.push_back(0.31 + 0.03 * u(rng));
      }
      const double rho = 0.9 + 0.34 + 0.1;
      box_.extend(Vec3::Constant(-rho));
      box_.extend(Vec3::Constant(rho));
      break;
    }
    case SyntheticKind::kSplash:
      box_.extend(SplashScene::box_min());
      box_.extend(SplashScene::box_max());
      break;
  }
  const Vec3 extent = box_.max - box_.min;
  voxel_size_ = extent.maxCoeff() / resolution_;
}

double SyntheticScene::time(int frame) const {
  return params_.frames == 1 ? 0.0 : double(frame - 1) / double(params_.frames - 1);
}

void SyntheticScene::check_frame(int frame) const {
  if (frame < 1 || frame > params_.frames)
    TT_THROW(InvalidInput, "synthetic sequence: frame " << frame << " is not in [1, " << params_.frames << "]");
}

RigidMotion SyntheticScene::blobs_motion(int frame) const {
  RigidMotion m;
  // One full turn over the sequence: frame N + 1 would be frame 1 again.
  const double angle = 2.0 * std::numbers::pi * double(frame - 1) / double(params_.frames);
  m.rotation = Eigen::AngleAxisd(angle, axis_).toRotationMatrix();
  return m;
}

std::pair<int, double> SyntheticScene::morph_blend(int frame) const {
  const double t = time(frame);
  return t <= 0.5 ? std::pair{0, 2.0 * t} : std::pair{1, 2.0 * t - 1.0};
}

std::vector<Ball> SyntheticScene::metaballs(int frame) const {
  const double t = time(frame);
  const double s = std::sin(std::numbers::pi * t);
  const double d = 0.25 + 0.65 * s * s;  // merged at the ends, apart mid-way
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(std::numbers::pi * t, Vec3::UnitZ()).toRotationMatrix();
  std::vector<Ball> balls;
  for (std::size_t i = 0; i < ball_dirs_.size(); ++i) balls.push_back({turn * (d * ball_dirs_[i]), ball_radii_[i]});
  return balls;
}

double SyntheticScene::field(int frame, const Vec3& x) const {
  switch (params_.kind) {
    case SyntheticKind::kBlobs: {
      const Vec3 p = blobs_motion(frame).rotation.transpose() * x;
      double f = capsule(p, blobs_[0].a, blobs_[0].b, blobs_[0].r);
      for (std::size_t i = 1; i < blobs_.size(); ++i)
        f = smooth_min(f, capsule(p, blobs_[i].a, blobs_[i].b, blobs_[i].r), kBlobBlend);
      return f;
    }
    case SyntheticKind::kMorph: {
      const auto [stage, w] = morph_blend(frame);
      const double dx = 0.02 * double(params_.seed % 5);
      if (stage == 0) return (1.0 - w) * morph_torus(x) + w * morph_two(x, dx);
      return (1.0 - w) * morph_two(x, dx) + w * morph_one(x);
    }
    case SyntheticKind::kMetaballs: {
      const auto balls = metaballs(frame);
      double f = sphere(x, balls[0].center, balls[0].radius);
      for (std::size_t i = 1; i < balls.size(); ++i) f = smooth_min(f, sphere(x, balls[i].center, balls[i].radius), kBallBlend);
      return f;
    }
    case SyntheticKind::kSplash: return splash_.field(time(frame), x);
  }
  return 1.0;
}

MeshData SyntheticScene::frame_mesh(int frame) const {
  check_frame(frame);
  // Per-frame constants hoisted out of the field (evaluated millions of times).
  switch (params_.kind) {
    case SyntheticKind::kBlobs: {
      const Eigen::Matrix3d Rt = blobs_motion(frame).rotation.transpose();
      return mesh_implicit(
          [&](const Vec3& x) {
            const Vec3 p = Rt * x;
            double f = capsule(p, blobs_[0].a, blobs_[0].b, blobs_[0].r);
            for (std::size_t i = 1; i < blobs_.size(); ++i)
              f = smooth_min(f, capsule(p, blobs_[i].a, blobs_[i].b, blobs_[i].r), kBlobBlend);
            return f;
          },
          box_, voxel_size_);
    }
    case SyntheticKind::kMetaballs: {
      const auto balls = metaballs(frame);
      return mesh_implicit(
          [&](const Vec3& x) {
            double f = sphere(x, balls[0].center, balls[0].radius);
            for (std::size_t i = 1; i < balls.size(); ++i)
              f = smooth_min(f, sphere(x, balls[i].center, balls[i].radius), kBallBlend);
            return f;
          },
          box_, voxel_size_);
    }
    default: return mesh_implicit([&](const Vec3& x) { return field(frame, x); }, box_, voxel_size_);
  }
}

nlohmann::json SyntheticScene::ground_truth() const {
  nlohmann::json j;
  j["kind"] = synthetic_kind_name(params_.kind);
  nlohmann::json frames = nlohmann::json::array();
  for (int n = 1; n <= params_.frames; ++n) {
    nlohmann::json f;
    f["frame"] = n;
    switch (params_.kind) {
      case SyntheticKind::kBlobs: {
        const RigidMotion m = blobs_motion(n);
        nlohmann::json rows = nlohmann::json::array();
        for (int r = 0; r < 3; ++r) rows.push_back({m.rotation(r, 0), m.rotation(r, 1), m.rotation(r, 2)});
        f["rotation"] = rows;
        f["center"] = vec_json(m.center);
        break;
      }
      case SyntheticKind::kMorph: {
        const auto [stage, w] = morph_blend(n);
        f["stage"] = stage;
        f["weight"] = w;
        break;
      }
      case SyntheticKind::kMetaballs: {
        nlohmann::json balls = nlohmann::json::array();
        for (const Ball& b : metaballs(n)) balls.push_back({{"center", vec_json(b.center)}, {"radius", b.radius}});
        f["balls"] = balls;
        break;
      }
      case SyntheticKind::kSplash: {
        nlohmann::json drops = nlohmann::json::array();
        for (const SplashDrop& d : splash_.drops(time(n))) drops.push_back({{"center", vec_json(d.center)}, {"radius", d.radius}});
        f["time"] = time(n);
        f["drops"] = drops;
        break;
      }
    }
    frames.push_back(f);
  }
  if (params_.kind == SyntheticKind::kBlobs) {
    j["axis"] = vec_json(axis_);
    j["convention"] = "x_n = rotation * (x_1 - center) + center";
  }
  if (params_.kind == SyntheticKind::kMorph)
    j["convention"] = "stage 0: (1-w) torus + w two_spheres; stage 1: (1-w) two_spheres + w sphere (signed distances)";
  j["frames"] = frames;
  return j;
}

}  // namespace topotrack
