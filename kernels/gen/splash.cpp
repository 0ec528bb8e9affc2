#include "kernels/gen/splash.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include "kernels/gen/shapes.hpp"

namespace topotrack {
namespace {

using namespace sdf_shapes;

// The pool: a rounded box, surface at z = 0, 1.7 wide, 0.4 deep.
constexpr double kPoolHalf = 0.85, kPoolDepth = 0.4, kPoolRound = 0.05;
// The falling drop: radius, start height of its centre, fall acceleration (per unit t^2); it touches the
// pool at t_touch and melts into the crater until t_touch + kDropMelt.
constexpr double kDropRadius = 0.15, kDropStart = 0.45, kDropFall = 20.0, kDropMelt = 0.08;
const double kTouch = std::sqrt((kDropStart - kDropRadius) / kDropFall);
// Crater and crown: from the impact over kCrownSpan; crater depth, crown height, wall radius and flare.
constexpr double kCrownSpan = 0.5, kCraterDepth = 0.16, kCrownHeight = 0.36, kWall = 0.035, kFlare = 0.1;
// Rim droplets: they grow on the crown's rim from crown phase kGrow to kBirth, then fly ballistically.
constexpr int kDroplets = 12;
constexpr double kGrow = 0.2, kBirth = 0.3, kDropletGravity = 4.6;
// Worthington jet: rises and sinks from kJetStart over kJetSpan; its tip drop is born at jet phase kJetBirth.
constexpr double kJetStart = 0.45, kJetSpan = 0.4, kJetHeight = 0.42, kJetRadius = 0.045;
constexpr double kJetDropRadius = 0.065, kJetBirth = 0.3, kJetDropSpeed = 2.2, kJetGravity = 9.0;
// Blend widths: drops and droplets with the rest, the crown with the pool, the crater's rim.
constexpr double kBlendDrop = 0.03, kBlendWall = 0.06, kBlendCrater = 0.04;

double smooth_max(double a, double b, double k) { return -smooth_min(-a, -b, k); }

double rounded_box(const Vec3& p, const Vec3& centre, const Vec3& half, double round) {
  const Vec3 q = (p - centre).cwiseAbs() - half + Vec3::Constant(round);
  return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0) - round;
}

// Phase s in [0, 1] of an event starting at `start` and lasting `span`; outside: clamped.
double phase(double t, double start, double span) { return std::clamp((t - start) / span, 0.0, 1.0); }

// Crater radius at the pool surface and crown height over the crown phase.
double crater_radius(double s) { return 0.12 + 0.25 * std::sqrt(s); }
double crown_height(double s) { return kCrownHeight * std::sin(std::numbers::pi * s); }
// Meridian coordinates (r, z) of the crown's rim.
Eigen::Vector2d crown_rim(double s) {
  const double h = crown_height(s);
  return {crater_radius(s) + kFlare * h / kCrownHeight, h};
}
double jet_height(double s) { return kJetHeight * std::sin(std::numbers::pi * s); }
double crater_depth(double s) { return kCraterDepth * std::sin(std::numbers::pi * s); }
// Crown wall and jet fade in and out by thinning and sinking below the surface, so that no frame pops.
double fade(double s) { return std::min(1.0, 5.0 * std::sin(std::numbers::pi * s)); }

// A drop sinking into the pool shrinks to nothing over its first 0.15 below the surface, so it never pokes
// out of the pool's bottom.
double sunk_radius(double radius, double z) { return radius * std::clamp(1.0 + z / 0.15, 0.0, 1.0); }

}  // namespace

SplashScene::SplashScene(unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int k = 0; k < kDroplets; ++k) {
    Droplet d;
    d.angle = 2.0 * std::numbers::pi * (k + 0.3 * u(rng)) / kDroplets;
    d.radius = 0.0475 + 0.0075 * u(rng);
    d.speed_out = 0.7 * (1.0 + 0.15 * u(rng));
    d.speed_up = 1.6 * (1.0 + 0.1 * u(rng));
    droplets_.push_back(d);
  }
}

Vec3 SplashScene::box_min() { return {-kPoolHalf - 0.1, -kPoolHalf - 0.1, -kPoolDepth - 0.1}; }
Vec3 SplashScene::box_max() { return {kPoolHalf + 0.1, kPoolHalf + 0.1, 0.75}; }

