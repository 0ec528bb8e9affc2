#include "kernels/mesh/mesh_queries.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>

namespace topotrack {
namespace {
constexpr double kRadToDeg = 180.0 / 3.14159265358979323846;

double angle_between(const Vec3& a, const Vec3& b) {
  // atan2 form: accurate for tiny and near-180° angles.
  return std::atan2(a.cross(b).norm(), a.dot(b));
}
}  // namespace

Stats make_stats(std::vector<double> v) {
  Stats s;
  s.count = v.size();
  if (v.empty()) return s;
  s.min = *std::min_element(v.begin(), v.end());
  s.max = *std::max_element(v.begin(), v.end());
  s.mean = std::accumulate(v.begin(), v.end(), 0.0) / double(v.size());
  auto mid = v.begin() + v.size() / 2;
  std::nth_element(v.begin(), mid, v.end());
  s.median = *mid;
  return s;
}

Vec3 face_normal(const SurfaceMesh& m, Face f) {
  const auto t = m.vertices(f);
  const Vec3 n = (m.position(t[1]) - m.position(t[0])).cross(m.position(t[2]) - m.position(t[0]));
  const double len = n.norm();
  return len > 0 ? Vec3(n / len) : Vec3::Zero();
}

double face_area(const SurfaceMesh& m, Face f) {
  const auto t = m.vertices(f);
  return 0.5 * (m.position(t[1]) - m.position(t[0])).cross(m.position(t[2]) - m.position(t[0])).norm();
}

std::vector<Vec3> vertex_normals(const SurfaceMesh& m) {
  // Each face's corner terms (angle times face normal) in parallel; then each vertex sums its terms in
  // ascending face order, in parallel over vertices: the same additions in the same order as one loop
  // over the faces, so the normals are bit for bit those of the serial sum on any thread count. The
  // serial sum scattered its additions over the whole array (80 ms at 98k vertices, BM_VertexNormals).
  const std::size_t nf = m.faces_size(), nv = m.vertices_size();
  std::vector<std::array<Vertex, 3>> corner(nf);
  std::vector<Vec3> term(3 * nf);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nf, 2048), [&](const auto& r) {
    for (std::size_t f = r.begin(); f != r.end(); ++f) {
      if (m.is_deleted(Face(Index(f)))) {
        corner[f] = {Vertex(), Vertex(), Vertex()};
        continue;
      }
      const auto t = m.vertices(Face(Index(f)));
      corner[f] = t;
      const Vec3 fn = face_normal(m, Face(Index(f)));
      for (int k = 0; k < 3; ++k) {
        const Vec3& p = m.position(t[k]);
        term[3 * f + std::size_t(k)] = angle_between(m.position(t[(k + 1) % 3]) - p, m.position(t[(k + 2) % 3]) - p) * fn;
      }
    }
  });
  // Each vertex's terms, in face order (a counting sort by vertex).
  std::vector<Index> offset(nv + 1, 0);
  for (const auto& t : corner)
    for (const Vertex v : t)
      if (v.is_valid()) ++offset[v.idx + 1];
  for (std::size_t v = 0; v < nv; ++v) offset[v + 1] += offset[v];
  std::vector<Index> terms(offset[nv]);
  {
    std::vector<Index> fill(offset.begin(), offset.end() - 1);
    for (std::size_t f = 0; f < nf; ++f)
      for (std::size_t k = 0; k < 3; ++k)
        if (const Vertex v = corner[f][k]; v.is_valid()) terms[fill[v.idx]++] = Index(3 * f + k);
  }
  std::vector<Vec3> n(nv, Vec3::Zero());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv, 2048), [&](const auto& r) {
    for (std::size_t v = r.begin(); v != r.end(); ++v) {
      Vec3 sum = Vec3::Zero();
      for (Index q = offset[v]; q < offset[v + 1]; ++q) sum += term[terms[q]];
      const double len = sum.norm();
      n[v] = len > 0 ? Vec3(sum / len) : sum;
    }
  });
  return n;
}

BoundingBox bounding_box(const SurfaceMesh& m) {
  BoundingBox b;
  for (Index v = 0; v < m.vertices_size(); ++v)
    if (!m.is_deleted(Vertex(v))) b.extend(m.position(Vertex(v)));
  return b;
}

double surface_area(const SurfaceMesh& m) {
  double a = 0;
  for (Index f = 0; f < m.faces_size(); ++f)
    if (!m.is_deleted(Face(f))) a += face_area(m, Face(f));
  return a;
}

Index connected_components(const SurfaceMesh& m, std::vector<Index>* labels_out) {
  std::vector<Index> labels(m.vertices_size(), kInvalidIndex);
  std::vector<Index> stack;
  std::vector<Vertex> ring;
  Index count = 0;
  for (Index s = 0; s < m.vertices_size(); ++s) {
    if (m.is_deleted(Vertex(s)) || labels[s] != kInvalidIndex) continue;
    labels[s] = count;
    stack.push_back(s);
    while (!stack.empty()) {
      const Index v = stack.back();
      stack.pop_back();
      m.one_ring(Vertex(v), ring);
      for (Vertex w : ring)
        if (labels[w.idx] == kInvalidIndex) {
          labels[w.idx] = count;
          stack.push_back(w.idx);
        }
    }
    ++count;
  }
  if (labels_out) *labels_out = std::move(labels);
  return count;
}

