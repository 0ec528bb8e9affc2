#pragma once
//! TargetSurface: the input surface S_n of a frame as an Embree 3 scene, for the correspondence
//! searches of the non-rigid alignment (§4.2): undirected rays along a normal (nearest hit either way)
//! and closest points. Immutable after construction; every query is thread-safe and deterministic
//! (ties between faces are broken by the smaller face index; hit distances are refined in double).
#include <array>
#include <memory>
#include <span>
#include <vector>

#include "kernels/mesh/mesh_queries.hpp"
#include "kernels/mesh/surface_mesh.hpp"

namespace topotrack {

class TargetSurface {
public:
  //! Build quality of the Embree BVH: Low suits a scene queried once per frame (the default).
  enum class BuildQuality { Low, Medium, High };

  //! \throw InvalidInput on empty input, non-finite coordinates or an index out of range.
  TargetSurface(std::span<const Vec3> positions, std::span<const std::array<Index, 3>> triangles,
                BuildQuality quality = BuildQuality::Low);
  //! The live triangles of `mesh`. \throw InvalidInput as the constructor.
  static TargetSurface from_mesh(const SurfaceMesh& mesh, BuildQuality quality = BuildQuality::Low);
  ~TargetSurface();
  TargetSurface(TargetSurface&&) noexcept;
  TargetSurface& operator=(TargetSurface&&) noexcept;
  TargetSurface(const TargetSurface&) = delete;
  TargetSurface& operator=(const TargetSurface&) = delete;

  struct Hit {
    bool hit = false;
    Vec3 point = Vec3::Zero();
    Vec3 normal = Vec3::Zero();  //!< unit normal of the face hit (outward for a consistently oriented surface)
    double distance = 0;         //!< from the query point to `point`
    Index face = kInvalidIndex;
  };

  //! The nearest intersection of the line origin + t * direction, |t| <= max_distance, either way
  //! (the paper's undirected ray). `direction` need not be unit; a zero direction never hits.
  Hit cast_undirected(const Vec3& origin, const Vec3& direction, double max_distance) const;
  //! The first intersection for t in [0, max_distance] only.
  Hit cast(const Vec3& origin, const Vec3& direction, double max_distance) const;
  //! The closest point on the surface (always hits).
  Hit closest_point(const Vec3& p) const;
  //! The closest point within max_distance (no hit when farther).
  Hit closest_point(const Vec3& p, double max_distance) const;

  //! Batch variants, parallel over the queries (TBB), results indexed like the input.
  std::vector<Hit> cast_undirected(std::span<const Vec3> origins, std::span<const Vec3> directions,
                                   double max_distance) const;
  std::vector<Hit> closest_points(std::span<const Vec3> points) const;

  const BoundingBox& bounds() const;
  double bbox_diagonal() const;
  std::size_t n_vertices() const;
  std::size_t n_triangles() const;
  const std::vector<Vec3>& positions() const;
  const std::vector<std::array<Index, 3>>& triangles() const;
  //! Unit normal of triangle f (zero for a degenerate one).
  const Vec3& face_normal(Index f) const;

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace topotrack