std::vector<SplashDrop> SplashScene::drops(double t) const {
  std::vector<SplashDrop> out;
  // The falling drop, then melting into the crater.
  const double s = phase(t, kTouch, kCrownSpan);
  if (t < kTouch + kDropMelt) {
    // It falls until it rests in the crater's bottom, so it never floats free above the crater.
    const double z = std::max(kDropStart - kDropFall * t * t, t > kTouch ? -crater_depth(s) : 0.0);
    const double melt = t <= kTouch ? 1.0 : 1.0 - (t - kTouch) / kDropMelt;
    out.push_back({Vec3(0, 0, z), kDropRadius * melt});
  }
  // Rim droplets: grow on the rim, then fly; sink into the pool where they land.
  if (t > kTouch && s > kGrow) {
    const double tb = kTouch + kBirth * kCrownSpan;
    const Eigen::Vector2d rim = crown_rim(std::min(s, kBirth));
    const double grow = std::min((s - kGrow) / (kBirth - kGrow), 1.0);
    const double dt = std::max(t - tb, 0.0);
    for (const Droplet& d : droplets_) {
      const double r = rim.x() + d.speed_out * dt;
      const double z = rim.y() + d.speed_up * dt - kDropletGravity * dt * dt;
      const double radius = sunk_radius(d.radius * grow, z);
      if (radius > 0) out.push_back({Vec3(r * std::cos(d.angle), r * std::sin(d.angle), z), radius});
    }
  }
  // The jet's tip drop.
  const double js = phase(t, kJetStart, kJetSpan);
  if (t > kJetStart && js > kJetBirth - 0.1) {
    const double tb = kJetStart + kJetBirth * kJetSpan;
    const double grow = std::min((js - (kJetBirth - 0.1)) / 0.1, 1.0);
    const double dt = std::max(t - tb, 0.0);
    const double z = jet_height(std::min(js, kJetBirth)) + kJetDropSpeed * dt - kJetGravity * dt * dt;
    const double radius = sunk_radius(kJetDropRadius * grow, z);
    if (radius > 0) out.push_back({Vec3(0, 0, z), radius});
  }
  return out;
}

double SplashScene::field(double t, const Vec3& x) const {
  double f = rounded_box(x, Vec3(0, 0, -kPoolDepth / 2), Vec3(kPoolHalf, kPoolHalf, kPoolDepth / 2), kPoolRound);
  const double r = std::hypot(x.x(), x.y());
  const double s = phase(t, kTouch, kCrownSpan);
  if (t > kTouch && s < 1.0) {
    // The crater: a sphere cap of depth D and radius R at the surface, carved out of the pool.
    // The blend width shrinks with the depth so that the carving vanishes continuously as D -> 0.
    const double depth = crater_depth(s), radius = crater_radius(s);
    if (depth > 1e-6) {
      const double rc = (radius * radius + depth * depth) / (2.0 * depth);
      f = smooth_max(f, -sphere(x, Vec3(0, 0, rc - depth), rc), std::min(kBlendCrater, depth));
    }
    // The crown: a flared wall of revolution from the crater's rim up to height H (a capsule in the
    // meridian plane, so an exact distance in 3D).
    const double sink = 0.1 * (1.0 - fade(s));
    const Eigen::Vector2d base(radius, -0.02 - sink), rim = crown_rim(s) - Eigen::Vector2d(0, sink);
    const Eigen::Vector2d p(r, x.z()), ab = rim - base;
    const double w = std::clamp((p - base).dot(ab) / std::max(ab.squaredNorm(), 1e-12), 0.0, 1.0);
    f = smooth_min(f, (p - (base + w * ab)).norm() - kWall * fade(s), kBlendWall);
  }
  const double js = phase(t, kJetStart, kJetSpan);
  if (t > kJetStart && js < 1.0) {
    // Rooted deep in the pool, below any crater, and rising from there as it fades in.
    constexpr double kRoot = -0.3;
    const double top = kRoot + (jet_height(js) - kRoot) * fade(js);
    f = smooth_min(f, capsule(x, Vec3(0, 0, kRoot), Vec3(0, 0, top), kJetRadius * fade(js)), kBlendWall);
  }
  for (const SplashDrop& d : drops(t)) f = smooth_min(f, sphere(x, d.center, d.radius), kBlendDrop);
  return f;
}

}  // namespace topotrack