long euler_characteristic(const SurfaceMesh& m) {
  return long(m.n_vertices()) - long(m.n_edges()) + long(m.n_faces());
}

long genus(const SurfaceMesh& m) {
  return (2 * long(connected_components(m)) - euler_characteristic(m)) / 2;
}

std::size_t boundary_edge_count(const SurfaceMesh& m) {
  std::size_t n = 0;
  for (Index e = 0; e < m.edges_size(); ++e)
    if (!m.is_deleted(Edge(e)) && m.is_boundary(Edge(e))) ++n;
  return n;
}

Stats edge_length_stats(const SurfaceMesh& m) {
  std::vector<double> len;
  len.reserve(m.n_edges());
  for (Index e = 0; e < m.edges_size(); ++e)
    if (!m.is_deleted(Edge(e))) len.push_back((m.position(m.vertex(Edge(e), 0)) - m.position(m.vertex(Edge(e), 1))).norm());
  return make_stats(std::move(len));
}

double mean_edge_length(const SurfaceMesh& m) {
  double sum = 0;
  std::size_t n = 0;
  for (Index e = 0; e < m.edges_size(); ++e)
    if (!m.is_deleted(Edge(e))) {
      sum += (m.position(m.vertex(Edge(e), 0)) - m.position(m.vertex(Edge(e), 1))).norm();
      ++n;
    }
  return n ? sum / double(n) : 0.0;
}

std::array<double, 3> face_angles_deg(const SurfaceMesh& m, Face f) {
  const auto t = m.vertices(f);
  std::array<double, 3> a{};
  for (int k = 0; k < 3; ++k) {
    const Vec3& p = m.position(t[k]);
    a[k] = angle_between(m.position(t[(k + 1) % 3]) - p, m.position(t[(k + 2) % 3]) - p) * kRadToDeg;
  }
  return a;
}

double dihedral_angle_deg(const SurfaceMesh& m, Edge e) {
  const Halfedge h0 = m.halfedge(e, 0), h1 = m.halfedge(e, 1);
  if (m.is_boundary(h0) || m.is_boundary(h1)) return 180.0;
  const Vec3 n0 = face_normal(m, m.face(h0)), n1 = face_normal(m, m.face(h1));
  // Angle between the faces: 180° minus the angle between their normals.
  return 180.0 - angle_between(n0, n1) * kRadToDeg;
}

bool is_near_degenerate(const Vec3& p0, const Vec3& p1, const Vec3& p2) {
  if (!(min_angle_sin(p0, p1, p2) >= kNearDegenerateSin)) return true;
  // Through volatile floats: the optimiser must not fold the round trip away.
  const auto rounded = [](const Vec3& p) {
    volatile float x = static_cast<float>(p.x()), y = static_cast<float>(p.y()), z = static_cast<float>(p.z());
    return Vec3(double(x), double(y), double(z));
  };
  return !(min_angle_sin(rounded(p0), rounded(p1), rounded(p2)) >= kNearDegenerateSin);
}

QualityStats quality_stats(const SurfaceMesh& m) {
  QualityStats q;
  std::size_t nf = 0, below10 = 0;
  for (Index f = 0; f < m.faces_size(); ++f) {
    if (m.is_deleted(Face(f))) continue;
    ++nf;
    const auto a = face_angles_deg(m, Face(f));
    const double mn = std::min({a[0], a[1], a[2]});
    q.min_angle_deg = std::min(q.min_angle_deg, mn);
    below10 += mn < 10.0;
    q.below_2deg += mn < 2.0;
    const auto t = m.vertices(Face(f));
    q.near_degenerate += is_near_degenerate(m.position(t[0]), m.position(t[1]), m.position(t[2]));
  }
  q.share_below_10deg = nf ? double(below10) / double(nf) : 0.0;
  for (Index e = 0; e < m.edges_size(); ++e) {
    if (m.is_deleted(Edge(e)) || m.is_boundary(Edge(e))) continue;
    const double d = dihedral_angle_deg(m, Edge(e));
    q.min_dihedral_deg = std::min(q.min_dihedral_deg, d);
    q.dihedral_below_45deg += d < 45.0;
  }
  q.edge_length = edge_length_stats(m);
  return q;
}

Vec3 closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double v = d1 / (d1 - d3);
    return a + v * ab;
  }
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double w = d2 / (d2 - d6);
    return a + w * ac;
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return b + w * (c - b);
  }
  const double denom = va + vb + vc;
  if (!(std::abs(denom) > 0)) return a;  // degenerate triangle
  const double v = vb / denom, w = vc / denom;
  return a + ab * v + ac * w;
}

}  // namespace topotrack
