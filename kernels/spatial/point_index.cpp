#include "kernels/spatial/point_index.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <nanoflann.hpp>

namespace topotrack {
namespace {

struct Cloud {
  std::vector<Vec3> pts;
  std::size_t kdtree_get_point_count() const { return pts.size(); }
  double kdtree_get_pt(std::size_t i, std::size_t dim) const { return pts[i][Eigen::Index(dim)]; }
  template <class BBox>
  bool kdtree_get_bbox(BBox&) const {
    return false;
  }
};

using Tree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, Cloud>, Cloud, 3, std::size_t>;

bool closer(const PointIndex::Neighbor& a, const PointIndex::Neighbor& b) {
  return a.distance < b.distance || (a.distance == b.distance && a.index < b.index);
}

}  // namespace

struct PointIndex::Impl {
  Cloud cloud;
  std::unique_ptr<Tree> tree;
};

PointIndex::PointIndex(std::span<const Vec3> points) : impl_(std::make_unique<Impl>()) {
  impl_->cloud.pts.assign(points.begin(), points.end());
  for (std::size_t i = 0; i < points.size(); ++i)
    if (!points[i].allFinite()) TT_THROW(InvalidInput, "point index: point " << i << " is not finite");
  if (points.size() >= std::size_t(kInvalidIndex)) TT_THROW(InvalidInput, "point index: too many points");
  impl_->tree = std::make_unique<Tree>(3, impl_->cloud, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  if (!points.empty()) impl_->tree->buildIndex();
}

PointIndex::~PointIndex() = default;
PointIndex::PointIndex(PointIndex&&) noexcept = default;
PointIndex& PointIndex::operator=(PointIndex&&) noexcept = default;

std::size_t PointIndex::size() const { return impl_->cloud.pts.size(); }
const std::vector<Vec3>& PointIndex::points() const { return impl_->cloud.pts; }

std::vector<PointIndex::Neighbor> PointIndex::k_nearest(const Vec3& q, std::size_t k) const {
  std::vector<Neighbor> out;
  if (size() == 0 || k == 0 || !q.allFinite()) return out;
  // Ask for one more than needed so that a tie at the k-th place is resolved by index.
  const std::size_t n = std::min(size(), k + 1);
  std::vector<std::size_t> idx(n);
  std::vector<double> d2(n);
  const std::size_t found = impl_->tree->knnSearch(q.data(), n, idx.data(), d2.data());
  out.resize(found);
  for (std::size_t i = 0; i < found; ++i) out[i] = {Index(idx[i]), std::sqrt(d2[i])};
  std::sort(out.begin(), out.end(), closer);
  if (out.size() > k) out.resize(k);
  return out;
}

PointIndex::Neighbor PointIndex::nearest(const Vec3& q) const {
  const auto r = k_nearest(q, 1);
  return r.empty() ? Neighbor{} : r.front();
}

std::vector<PointIndex::Neighbor> PointIndex::within_radius(const Vec3& q, double radius) const {
  std::vector<Neighbor> out;
  if (size() == 0 || !(radius >= 0) || !q.allFinite()) return out;
  std::vector<std::pair<std::size_t, double>> matches;
  nanoflann::SearchParams params;
  params.sorted = false;
  // nanoflann's radius is squared for the L2 metric; pad it so that points exactly on the sphere are kept.
  impl_->tree->radiusSearch(q.data(), radius * radius * (1 + 1e-12) + 1e-300, matches, params);
  out.reserve(matches.size());
  for (const auto& [i, d2] : matches) {
    const double d = std::sqrt(d2);
    if (d <= radius) out.push_back({Index(i), d});
  }
  std::sort(out.begin(), out.end(), closer);
  return out;
}

std::vector<PointIndex::Neighbor> PointIndex::nearest(std::span<const Vec3> queries) const {
  std::vector<Neighbor> out(queries.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, queries.size(), 512), [&](const auto& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) out[i] = nearest(queries[i]);
  });
  return out;
}

}  // namespace topotrack
