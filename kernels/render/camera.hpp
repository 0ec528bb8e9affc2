#pragma once
//! A pinhole camera and fitting it to the bounds of a sequence (so every frame is seen from the same place).
#include "kernels/mesh/mesh_queries.hpp"

namespace topotrack {

struct Camera {
  Vec3 eye = Vec3(0, 0, 5);
  Vec3 target = Vec3::Zero();
  Vec3 up = Vec3::UnitY();
  double fov_y_deg = 30;  //!< vertical field of view

  //! Unit viewing direction and the orthonormal image-plane axes (right, up).
  Vec3 forward() const;
  Vec3 right() const;
  Vec3 true_up() const;
};

struct CameraFit {
  double azimuth_deg = 30;     //!< rotation about `up`, 0 = looking along -front
  double elevation_deg = 20;   //!< above the horizontal plane
  double fov_y_deg = 30;
  double aspect = 1;           //!< image width / height
  double margin = 1.05;        //!< > 1 leaves room around the bounding sphere
  Vec3 up = Vec3::UnitY();
};

//! A camera that sees the whole bounding sphere of `bounds` from the direction given by azimuth and
//! elevation (about `params.up`, azimuth 0 looking from the +front side: +Z for up = Y, +Y for up = Z, else
//! any axis orthogonal to up). \throw InvalidInput for empty bounds, a zero up vector or a fov outside (0, 180).
Camera fit_camera(const BoundingBox& bounds, const CameraFit& params = {});

//! The same camera rotated by `degrees` about the axis through its target along `axis` (a turntable step).
Camera orbit(const Camera& camera, const Vec3& axis, double degrees);

//! The camera moved rigidly with the scene: x -> rotation (x - center) + center applied to eye, target and up
//! (a camera that follows a rigidly moving object, e.g. by the ground truth of `topotrack gen blobs`).
Camera transform_camera(const Camera& camera, const Eigen::Matrix3d& rotation, const Vec3& center);

}  // namespace topotrack
