#pragma once
//! PointIndex: a nanoflann kd-tree over a fixed set of points, for nearest-neighbour and radius
//! queries (closest vertices, point-cloud correspondences, ground-truth matching). Immutable after
//! construction; queries are thread-safe. Results are sorted by distance, ties by the smaller index,
//! so they do not depend on the tree's build order or the thread count.
#include <memory>
#include <span>
#include <vector>

#include "kernels/mesh/surface_mesh.hpp"

namespace topotrack {

class PointIndex {
public:
  struct Neighbor {
    Index index = kInvalidIndex;
    double distance = 0;
  };

  //! Copies the points. \throw InvalidInput on a non-finite point.
  explicit PointIndex(std::span<const Vec3> points);
  ~PointIndex();
  PointIndex(PointIndex&&) noexcept;
  PointIndex& operator=(PointIndex&&) noexcept;
  PointIndex(const PointIndex&) = delete;
  PointIndex& operator=(const PointIndex&) = delete;

  std::size_t size() const;
  const std::vector<Vec3>& points() const;
  //! The nearest point (index kInvalidIndex when the index is empty).
  Neighbor nearest(const Vec3& q) const;
  //! The k nearest points, nearest first (fewer when the index holds fewer).
  std::vector<Neighbor> k_nearest(const Vec3& q, std::size_t k) const;
  //! Every point within `radius` (inclusive), nearest first.
  std::vector<Neighbor> within_radius(const Vec3& q, double radius) const;
  //! nearest() for many queries in parallel, indexed like the queries.
  std::vector<Neighbor> nearest(std::span<const Vec3> queries) const;

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace topotrack
