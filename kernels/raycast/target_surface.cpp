#include "kernels/raycast/target_surface.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <limits>
#include <mutex>

#include "kernels/mesh/mesh_convert.hpp"
#include "kernels/raycast/embree_scene.hpp"

namespace topotrack {
namespace {

struct PointQueryState {
  const std::vector<Vec3>* positions;
  const std::vector<std::array<Index, 3>>* triangles;
  Vec3 p;
  double best_d2 = std::numeric_limits<double>::infinity();
  Index best_face = kInvalidIndex;
  Vec3 best_point = Vec3::Zero();
};

bool point_query_callback(RTCPointQueryFunctionArguments* args) {
  auto* s = static_cast<PointQueryState*>(args->userPtr);
  const auto& t = (*s->triangles)[args->primID];
  const auto& P = *s->positions;
  const Vec3 q = closest_point_on_triangle(s->p, P[t[0]], P[t[1]], P[t[2]]);
  const double d2 = (q - s->p).squaredNorm();
  if (d2 < s->best_d2 || (d2 == s->best_d2 && args->primID < s->best_face)) {
    s->best_d2 = d2;
    s->best_face = args->primID;
    s->best_point = q;
    // Shrink the search a little less than to the best distance so that faces at an equal distance
    // are still visited and the tie is broken by the face index, whatever the traversal order.
    const float r = float(std::sqrt(d2) * (1.0 + 1e-5)) + 1e-30f;
    if (r < args->query->radius) {
      args->query->radius = r;
      return true;
    }
  }
  return false;
}

}  // namespace

struct TargetSurface::Impl {
  std::vector<Vec3> positions;
  std::vector<std::array<Index, 3>> triangles;
  std::vector<Vec3> face_normals;
  BoundingBox bounds;
  EmbreeScene scene;

  // Re-intersect the ray with triangle f in double (Möller–Trumbore); Embree works in float.
  double refine(Index f, const Vec3& o, const Vec3& d, double t_float) const {
    const auto& tri = triangles[f];
    const Vec3 &a = positions[tri[0]], &b = positions[tri[1]], &c = positions[tri[2]];
    const Vec3 e1 = b - a, e2 = c - a, pv = d.cross(e2);
    const double det = e1.dot(pv);
    if (!(std::abs(det) > 1e-300)) return t_float;
    const Vec3 tv = o - a, qv = tv.cross(e1);
    const double t = e2.dot(qv) / det;
    return std::isfinite(t) && std::abs(t - t_float) <= 1e-3 * (std::abs(t_float) + bounds.diagonal()) ? t : t_float;
  }

