#include "kernels/render/camera.hpp"

#include <cmath>
#include <numbers>

#include "io/error.hpp"

namespace topotrack {

Vec3 Camera::forward() const { return (target - eye).normalized(); }
Vec3 Camera::right() const {
  Vec3 r = forward().cross(up);
  if (r.squaredNorm() < 1e-24) r = forward().unitOrthogonal();
  return r.normalized();
}
Vec3 Camera::true_up() const { return right().cross(forward()).normalized(); }

Camera fit_camera(const BoundingBox& bounds, const CameraFit& params) {
  if (bounds.empty()) TT_THROW(InvalidInput, "fit_camera: empty bounds");
  if (!(params.up.norm() > 0)) TT_THROW(InvalidInput, "fit_camera: zero up vector");
  if (!(params.fov_y_deg > 0 && params.fov_y_deg < 180))
    TT_THROW(InvalidInput, "fit_camera: field of view " << params.fov_y_deg << " not in (0, 180)");
  if (!(params.aspect > 0)) TT_THROW(InvalidInput, "fit_camera: aspect " << params.aspect << " not positive");
  const double deg = std::numbers::pi / 180;
  const Vec3 up = params.up.normalized();
  Vec3 front;
  if (std::abs(up.y()) > 0.9)
    front = Vec3::UnitZ();
  else if (std::abs(up.z()) > 0.9)
    front = Vec3::UnitY();
  else
    front = up.unitOrthogonal();
  front = (front - front.dot(up) * up).normalized();
  const Vec3 side = up.cross(front).normalized();
  const double az = params.azimuth_deg * deg, el = params.elevation_deg * deg;
  const Vec3 dir = std::cos(el) * (std::cos(az) * front + std::sin(az) * side) + std::sin(el) * up;

  const double radius = std::max(0.5 * bounds.diagonal(), 1e-12) * std::max(params.margin, 1e-3);
  const double half_y = 0.5 * params.fov_y_deg * deg;
  const double half_x = std::atan(std::tan(half_y) * params.aspect);
  const double half = std::min(half_x, half_y);
  Camera cam;
  cam.target = bounds.center();
  cam.eye = cam.target + dir * (radius / std::sin(half));
  cam.up = up;
  cam.fov_y_deg = params.fov_y_deg;
  return cam;
}

Camera orbit(const Camera& camera, const Vec3& axis, double degrees) {
  if (!(axis.norm() > 0)) TT_THROW(InvalidInput, "orbit: zero axis");
  const Eigen::AngleAxisd rot(degrees * std::numbers::pi / 180, axis.normalized());
  Camera c = camera;
  c.eye = camera.target + rot * (camera.eye - camera.target);
  c.up = rot * camera.up;
  return c;
}

Camera transform_camera(const Camera& camera, const Eigen::Matrix3d& rotation, const Vec3& center) {
  if (!rotation.allFinite() || !center.allFinite()) TT_THROW(InvalidInput, "transform_camera: non-finite motion");
  Camera c = camera;
  c.eye = rotation * (camera.eye - center) + center;
  c.target = rotation * (camera.target - center) + center;
  c.up = rotation * camera.up;
  return c;
}

}  // namespace topotrack