  Hit cast_one(const Vec3& o, const Vec3& d, double max_distance) const {
    Hit out;
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRayHit rh = embree_ray(o, d,
                              max_distance >= double(std::numeric_limits<float>::max())
                                  ? std::numeric_limits<float>::infinity()
                                  : float(max_distance));
    rtcIntersect1(scene.get(), &context, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return out;
    const Index f = rh.hit.primID;
    const double t = std::max(0.0, refine(f, o, d, double(rh.ray.tfar)));
    if (t > max_distance) return out;
    out.hit = true;
    out.face = f;
    out.distance = t;
    out.point = o + t * d;
    out.normal = face_normals[f];
    return out;
  }
};

TargetSurface::TargetSurface(std::span<const Vec3> positions, std::span<const std::array<Index, 3>> triangles,
                             BuildQuality quality)
    : impl_(std::make_unique<Impl>()) {
  if (positions.empty() || triangles.empty())
    TT_THROW(InvalidInput, "target surface: empty (" << positions.size() << " vertices, " << triangles.size()
                                                     << " triangles)");
  Impl& m = *impl_;
  m.positions.assign(positions.begin(), positions.end());
  m.triangles.assign(triangles.begin(), triangles.end());
  for (std::size_t i = 0; i < m.positions.size(); ++i) {
    if (!m.positions[i].allFinite()) TT_THROW(InvalidInput, "target surface: vertex " << i << " is not finite");
    m.bounds.extend(m.positions[i]);
  }
  const auto nv = Index(m.positions.size());
  m.face_normals.resize(m.triangles.size());
  for (std::size_t f = 0; f < m.triangles.size(); ++f) {
    const auto& t = m.triangles[f];
    if (t[0] >= nv || t[1] >= nv || t[2] >= nv)
      TT_THROW(InvalidInput, "target surface: triangle " << f << " has a vertex index out of range");
    const Vec3 n = (m.positions[t[1]] - m.positions[t[0]]).cross(m.positions[t[2]] - m.positions[t[0]]);
    const double len = n.norm();
    m.face_normals[f] = len > 0 ? Vec3(n / len) : Vec3::Zero();
  }

  const RTCBuildQuality q = quality == BuildQuality::Low      ? RTC_BUILD_QUALITY_LOW
                            : quality == BuildQuality::Medium ? RTC_BUILD_QUALITY_MEDIUM
                                                              : RTC_BUILD_QUALITY_HIGH;
  m.scene = EmbreeScene(m.positions, m.triangles, q, RTC_SCENE_FLAG_ROBUST);
}

TargetSurface TargetSurface::from_mesh(const SurfaceMesh& mesh, BuildQuality quality) {
  std::vector<Vec3> positions;
  std::vector<std::array<Index, 3>> triangles;
  extract_triangles(mesh, positions, triangles);
  return TargetSurface(positions, triangles, quality);
}

TargetSurface::~TargetSurface() = default;
TargetSurface::TargetSurface(TargetSurface&&) noexcept = default;
TargetSurface& TargetSurface::operator=(TargetSurface&&) noexcept = default;

TargetSurface::Hit TargetSurface::cast(const Vec3& origin, const Vec3& direction, double max_distance) const {
  const double len = direction.norm();
  if (!(len > 0) || !origin.allFinite() || !std::isfinite(len) || !(max_distance >= 0)) return {};
  return impl_->cast_one(origin, direction / len, max_distance);
}

TargetSurface::Hit TargetSurface::cast_undirected(const Vec3& origin, const Vec3& direction,
                                                  double max_distance) const {
  const double len = direction.norm();
  if (!(len > 0) || !origin.allFinite() || !std::isfinite(len) || !(max_distance >= 0)) return {};
  const Vec3 d = direction / len;
  const Hit forward = impl_->cast_one(origin, d, max_distance);
  const Hit backward = impl_->cast_one(origin, -d, forward.hit ? forward.distance : max_distance);
  if (!backward.hit) return forward;
  if (!forward.hit || backward.distance < forward.distance ||
      (backward.distance == forward.distance && backward.face < forward.face))
    return backward;
  return forward;
}

TargetSurface::Hit TargetSurface::closest_point(const Vec3& p) const {
  return closest_point(p, std::numeric_limits<double>::infinity());
}

TargetSurface::Hit TargetSurface::closest_point(const Vec3& p, double max_distance) const {
  Hit out;
  if (!p.allFinite() || !(max_distance >= 0)) return out;
  PointQueryState state;
  state.positions = &impl_->positions;
  state.triangles = &impl_->triangles;
  state.p = p;
  RTCPointQuery query;
  query.x = float(p.x());
  query.y = float(p.y());
  query.z = float(p.z());
  query.time = 0.0f;
  // Embree culls by float bounds: pad the radius so that a face exactly at max_distance is visited.
  query.radius = std::isfinite(max_distance) && max_distance < 1e30
                     ? float(max_distance * (1.0 + 1e-5) + 1e-6 * impl_->bounds.diagonal())
                     : std::numeric_limits<float>::infinity();
  RTCPointQueryContext context;
  rtcInitPointQueryContext(&context);
  rtcPointQuery(impl_->scene.get(), &query, &context, point_query_callback, &state);
  if (state.best_face == kInvalidIndex) return out;
  const double d = std::sqrt(state.best_d2);
  if (d > max_distance) return out;
  out.hit = true;
  out.face = state.best_face;
  out.point = state.best_point;
  out.distance = d;
  out.normal = impl_->face_normals[state.best_face];
  return out;
}

std::vector<TargetSurface::Hit> TargetSurface::cast_undirected(std::span<const Vec3> origins,
                                                               std::span<const Vec3> directions,
                                                               double max_distance) const {
  if (origins.size() != directions.size())
    TT_THROW(InvalidInput, "cast_undirected: " << origins.size() << " origins but " << directions.size()
                                               << " directions");
  std::vector<Hit> out(origins.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, origins.size(), 256), [&](const auto& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) out[i] = cast_undirected(origins[i], directions[i], max_distance);
  });
  return out;
}

std::vector<TargetSurface::Hit> TargetSurface::closest_points(std::span<const Vec3> points) const {
  std::vector<Hit> out(points.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 256), [&](const auto& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) out[i] = closest_point(points[i]);
  });
  return out;
}

const BoundingBox& TargetSurface::bounds() const { return impl_->bounds; }
double TargetSurface::bbox_diagonal() const { return impl_->bounds.diagonal(); }
std::size_t TargetSurface::n_vertices() const { return impl_->positions.size(); }
std::size_t TargetSurface::n_triangles() const { return impl_->triangles.size(); }
const std::vector<Vec3>& TargetSurface::positions() const { return impl_->positions; }
const std::vector<std::array<Index, 3>>& TargetSurface::triangles() const { return impl_->triangles; }
const Vec3& TargetSurface::face_normal(Index f) const { return impl_->face_normals[f]; }

}  // namespace topotrack
