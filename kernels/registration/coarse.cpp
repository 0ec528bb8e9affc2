#include "kernels/registration/coarse.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>

#include "kernels/mesh/edge_graph.hpp"
#include "kernels/mesh/mesh_queries.hpp"
#include "kernels/registration/block_cholesky.hpp"
#include "kernels/registration/correspondences.hpp"
#include "kernels/registration/deformation_graph.hpp"
#include "kernels/registration/intrinsic_matches.hpp"

namespace topotrack {
namespace {

// A nested stage (the low-density pass, the denser graph) calls the caller's diagnostics hooks under its own stage.
void report_hooks_as(CoarseParams& nested, const CoarseParams& params, CoarseStage stage) {
  if (params.observer)
    nested.observer = [&params, stage](CoarseSnapshot snap) {
      snap.stage = stage;
      params.observer(snap);
    };
  if (params.match_override)
    nested.match_override = [&params, stage](CoarseMatchRound round, std::vector<Correspondence>& c) {
      round.stage = stage;
      params.match_override(round, c);
    };
}

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

using Mat3 = Eigen::Matrix3d;
using Mat12 = Eigen::Matrix<double, 12, 12>;
using Vec12 = Eigen::Matrix<double, 12, 1>;

// Unknowns of node j: the columns a1, a2, a3 of A_j (entries 0..8), then b_j (9..11).
struct NodeState {
  Mat3 A = Mat3::Identity();
  Vec3 b = Vec3::Zero();
};

struct Weights {
  double fit_point, fit_plane, rigid, smooth, damping_A, damping_b;
  double backward;  // weight of the backward correspondences relative to the forward ones
};

struct Problem {
  const DeformationGraph& graph;
  const std::vector<Vec3>& rest;  // vertex positions at the start (by handle)
  const SurfaceMesh& mesh;
};

Vec3 skin(const Problem& p, const std::vector<NodeState>& s, Index v) {
  const auto K = std::size_t(p.graph.k);
  const Vec3& x = p.rest[v];
  Vec3 out = Vec3::Zero();
  double wsum = 0;
  for (std::size_t t = 0; t < K; ++t) {
    const Index j = p.graph.influence_node[v * K + t];
    if (j == kInvalidIndex) continue;
    const double w = p.graph.influence_weight[v * K + t];
    const Vec3& g = p.graph.node_position[j];
    out += w * (s[j].A * (x - g) + g + s[j].b);
    wsum += w;
  }
  return wsum > 0 ? out : x;
}

// Angle-weighted normal of vertex v, its one-ring's vertices placed by `position` (by handle index).
template <class Position>
Vec3 angle_weighted_normal(const SurfaceMesh& mesh, Vertex v, std::vector<Halfedge>& ring, const Position& position) {
  mesh.outgoing(v, ring);
  const Vec3 x = position(v.idx);
  Vec3 n = Vec3::Zero();
  for (Halfedge h : ring) {
    if (mesh.is_boundary(h)) continue;
    const Vec3 a = position(mesh.to_vertex(h).idx) - x;
    const Vec3 b = position(mesh.to_vertex(mesh.next(h)).idx) - x;
    const Vec3 c = a.cross(b);
    const double len = c.norm(), la = a.norm(), lb = b.norm();
    if (!(len > 0) || !(la > 0) || !(lb > 0)) continue;
    const double angle = std::atan2(len, a.dot(b));
    n += angle * c / len;
  }
  const double len = n.norm();
  return len > 0 ? Vec3(n / len) : Vec3::Zero();
}

// Each node's normal transform A^-T (its cofactor matrix where A is near singular: the same direction up to sign).
std::vector<Mat3> normal_transforms(const std::vector<NodeState>& s) {
  std::vector<Mat3> out(s.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, s.size(), 256), [&](const auto& r) {
    for (std::size_t j = r.begin(); j != r.end(); ++j) {
      const Mat3& A = s[j].A;
      Mat3 C;  // cofactors: C = det(A) A^-T
      C.col(0) = A.col(1).cross(A.col(2));
      C.col(1) = A.col(2).cross(A.col(0));
      C.col(2) = A.col(0).cross(A.col(1));
      const double det = A.col(0).dot(C.col(0));
      out[j] = std::abs(det) > 1e-12 ? Mat3(C / det) : C;
    }
  });
  return out;
}

// The normal of vertex v (rest normal n) skinned like its position: sum_t w_t A_t^-T n, normalised (the embedded
// deformation's normals). Used for the vertices' fit (VertexFit), where one-ring skinning cost 7 skinnings a vertex.
Vec3 blended_normal(const Problem& p, const std::vector<Mat3>& transform, Index v, const Vec3& n) {
  const auto K = std::size_t(p.graph.k);
  Vec3 out = Vec3::Zero();
  for (std::size_t t = 0; t < K; ++t)
    if (const Index j = p.graph.influence_node[v * K + t]; j != kInvalidIndex)
      out += p.graph.influence_weight[v * K + t] * (transform[j] * n);
  const double len = out.norm();
  return len > 0 ? Vec3(out / len) : n;
}

// Angle-weighted normal of vertex v of the deformed mesh, from its deformed one-ring.
Vec3 skinned_normal(const Problem& p, const std::vector<NodeState>& s, Vertex v, std::vector<Halfedge>& ring) {
  return angle_weighted_normal(p.mesh, v, ring, [&](Index u) { return skin(p, s, u); });
}

double rigid_energy(const Mat3& A) {
  const Vec3 a1 = A.col(0), a2 = A.col(1), a3 = A.col(2);
  const double r1 = a1.dot(a2), r2 = a1.dot(a3), r3 = a2.dot(a3);
  const double r4 = 1 - a1.norm(), r5 = 1 - a2.norm(), r6 = 1 - a3.norm();
  return r1 * r1 + r2 * r2 + r3 * r3 + r4 * r4 + r5 * r5 + r6 * r6;
}

double fit_energy(const Vec3& x, const Correspondence& c, const Weights& w) {
  if (!c.valid()) return 0;
  const Vec3 r = x - c.point;
  const double rn = c.normal.dot(r);
  return w.fit_point * r.squaredNorm() + w.fit_plane * rn * rn;
}

struct Energy {
  double total = 0, fit = 0;  // fit: alpha_point |r|^2 + alpha_plane <n, r>^2 in relative units, unweighted by alpha_fit
};

// Forward correspondences of the nodes and (possibly empty) backward ones (see Weights::backward).
struct NodeMatches {
  const std::vector<Correspondence>& forward;
  const std::vector<Correspondence>& backward;
};

double node_fit_energy(const Vec3& x, const NodeMatches& m, std::size_t j, const Weights& w) {
  double f = fit_energy(x, m.forward[j], w);
  if (!m.backward.empty()) f += w.backward * fit_energy(x, m.backward[j], w);
  return f;
}

// CoarseParams::vertex_fit_weight: the fitting term at the mesh's vertices too. Vertex v (rest x_v) is skinned by its
// nodes t as sum_t w_t (A_t (x_v - g_t) + g_t + b_t), linear in node t's unknowns (a1, a2, a3, b) with coefficients
// w_t u_t, u_t = (x_v - g_t, 1): the Gauss–Newton block of nodes t, s is w_t w_s (u_t u_s^T) (x) W_v, W_v the 3 x 3
// weight of v's match, and every pair of nodes that share a vertex is a graph edge (deformation_graph.cpp).
struct VertexFit {
  std::vector<Vertex> vertex;           // the vertices fitted
  std::vector<Index> node_offset;       // node j's entries: [node_offset[j], node_offset[j + 1])
  std::vector<Index> entry_slot;        // per entry: its vertex q (index into `vertex`) and slot t, as q k + t
  std::vector<double> slot_weight;      // per vertex and influence slot t (k per vertex): w_t (0: no node)
  std::vector<Vec3> slot_offset;        // likewise x_v - g_t
  std::vector<Vec3> rest_normal;        // per vertex, of the rest mesh (angle-weighted)
  std::vector<Correspondence> match;    // per vertex, this round (invalid: no term)
  std::vector<Correspondence> back;     // per vertex, its backward match this round (empty: none; backward_vertex_weight)
  double back_scale = 0;                // its weight relative to `match`'s
  bool active(std::size_t q) const { return match[q].valid() || (!back.empty() && back[q].valid()); }
  std::vector<Vec3> x;                  // per vertex, skinned by the current state
  double weight = 0;                    // of a vertex's term relative to a node's
  bool empty() const { return vertex.empty(); }
};

// The vertices fitted: every vertex (spacing 0), or vertices sampled `spacing` apart like the nodes.
VertexFit build_vertex_fit(const Problem& p, double weight, double spacing) {
  VertexFit f;
  const DeformationGraph& g = p.graph;
  const auto K = std::size_t(g.k);
  const std::size_t nn = g.n_nodes();
  const auto influenced = [&](Vertex v) { return std::size_t(v.idx) * K < g.influence_node.size() && g.influence_node[v.idx * K] != kInvalidIndex; };
  if (spacing > 0) {
    for (Vertex v : sample_graph_nodes(p.mesh, spacing))
      if (influenced(v)) f.vertex.push_back(v);
  } else {
    for (std::size_t v = 0; v < p.mesh.vertices_size(); ++v)
      if (!p.mesh.is_deleted(Vertex(Index(v))) && influenced(Vertex(Index(v)))) f.vertex.push_back(Vertex(Index(v)));
  }
  if (f.vertex.empty()) return f;
  f.weight = weight * double(nn) / double(f.vertex.size());
  f.node_offset.assign(nn + 1, 0);
  for (Vertex v : f.vertex)
    for (std::size_t t = 0; t < K; ++t)
      if (const Index j = g.influence_node[v.idx * K + t]; j != kInvalidIndex) ++f.node_offset[j + 1];
  for (std::size_t j = 0; j < nn; ++j) f.node_offset[j + 1] += f.node_offset[j];
  const std::size_t ne = std::size_t(f.node_offset[nn]);
  f.entry_slot.resize(ne);
  f.slot_weight.assign(f.vertex.size() * K, 0.0);
  f.slot_offset.assign(f.vertex.size() * K, Vec3::Zero());
  std::vector<Index> fill(f.node_offset.begin(), f.node_offset.end() - 1);
  f.rest_normal.resize(f.vertex.size());
  std::vector<Halfedge> ring;
  for (std::size_t q = 0; q < f.vertex.size(); ++q) {
    f.rest_normal[q] = angle_weighted_normal(p.mesh, f.vertex[q], ring, [&](Index u) { return p.rest[u]; });
    const Index v = f.vertex[q].idx;
    for (std::size_t t = 0; t < K; ++t) {
      const Index j = g.influence_node[v * K + t];
      if (j == kInvalidIndex) continue;
      f.slot_weight[q * K + t] = g.influence_weight[v * K + t];
      f.slot_offset[q * K + t] = p.rest[v] - g.node_position[j];
      f.entry_slot[fill[j]++] = Index(q * K + t);
    }
  }
  return f;
}

Mat3 fit_matrix(const Correspondence& c, const Weights& w, double scale) {
  return scale * (w.fit_point * Mat3::Identity() + w.fit_plane * c.normal * c.normal.transpose());
}

// The vertices' fit energy for the state `s` (their skinned positions in `x`); summed in vertex order.
double vertex_fit_energy(const Problem& p, const std::vector<NodeState>& s, const VertexFit& f, const Weights& w,
                         std::vector<Vec3>& x, std::vector<double>& e) {
  const std::size_t n = f.vertex.size();
  x.resize(n);
  e.resize(n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const auto& r) {
    for (std::size_t q = r.begin(); q != r.end(); ++q) {
      x[q] = skin(p, s, f.vertex[q].idx);
      e[q] = fit_energy(x[q], f.match[q], w);
      if (!f.back.empty()) e[q] += f.back_scale * fit_energy(x[q], f.back[q], w);
    }
  });
  double sum = 0;
  for (const double v : e) sum += v;
  return f.weight * sum;
}

Energy evaluate_energy(const Problem& p, const std::vector<NodeState>& s, const NodeMatches& corr,
                       const Weights& w, double fit_scale, const VertexFit* vertices = nullptr) {
  const DeformationGraph& g = p.graph;
  const std::size_t nn = g.n_nodes();
  std::vector<double> total(nn), fit(nn);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nn, 64), [&](const auto& r) {
    for (std::size_t j = r.begin(); j != r.end(); ++j) {
      const double f = node_fit_energy(g.node_position[j] + s[j].b, corr, j, w);
      double e = f + w.rigid * rigid_energy(s[j].A);
      for (Index q = g.neighbor_offset[j]; q < g.neighbor_offset[j + 1]; ++q) {
        const Index k = g.neighbors[q];
        const Vec3 d = g.node_position[k] - g.node_position[j];
        const Vec3 res = s[j].A * d + g.node_position[j] + s[j].b - g.node_position[k] - s[k].b;
        e += w.smooth * res.squaredNorm();
      }
      total[j] = e;
      fit[j] = f * fit_scale;
    }
  });
  Energy out;
  for (std::size_t j = 0; j < nn; ++j) {
    out.total += total[j];
    out.fit += fit[j];
  }
  if (vertices && !vertices->empty()) {
    std::vector<Vec3> x;
    std::vector<double> e;
    out.total += vertex_fit_energy(p, s, *vertices, w, x, e);
  }
  return out;
}

// The lower triangle of a block matrix over the graph nodes (block size B) in compressed columns,
// built once: column B j + a holds rows B j + a .. B j + B - 1 of the diagonal block, then B rows per
// graph neighbour k > j. B = 12 for the Gauss–Newton matrix H, B = 4 for the per-coordinate
// preconditioner P.
struct SystemPattern {
  SparseCholesky::Matrix H;
  int block = 12;
};

SystemPattern build_pattern(const DeformationGraph& g, int B) {
  const std::size_t nn = g.n_nodes(), n = std::size_t(B) * nn;
  SystemPattern sp;
  sp.block = B;
  std::vector<int> outer(n + 1, 0);
  for (std::size_t j = 0; j < nn; ++j) {
    int upper = 0;
    for (Index q = g.neighbor_offset[j]; q < g.neighbor_offset[j + 1]; ++q) upper += g.neighbors[q] > j;
    for (int a = 0; a < B; ++a) outer[B * j + a + 1] = (B - a) + B * upper;
  }
  for (std::size_t c = 0; c < n; ++c) outer[c + 1] += outer[c];
  sp.H.resize(int(n), int(n));
  sp.H.makeCompressed();
  sp.H.resizeNonZeros(outer[n]);
  std::copy(outer.begin(), outer.end(), sp.H.outerIndexPtr());
  int* inner = sp.H.innerIndexPtr();
  for (std::size_t j = 0; j < nn; ++j)
    for (int a = 0; a < B; ++a) {
      int pos = outer[B * j + a];
      for (int r = a; r < B; ++r) inner[pos++] = int(B * j) + r;
      for (Index q = g.neighbor_offset[j]; q < g.neighbor_offset[j + 1]; ++q)
        if (g.neighbors[q] > j)
          for (int r = 0; r < B; ++r) inner[pos++] = int(B * g.neighbors[q]) + r;
    }
  std::fill(sp.H.valuePtr(), sp.H.valuePtr() + outer[n], 0.0);
  return sp;
}

// Index in a node's 12 unknowns of entry m (0..2: A(c, m); 3: b_c) of coordinate c.
inline int unknown(int m, int c) { return m < 3 ? 3 * m + c : 9 + c; }

// The 4 x 4 per-coordinate block of a 12 x 12 block, averaged over the coordinates. The smoothness
// and point-to-point terms are separable by coordinate with the same coefficients for x, y and z;
// only the rigidity and point-to-plane terms couple coordinates, and only within a node.
Eigen::Matrix4d coordinate_average(const Mat12& M) {
  Eigen::Matrix4d out;
  for (int m = 0; m < 4; ++m)
    for (int q = 0; q < 4; ++q)
      out(m, q) = (M(unknown(m, 0), unknown(q, 0)) + M(unknown(m, 1), unknown(q, 1)) +
                   M(unknown(m, 2), unknown(q, 2))) / 3.0;
  return out;
}

// The Gauss–Newton matrix of the PCG path, without storing its off-diagonal blocks: the 12 x 12 node
// blocks D_j, and the smoothness coupling of neighbours j, k, which only depends on alpha_reg and
// d = g_k - g_j: (H x)_j gets, from x_k, -w d_m b_k in column m of A_j and
// w (sum_m d_m a_m,k) - 2 w b_k in b_j.
struct NodeSystem {
  std::vector<Mat12> diag;          // D_j without the vertices' share (applied through the vertices, below)
  std::vector<Mat12> diag_inverse;  // of the whole D_j, the vertices' share included
  double smooth = 0;
  // With a vertex fit (VertexFit), the vertices' share of H, diagonal blocks included: applied through each vertex,
  // W_v times the product of its row of the skinning with x in `vertex_product` (scratch), then J_v^T of that. This
  // costs one 3 x 3 product per vertex instead of one per vertex and node (measured in docs/results.md 2026-12-03).
  const VertexFit* vertices = nullptr;
  std::vector<Mat3> vertex_matrix;  // per vertex: its W_v (zero: no match)
  mutable std::vector<Vec3> vertex_product;
};

// Fill the gradient g = J^T r and either the lower triangle of H (`full`, the direct path) or the node
// blocks with the per-coordinate matrix (`nodes`, `precond`: the PCG path) for the current state; each
// node writes its own columns and entries, so the result does not depend on the scheduling.
void assemble(const Problem& p, const std::vector<NodeState>& s, const NodeMatches& corr, const VertexFit* vertices,
              const Weights& w, SystemPattern* full, SystemPattern* precond, NodeSystem* nodes, Eigen::VectorXd& grad) {
  const DeformationGraph& g = p.graph;
  const std::size_t nn = g.n_nodes();
  const auto K = std::size_t(g.k);
  if (vertices && vertices->empty()) vertices = nullptr;
  // Each vertex's fit weight W_v and residual W_v (x_v - c_v) (x_v: VertexFit::x, skinned by `s`).
  std::vector<Mat3> vertex_matrix(vertices ? vertices->vertex.size() : 0, Mat3::Zero());
  std::vector<Vec3> vertex_residual(vertex_matrix.size(), Vec3::Zero());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, vertex_matrix.size(), 1024), [&](const auto& r) {
    for (std::size_t q = r.begin(); q != r.end(); ++q) {
      const Correspondence& c = vertices->match[q];
      if (c.valid()) {
        vertex_matrix[q] = fit_matrix(c, w, vertices->weight);
        vertex_residual[q] = vertex_matrix[q] * (vertices->x[q] - c.point);
      }
      if (!vertices->back.empty() && vertices->back[q].valid()) {
        const Correspondence& b = vertices->back[q];
        const Mat3 M = fit_matrix(b, w, vertices->weight * vertices->back_scale);
        vertex_matrix[q] += M;
        vertex_residual[q] += M * (vertices->x[q] - b.point);
      }
    }
  });
  grad.setZero(Eigen::Index(12 * nn));
  double* values = full ? full->H.valuePtr() : nullptr;
  const int* outer = full ? full->H.outerIndexPtr() : nullptr;
  double* pvalues = precond ? precond->H.valuePtr() : nullptr;
  const int* pouter = precond ? precond->H.outerIndexPtr() : nullptr;
  if (nodes) {
    nodes->diag.resize(nn);
    nodes->diag_inverse.resize(nn);
    nodes->smooth = w.smooth;
  }
  if (nodes) {
    nodes->vertices = vertices;
    nodes->vertex_matrix = std::move(vertex_matrix);
  }
  const std::vector<Mat3>& vertex_w = nodes ? nodes->vertex_matrix : vertex_matrix;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nn, 32), [&](const auto& range) {
    for (std::size_t j = range.begin(); j != range.end(); ++j) {
      Mat12 D = Mat12::Zero();
      Vec12 gj = Vec12::Zero();
      const Mat3& A = s[j].A;
      const Vec3& gpos = g.node_position[j];
      // E_rigid (§4.2): columns orthogonal and of unit length.
      {
        const Vec3 a[3] = {A.col(0), A.col(1), A.col(2)};
        const int pairs[3][2] = {{0, 1}, {0, 2}, {1, 2}};
        for (const auto& pr : pairs) {
          Eigen::Matrix<double, 9, 1> J = Eigen::Matrix<double, 9, 1>::Zero();
          J.segment<3>(3 * pr[0]) = a[pr[1]];
          J.segment<3>(3 * pr[1]) = a[pr[0]];
          const double r = a[pr[0]].dot(a[pr[1]]);
          D.topLeftCorner<9, 9>() += w.rigid * J * J.transpose();
          gj.head<9>() += w.rigid * r * J;
        }
        for (int c = 0; c < 3; ++c) {
          const double len = a[c].norm();
          if (!(len > 0)) continue;
          const Vec3 J = -a[c] / len;
          const double r = 1 - len;
          D.block<3, 3>(3 * c, 3 * c) += w.rigid * J * J.transpose();
          gj.segment<3>(3 * c) += w.rigid * r * J;
        }
      }
      // E_fit at the node: point-to-point and point-to-plane.
      auto add_fit = [&](const Correspondence& c, double scale) {
        if (!c.valid()) return;
        const Vec3 r = gpos + s[j].b - c.point;
        const Mat3 W = scale * (w.fit_point * Mat3::Identity() + w.fit_plane * c.normal * c.normal.transpose());
        D.block<3, 3>(9, 9) += W;
        gj.tail<3>() += W * r;
      };
      add_fit(corr.forward[j], 1);
      if (!corr.backward.empty()) add_fit(corr.backward[j], w.backward);
      // E_smooth over both directed edges j->k and k->j.
      for (Index q = g.neighbor_offset[j]; q < g.neighbor_offset[j + 1]; ++q) {
        const Index k = g.neighbors[q];
        const Vec3& gk = g.node_position[k];
        const Vec3 d = gk - gpos;  // j -> k
        const Vec3 r_jk = A * d + gpos + s[j].b - gk - s[k].b;
        const Vec3 r_kj = s[k].A * (-d) + gk + s[k].b - gpos - s[j].b;
        // j -> k: J_j = [d0 I, d1 I, d2 I, I].
        for (int c1 = 0; c1 < 4; ++c1) {
          const double f1 = c1 < 3 ? d[c1] : 1.0;
          gj.segment<3>(3 * c1) += w.smooth * f1 * r_jk;
          for (int c2 = 0; c2 < 4; ++c2) {
            const double f2 = c2 < 3 ? d[c2] : 1.0;
            D.block<3, 3>(3 * c1, 3 * c2).diagonal().array() += w.smooth * f1 * f2;
          }
        }
        // k -> j: J wrt b_j = -I.
        D.block<3, 3>(9, 9).diagonal().array() += w.smooth;
        gj.tail<3>() -= w.smooth * r_kj;
      }
      // Levenberg–Marquardt damping.
      for (int c = 0; c < 9; ++c) D(c, c) += w.damping_A;
      for (int c = 9; c < 12; ++c) D(c, c) += w.damping_b;
      if (nodes) nodes->diag[j] = D;  // without the vertices' share, which apply_system adds through the vertices
      // E_fit at the vertices node j skins (VertexFit): J = w_j u^T (x) I over (a1, a2, a3, b).
      if (vertices)
        for (Index e = vertices->node_offset[j]; e < vertices->node_offset[j + 1]; ++e) {
          const std::size_t slot = vertices->entry_slot[e], q = slot / K;
          if (!vertices->active(q)) continue;
          const double wt = vertices->slot_weight[slot];
          const Vec3& o = vertices->slot_offset[slot];
          const Eigen::Vector4d u(o.x(), o.y(), o.z(), 1);
          for (int m = 0; m < 4; ++m) {
            gj.segment<3>(3 * m) += wt * u[m] * vertex_residual[q];
            for (int c = 0; c < 4; ++c) D.block<3, 3>(3 * m, 3 * c) += (wt * wt * u[m] * u[c]) * vertex_w[q];
          }
        }

      grad.segment<12>(Eigen::Index(12 * j)) = gj;
      if (nodes) nodes->diag_inverse[j] = D.ldlt().solve(Mat12::Identity());
      if (values)
        for (int a = 0; a < 12; ++a) {
          int pos = outer[12 * j + a];
          for (int r = a; r < 12; ++r) values[pos++] = D(r, a);
        }
      if (precond) {
        const Eigen::Matrix4d P = coordinate_average(D);
        for (int a = 0; a < 4; ++a) {
          int pos = pouter[4 * j + a];
          for (int r = a; r < 4; ++r) pvalues[pos++] = P(r, a);
        }
      }
      if (!values && !precond) continue;
      // Off-diagonal blocks H_kj (rows: unknowns of k > j, columns: unknowns of j), m-th of j's neighbours k > j.
      const Index first_upper = Index(std::upper_bound(g.neighbors.begin() + g.neighbor_offset[j],
                                                       g.neighbors.begin() + g.neighbor_offset[j + 1], Index(j)) -
                                      g.neighbors.begin());
      const auto n_upper = std::size_t(g.neighbor_offset[j + 1] - first_upper);
      // The vertices node j skins with a node k > j, each as f(m, w_k w_j u_k u_j^T, W_v): the block
      // w_k w_j (u_k u_j^T) (x) W_v of H_kj, k the m-th upper neighbour.
      const auto vertex_pairs = [&](const auto& f) {
        if (!vertices) return;
        for (Index e = vertices->node_offset[j]; e < vertices->node_offset[j + 1]; ++e) {
          const std::size_t slot = vertices->entry_slot[e], q = slot / K;
          if (!vertices->active(q)) continue;
          const Index v = vertices->vertex[q].idx;
          const Vec3& oj = vertices->slot_offset[slot];
          const Eigen::Vector4d uj = vertices->slot_weight[slot] * Eigen::Vector4d(oj.x(), oj.y(), oj.z(), 1);
          for (std::size_t t = 0; t < K; ++t) {
            const Index k = g.influence_node[v * K + t];
            if (k == kInvalidIndex || k <= Index(j)) continue;
            const auto at = std::lower_bound(g.neighbors.begin() + first_upper, g.neighbors.begin() + g.neighbor_offset[j + 1], k);
            const Vec3& ok = vertices->slot_offset[q * K + t];
            const Eigen::Vector4d uk = vertices->slot_weight[q * K + t] * Eigen::Vector4d(ok.x(), ok.y(), ok.z(), 1);
            f(std::size_t(at - (g.neighbors.begin() + first_upper)), Eigen::Matrix4d(uk * uj.transpose()), vertex_w[q]);
          }
        }
      };
      // E_smooth's share of H_kj: j -> k (J_k = [0, 0, 0, -I], J_j = [d0 I, d1 I, d2 I, I]) in the rows of b_k,
      // k -> j (J_k = [-d0 I, -d1 I, -d2 I, I], its edge vector -d; J_j = [0, 0, 0, -I]) in the columns of b_j: of the
      // 4 x 4 grid of 3 x 3 blocks, the diagonal of block (3, c) gets -row[c] and that of block (c, 3) -col[c].
      const auto smooth_coefficients = [&](std::size_t m, double (&row)[4], double (&col)[4]) {
        const Vec3 d = g.node_position[g.neighbors[first_upper + Index(m)]] - gpos;
        for (int c = 0; c < 4; ++c) {
          row[c] = w.smooth * (c < 3 ? d[c] : 1.0);
          col[c] = w.smooth * (c < 3 ? -d[c] : 1.0);
        }
      };
      if (values) {  // the direct path: the whole 12 x 12 blocks
        std::vector<Mat12> upper(n_upper, Mat12::Zero());
        vertex_pairs([&](std::size_t m, const Eigen::Matrix4d& M, const Mat3& W) {
          for (int a = 0; a < 4; ++a)
            for (int c = 0; c < 4; ++c) upper[m].block<3, 3>(3 * a, 3 * c) += M(a, c) * W;
        });
        for (std::size_t m = 0; m < n_upper; ++m) {
          Mat12& B = upper[m];
          double row[4], col[4];
          smooth_coefficients(m, row, col);
          for (int c = 0; c < 4; ++c) {
            B.block<3, 3>(9, 3 * c).diagonal().array() -= row[c];
            B.block<3, 3>(3 * c, 9).diagonal().array() -= col[c];
          }
          for (int a = 0; a < 12; ++a) {
            const int pos = outer[12 * j + a] + (12 - a) + 12 * int(m);
            for (int r = 0; r < 12; ++r) values[pos + r] = B(r, a);
          }
        }
      } else {  // the PCG path: only the preconditioner's coordinate averages, built as 4 x 4 blocks
        std::vector<Eigen::Matrix4d> upper(n_upper, Eigen::Matrix4d::Zero());
        vertex_pairs([&](std::size_t m, const Eigen::Matrix4d& M, const Mat3& W) { upper[m] += (W.trace() / 3.0) * M; });
        for (std::size_t m = 0; m < n_upper; ++m) {
          Eigen::Matrix4d& P = upper[m];
          double row[4], col[4];
          smooth_coefficients(m, row, col);
          Eigen::Matrix4d S = Eigen::Matrix4d::Zero();
          for (int c = 0; c < 4; ++c) {
            S(3, c) -= row[c];
            S(c, 3) -= col[c];
          }
          // Each entry e is the same for x, y and z: averaged as coordinate_average does, (e + e + e) / 3, so that a
          // system without vertices is the same to the bit as when the 12 x 12 blocks were built and averaged.
          P += S.unaryExpr([](double e) { return (e + e + e) / 3.0; });
          for (int a = 0; a < 4; ++a) {
            const int pos = pouter[4 * j + a] + (4 - a) + 4 * int(m);
            for (int r = 0; r < 4; ++r) pvalues[pos + r] = P(r, a);
          }
        }
      }
    }
  });
}

// y = H x, matrix-free off the diagonal (see NodeSystem); parallel over nodes, each writes its own rows.
void apply_system(const DeformationGraph& g, const NodeSystem& sys, const Eigen::VectorXd& x, Eigen::VectorXd& y) {
  const std::size_t nn = g.n_nodes();
  y.resize(x.size());
  // Node j's unknowns x_j applied to u: A u.head(3) + b (the 3 x 4 matrix [a1 a2 a3 b] times u).
  const auto apply_node = [&x](std::size_t j, const Vec3& offset) {
    const auto xj = x.segment<12>(Eigen::Index(12 * j));
    return Vec3(offset.x() * xj.segment<3>(0) + offset.y() * xj.segment<3>(3) + offset.z() * xj.segment<3>(6) + xj.tail<3>());
  };
  const VertexFit* vf = sys.vertices;
  const auto K = std::size_t(g.k);
  if (vf) {  // each vertex's weight times its skinning row times x: W_v sum_t w_t X_t u_t
    sys.vertex_product.resize(vf->vertex.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, vf->vertex.size(), 1024), [&](const auto& r) {
      for (std::size_t q = r.begin(); q != r.end(); ++q) {
        if (!vf->active(q)) {
          sys.vertex_product[q].setZero();
          continue;
        }
        Vec3 sum = Vec3::Zero();
        const Index v = vf->vertex[q].idx;
        for (std::size_t t = 0; t < K; ++t)
          if (const Index k = g.influence_node[v * K + t]; k != kInvalidIndex)
            sum += vf->slot_weight[q * K + t] * apply_node(std::size_t(k), vf->slot_offset[q * K + t]);
        sys.vertex_product[q] = sys.vertex_matrix[q] * sum;
      }
    });
  }
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nn, 128), [&](const auto& range) {
    for (std::size_t j = range.begin(); j != range.end(); ++j) {
      // lazyProduct: an unrolled product; Eigen's `*` called its general GEMV kernel for this fixed 12 x 12 block, 1.3x
      // the time in isolation (registration_bench BM_Block12Product, the same sums to the bit).
      Vec12 yj = sys.diag[j].lazyProduct(x.segment<12>(Eigen::Index(12 * j)));
      if (vf)  // the vertices node j skins, their whole share (diag[j] holds none of it): w_j u (x) W_v J_v x
        for (Index e = vf->node_offset[j]; e < vf->node_offset[j + 1]; ++e) {
          const std::size_t slot = vf->entry_slot[e];
          const Vec3& o = vf->slot_offset[slot];
          const Vec3 f = vf->slot_weight[slot] * sys.vertex_product[slot / K];
          yj.segment<3>(0) += o.x() * f;
          yj.segment<3>(3) += o.y() * f;
          yj.segment<3>(6) += o.z() * f;
          yj.tail<3>() += f;
        }
      const Vec3& gj = g.node_position[j];
      for (Index q = g.neighbor_offset[j]; q < g.neighbor_offset[j + 1]; ++q) {
        const Index k = g.neighbors[q];
        const Vec3 d = g.node_position[k] - gj;
        const auto xk = x.segment<12>(Eigen::Index(12 * k));
        const Vec3 bk = xk.tail<3>();
        for (int m = 0; m < 3; ++m) yj.segment<3>(3 * m) -= sys.smooth * d[m] * bk;
        yj.tail<3>() += sys.smooth * (d[0] * xk.segment<3>(0) + d[1] * xk.segment<3>(3) + d[2] * xk.segment<3>(6) - 2 * bk);
      }
      y.segment<12>(Eigen::Index(12 * j)) = yj;
    }
  });
}

// Solve H x = rhs by preconditioned conjugate gradients. The preconditioner is a symmetric
// multiplicative two-level scheme: node-block Jacobi (the exact 12 x 12 diagonal blocks, which hold
// the stiff rigidity coupling of x, y, z within a node), then a coarse correction by the Cholesky
// factor of the per-coordinate matrix P (the coupling between nodes), then block Jacobi again. The
// node's 12 unknowns (a1, a2, a3, b) are 4 rows of (x, y, z), so a vector is already P's 4N x 3
// right-hand side, row-major. Without P (CoarseParams::pcg_coarse_correction off): block Jacobi alone.
int preconditioned_cg(const DeformationGraph& g, const NodeSystem& sys, const BlockCholesky* P,
                      const Eigen::VectorXd& rhs, double tolerance, int max_iterations, Eigen::VectorXd& x) {
  const Eigen::Index nn = rhs.size() / 12;
  Eigen::VectorXd t(rhs.size()), Ht(rhs.size());
  auto apply_blocks = [&](const Eigen::VectorXd& r, Eigen::VectorXd& z, bool add) {
    tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, nn, 256), [&](const auto& range) {
      for (Eigen::Index j = range.begin(); j != range.end(); ++j) {
        const Vec12 zj = sys.diag_inverse[std::size_t(j)].lazyProduct(r.segment<12>(12 * j));  // as in apply_system
        if (add) z.segment<12>(12 * j) += zj;
        else z.segment<12>(12 * j) = zj;
      }
    });
  };
  auto precondition = [&](const Eigen::VectorXd& r, Eigen::VectorXd& z) {
    z.resize(r.size());
    apply_blocks(r, z, false);
    if (!P) return;
    apply_system(g, sys, z, Ht);
    t = r - Ht;
    P->solve3(t.data());
    z += t;
    apply_system(g, sys, z, Ht);
    t = r - Ht;
    apply_blocks(t, z, true);
  };
  x.setZero(rhs.size());
  const double rhs_norm = rhs.norm();
  if (!(rhs_norm > 0)) return 0;
  Eigen::VectorXd r = rhs, z, p, Hp;
  precondition(r, z);
  p = z;
  double rz = r.dot(z);
  int it = 0;
  while (it < max_iterations && r.norm() > tolerance * rhs_norm) {
    apply_system(g, sys, p, Hp);
    const double pHp = p.dot(Hp);
    if (!(pHp > 0)) break;
    const double alpha = rz / pHp;
    x += alpha * p;
    r -= alpha * Hp;
    precondition(r, z);
    const double rz_new = r.dot(z);
    p = z + (rz_new / rz) * p;
    rz = rz_new;
    ++it;
  }
  return it;
}

// Matches given to the nodes of a pass (the intrinsic matches of the large-motion stage): the nodes, their
// spacing, and per node a match that replaces its ray's in every round where it is valid.
struct NodeGuide {
  std::vector<Vertex> nodes;
  double spacing = 0;
  std::vector<Correspondence> match;
  //! When set (the guided passes), the graph over `nodes` to use instead of building one: its skinning
  //! weights and edges are kept, the mesh as it is now becomes its rest state.
  std::shared_ptr<const DeformationGraph> graph;
};

// `built`, when given, receives the graph the rounds ran on.
CoarseReport align_coarse_impl(SurfaceMesh& mesh, const TargetSurface& target, const CoarseParams& params,
                               const NodeGuide* guide, std::shared_ptr<const DeformationGraph>* built = nullptr);

// A low-density pass's report added to CoarseReport::low_density (or the denser graph's to CoarseReport::dense).
void add_pass(CoarsePhases& to, const CoarseReport& pass) {
  to.nodes = pass.nodes;
  to.rounds += pass.iterations;
  to.pcg_iterations += pass.pcg_iterations;
  to.factorisations += pass.factorisations;
  to.seconds_graph += pass.seconds_graph;
  to.seconds_correspondences += pass.seconds_correspondences;
  to.seconds_assembly += pass.seconds_assembly;
  to.seconds_factorisation += pass.seconds_factorisation;
  to.seconds_solve += pass.seconds_solve;
  to.seconds_total += pass.seconds_total;
}

// The large-motion intrinsic stage (CoarseParams::intrinsic_full_graph, intrinsic_passes), after the low-density pass
// `pass`: nodes are placed by their geodesic distances (intrinsic_matches.hpp); up to intrinsic_passes times,
// while some of the pass's nodes are misplaced, the pass runs again with their places as their matches; then
// the full graph's misplaced nodes get theirs (the guide returned, for the full graph's rounds).
// The guided passes start at this alpha_reg: the first pass has fitted all but the misplaced parts. Measured
// (elephant frame 1 -> 16, two guided passes, median over five re-samplings; 2026-12-01, each guided pass then on
// its own graph with 8 rounds per level): 1.01 % of the diagonal from 10, 1.08 % from 1000 (the first pass's
// start), at two thirds of the time per pass.
constexpr double kGuidedPassAlphaRegStart = 10;

// The node spacing of a graph built with `params` on a mesh of mean edge length `edge` (§4.2: node_spacing_factor
// edges at full density; graph_density d spaces them 1/sqrt(d) wider).
double graph_spacing(const CoarseParams& params, double edge) {
  return params.node_spacing_factor * edge / std::sqrt(params.graph_density);
}

std::optional<NodeGuide> intrinsic_stage(SurfaceMesh& mesh, const TargetSurface& target, const CoarseParams& params,
                                         const CoarseParams& pass, std::shared_ptr<const DeformationGraph> pass_graph,
                                         const EdgeGraph& rest, double edge, CoarseReport& rep) {
  auto t0 = Clock::now();
  const EdgeGraph target_graph = edge_graph(target.positions(), target.triangles());
  // Nodes at the pass's spacing sampled on the rest state, the anchors' candidates; every length of the
  // matching in units of their spacing.
  NodeGuide guide;
  guide.spacing = graph_spacing(pass, mean_edge_length(mesh));
  const std::vector<Index> nodes = poisson_disk_samples(rest, guide.spacing);
  std::vector<Vec3> x(nodes.size());
  for (std::size_t j = 0; j < nodes.size(); ++j) {
    guide.nodes.push_back(Vertex(nodes[j]));
    x[j] = mesh.position(guide.nodes[j]);
  }
  const IntrinsicAnchors anchors = intrinsic_anchors(rest, nodes, x, params.intrinsic.anchors);
  std::vector<Vec3> ax(anchors.anchor.size());
  IntrinsicTargetCache target_cache;  // the target's fields and candidates, shared by the matchings below
  // The intrinsic matches of `at` (source vertices) for the mesh as it is now.
  const auto matches = [&](const std::vector<Index>& at, std::vector<Vec3>& at_x) {
    for (std::size_t j = 0; j < at.size(); ++j) at_x[j] = mesh.position(Vertex(at[j]));
    for (std::size_t a = 0; a < ax.size(); ++a) ax[a] = mesh.position(Vertex(anchors.anchor[a]));
    return intrinsic_matches(anchors, ax, at, at_x, target, target_graph, guide.spacing, params.intrinsic, &target_cache);
  };
  CoarseParams guided = pass;
  guided.alpha_reg_start = std::min(pass.alpha_reg_start, kGuidedPassAlphaRegStart);
  guided.max_iterations_per_level = params.intrinsic_pass_max_iterations_per_level;
  // The guided passes run on the first pass's graph (its nodes, weights and edges; the mesh as it is now its
  // rest state): no graph to build again.
  std::vector<Index> pass_nodes = nodes;
  if (pass_graph) {
    guide.graph = pass_graph;
    guide.nodes = pass_graph->node_vertex;
    pass_nodes.resize(guide.nodes.size());
    for (std::size_t j = 0; j < guide.nodes.size(); ++j) pass_nodes[j] = guide.nodes[j].idx;
  }
  std::vector<Vec3> pass_x(pass_nodes.size());
  for (int k = 0; k < params.intrinsic_passes; ++k) {
    IntrinsicMatches im = matches(pass_nodes, pass_x);
    if (k == 0) rep.intrinsic_misplaced = im.misplaced;
    if (im.misplaced == 0) break;
    guide.match = std::move(im.match);
    rep.seconds_intrinsic += seconds_since(t0);
    const CoarseReport pr = align_coarse_impl(mesh, target, guided, &guide);
    rep.coarse_pass_iterations += pr.iterations;
    add_pass(rep.low_density, pr);
    ++rep.intrinsic_passes;
    t0 = Clock::now();
  }
  if (!params.intrinsic_full_graph) {
    rep.seconds_intrinsic += seconds_since(t0);
    return std::nullopt;
  }
  // The full graph's nodes, as align_coarse_impl samples them after the pass.
  NodeGuide full;
  full.spacing = graph_spacing(params, edge);
  full.nodes = sample_graph_nodes(mesh, full.spacing);
  std::vector<Index> fn(full.nodes.size());
  for (std::size_t j = 0; j < fn.size(); ++j) fn[j] = full.nodes[j].idx;
  std::vector<Vec3> fx(fn.size());
  IntrinsicMatches im = matches(fn, fx);
  rep.seconds_intrinsic += seconds_since(t0);
  rep.intrinsic_full_graph_misplaced = im.misplaced;
  if (im.misplaced == 0) return std::nullopt;
  full.match = std::move(im.match);
  return full;
}

// The low-density pass's share of the full graph's density where the misfit is small: CoarseParams::near_pass_density,
// its spacing held at near_pass_min_spacing of the diagonal at least (`edge`: the mesh's mean edge length in diagonals).
double near_pass_density(const CoarseParams& params, double edge) {
  double density = params.near_pass_density;
  if (params.near_pass_min_spacing > 0) {
    const double widest = graph_spacing(params, edge) / params.near_pass_min_spacing;
    density = std::min(density, widest * widest);
  }
  return std::max(density, params.coarse_pass_density);
}

// CoarseParams::min_nodes: the node spacing factor that gives a graph of at least min_nodes nodes at full density.
double node_spacing_for(const SurfaceMesh& mesh, const CoarseParams& params) {
  const double factor = params.node_spacing_factor;
  if (params.min_nodes <= 0 || !(factor > params.min_node_spacing_factor)) return factor;
  // A graph has about 0.67-0.76 nodes per (factor)^2 vertices (samba, pcow, the elephant): only a mesh that could
  // have fewer than min_nodes is sampled (a second time, at a cost its few vertices make small).
  if (double(mesh.n_vertices()) / (factor * factor) > 4.0 * params.min_nodes) return factor;
  const double n = double(sample_graph_nodes(mesh, factor * mean_edge_length(mesh)).size());
  if (n >= params.min_nodes) return factor;
  return std::max(params.min_node_spacing_factor, factor * std::sqrt(n / params.min_nodes));
}

}  // namespace

CoarseReport align_coarse(SurfaceMesh& mesh, const TargetSurface& target, const CoarseParams& params) {
  const auto t_total = Clock::now();
  if (!(params.dense_spacing_factor >= 0) || !(params.dense_alpha_reg > 0) || params.dense_max_pcg_iterations < 1 || params.min_nodes < 0 ||
      !(params.min_node_spacing_factor > 0))
    TT_THROW(InvalidInput, "align_coarse: invalid parameters");
  if (mesh.n_vertices() == 0 || mesh.n_faces() == 0) TT_THROW(InvalidInput, "align_coarse: empty mesh");
  CoarseParams sized = params;
  sized.node_spacing_factor = node_spacing_for(mesh, params);
  CoarseReport rep = align_coarse_impl(mesh, target, sized, nullptr);
  rep.seconds_total = seconds_since(t_total);  // with min_nodes' sampling
  if (!(params.dense_spacing_factor > 0) || !(params.dense_spacing_factor < sized.node_spacing_factor) ||
      rep.coarse_pass_iterations > 0 || rep.fitted_at_start || rep.iterations == 0)
    return rep;
  // The denser graph (CoarseParams::dense_spacing_factor): one level on the mesh as the schedule left it, the paper's
  // normal rays and energy, none of the large-motion stages (the misfit called for none of them).
  CoarseParams dense = params;
  dense.node_spacing_factor = params.dense_spacing_factor;
  dense.alpha_reg_start = params.dense_alpha_reg;
  dense.alpha_reg_min = params.dense_alpha_reg;
  dense.prealign_misfit = 0;
  dense.coarse_pass_misfit = 0;
  dense.backward_misfit = 0;
  dense.backward_weight = 0;
  dense.closest_point_levels = 0;
  dense.intrinsic_full_graph = false;
  dense.intrinsic_passes = 0;
  dense.check_fit_first = false;  // the full graph's nodes are fitted; the denser graph's finer fit is the point
  report_hooks_as(dense, params, CoarseStage::DenseLevel);
  // Its rounds start where the full graph's converged: a local refinement, which block Jacobi alone resolves in a
  // few PCG iterations (CoarseParams::dense_max_pcg_iterations).
  dense.max_pcg_iterations = params.dense_max_pcg_iterations;
  dense.pcg_coarse_correction = false;
  const CoarseReport dr = align_coarse_impl(mesh, target, dense, nullptr);
  add_pass(rep.dense, dr);
  rep.seconds_total = seconds_since(t_total);
  return rep;
}

namespace {

CoarseReport align_coarse_impl(SurfaceMesh& mesh, const TargetSurface& target, const CoarseParams& params,
                               const NodeGuide* guide, std::shared_ptr<const DeformationGraph>* built) {
  const auto t_total = Clock::now();
  CoarseReport rep;
  if (!(params.node_spacing_factor > 0) || !(params.graph_density > 0) || params.graph_density > 1 ||
      !(params.alpha_reg_start > 0) || !(params.alpha_reg_min > 0) || !(params.alpha_fit >= 0) ||
      !(params.alpha_point >= 0) || !(params.alpha_plane >= 0) || params.max_iterations < 0 ||
      params.max_iterations_per_level < 1 || params.max_iterations_per_level_after_pass < 1 ||
      !(params.damping > 0) || !(params.step_tolerance >= 0) || !(params.fit_tolerance >= 0) ||
      !(params.stall_ratio >= 0) || !(params.prealign_misfit >= 0) || params.closest_point_levels < 0 ||
      !(params.alpha_reg_start_after_pass >= 0) || !(params.alpha_reg_start_without_pass >= 0) ||
      !(params.check_fit_first_tolerance >= 0) ||
      !(params.coarse_pass_misfit >= 0) || !(params.coarse_pass_density > 0) || params.coarse_pass_density > 1 ||
      !(params.coarse_pass_alpha_reg_min > 0) || !(params.near_pass_density >= 0) || params.near_pass_density > 1 ||
      !(params.near_pass_misfit >= 0) || !(params.near_pass_min_spacing >= 0) ||
      params.near_pass_max_iterations_per_level < 1 || !(params.backward_weight >= 0) || !(params.backward_misfit >= 0) ||
      !(params.backward_all_misfit >= 0) || params.intrinsic_passes < 0 || params.intrinsic_pass_max_iterations_per_level < 1 ||
      params.backward_samples_per_node < 1 || !(params.vertex_fit_weight >= 0) || !(params.vertex_fit_spacing >= 0) ||
      !(params.vertex_fit_max_disagreement >= 0))
    TT_THROW(InvalidInput, "align_coarse: invalid parameters");
  if (params.prealign_misfit > 0 || params.coarse_pass_misfit > 0) validate(params.prealign);
  if (mesh.n_vertices() == 0 || mesh.n_faces() == 0) TT_THROW(InvalidInput, "align_coarse: empty mesh");

  if (const double d0 = bounding_box(mesh).diagonal(); !std::isfinite(d0))
    TT_THROW(InvalidInput, "align_coarse: non-finite vertex positions");
  auto t0 = Clock::now();
  const double edge = mean_edge_length(mesh);
  bool large_motion = false;
  bool pass_skipped = false;  // the misfit was measured and called for no low-density pass
  // Backward correspondences (target -> nodes) for large motion: for the nodes whose forward match is
  // pruned, or for every node (`backward_all`); always when their misfit threshold is 0.
  bool backward = params.backward_weight > 0 && params.backward_misfit == 0;
  bool backward_all = backward && params.backward_all_misfit == 0;
  std::optional<NodeGuide> full_guide;
  if (params.prealign_misfit > 0 || params.coarse_pass_misfit > 0 || params.backward_misfit > 0) {
    rep.misfit_start = trimmed_mean_distance(mesh, target, params.prealign) / target.bbox_diagonal();
    large_motion = params.prealign_misfit > 0 && rep.misfit_start > params.prealign_misfit;
    backward = backward || (params.backward_weight > 0 && rep.misfit_start > params.backward_misfit);
    backward_all = backward_all || (backward && rep.misfit_start > params.backward_all_misfit);
    const bool pass_runs = params.coarse_pass_misfit > 0 && rep.misfit_start > params.coarse_pass_misfit;
    pass_skipped = params.coarse_pass_misfit > 0 && !pass_runs;
    // The intrinsic stage's distances are the rest state's: its edge graph before anything moves the mesh.
    const bool intrinsic = pass_runs && (params.intrinsic_full_graph || params.intrinsic_passes > 0);
    const EdgeGraph rest_graph = intrinsic ? edge_graph(mesh) : EdgeGraph{};
    if (large_motion) {
      rep.prealign = align_rigid(mesh, target, params.prealign);
      rep.prealigned = rep.prealign.applied;
      if (params.observer && rep.prealigned)
        params.observer(CoarseSnapshot{CoarseStage::Prealigned, 0, rep.prealign.iterations, 0, mesh.positions()});
    }
    if (pass_runs) {
      CoarseParams pass = params;
      const bool near = params.near_pass_density > 0 && rep.misfit_start < params.near_pass_misfit;
      pass.graph_density = params.graph_density * (near ? near_pass_density(params, edge / target.bbox_diagonal())
                                                         : params.coarse_pass_density);
      if (near) pass.max_iterations_per_level = params.near_pass_max_iterations_per_level;
      pass.alpha_reg_min = params.coarse_pass_alpha_reg_min;
      pass.prealign_misfit = 0;
      pass.coarse_pass_misfit = 0;
      pass.backward_misfit = 0;
      pass.backward_all_misfit = backward_all ? 0 : std::numeric_limits<double>::infinity();
      if (!backward) pass.backward_weight = 0;
      report_hooks_as(pass, params, CoarseStage::LowDensityLevel);
      pass.intrinsic_passes = 0;
      pass.intrinsic_full_graph = false;
      pass.vertex_fit_weight = 0;  // (CoarseParams::vertex_fit_weight: the full graph's alone)
      std::shared_ptr<const DeformationGraph> pass_graph;
      const CoarseReport pr = align_coarse_impl(mesh, target, pass, nullptr, params.intrinsic_passes > 0 ? &pass_graph : nullptr);
      rep.coarse_pass_iterations = pr.iterations;
      add_pass(rep.low_density, pr);
      if (params.intrinsic_full_graph || params.intrinsic_passes > 0)
        full_guide = intrinsic_stage(mesh, target, params, pass, std::move(pass_graph), rest_graph, edge, rep);
    }
  }
  rep.backward = backward;
  rep.backward_all = backward_all;
  rep.seconds_prealign = seconds_since(t0);
  // Relative units: the scene's bounding-box diagonal is 1 (§4.2), after the pre-alignment.
  BoundingBox scene = bounding_box(mesh);
  scene.extend(target.bounds().min);
  scene.extend(target.bounds().max);
  const double D = scene.diagonal();
  if (!(D > 0) || !std::isfinite(D)) TT_THROW(InvalidInput, "align_coarse: degenerate or non-finite scene");
  const double inv_d2 = 1.0 / (D * D);

  CorrespondenceParams cparams;
  cparams.max_normal_angle_deg = params.max_normal_angle_deg;
  cparams.max_closest_ratio = params.max_closest_ratio;
  cparams.closest_point = large_motion && params.closest_point_levels > 0;

  t0 = Clock::now();
  if (full_guide) guide = &*full_guide;  // the intrinsic stage's matches for the full graph's nodes
  const double spacing = guide ? guide->spacing : graph_spacing(params, edge);
  std::vector<Vertex> nodes = guide ? guide->nodes : sample_graph_nodes(mesh, spacing);
  rep.node_spacing = spacing;
  const double fitted_first = params.check_fit_first_tolerance > 0 ? params.check_fit_first_tolerance : params.fit_tolerance;
  if (params.check_fit_first && fitted_first > 0 && !guide) {
    // Converged before the first step: the nodes already lie on their correspondences (the measure that
    // ends the schedule after a round, within check_fit_first_tolerance), so the graph is not completed.
    const auto tc = Clock::now();
    const std::size_t n = nodes.size();
    std::vector<Vec3> x(n), normal(n);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 64), [&](const auto& r) {
      std::vector<Halfedge> ring;
      for (std::size_t j = r.begin(); j != r.end(); ++j) {
        x[j] = mesh.position(nodes[j]);
        normal[j] = angle_weighted_normal(mesh, nodes[j], ring, [&](Index u) { return mesh.positions()[u]; });
      }
    });
    const std::vector<Correspondence> corr = find_correspondences(target, x, normal, cparams);
    const CorrespondenceCounts counts = count_correspondences(corr);
    double fit_distance = 0;
    for (std::size_t j = 0; j < n; ++j)
      if (corr[j].valid()) fit_distance += (x[j] - corr[j].point).norm();
    fit_distance /= double(std::max<std::size_t>(1, counts.ok));
    rep.seconds_correspondences += seconds_since(tc);
    if (counts.ok > 0 && fit_distance <= fitted_first * edge) {
      rep.fitted_at_start = true;
      rep.levels = 0;
      rep.nodes = int(n);
      rep.correspondences = counts.ok;
      rep.pruned_no_hit = counts.no_hit;
      rep.pruned_normal = counts.normal_angle;
      rep.pruned_distance = counts.too_far;
      rep.mean_fit_distance = fit_distance;
      rep.alpha_reg_end = params.alpha_reg_start;
      rep.seconds_graph = seconds_since(t0) - rep.seconds_correspondences;
      rep.seconds_total = seconds_since(t_total);
      return rep;
    }
  }
  const DeformationGraph graph = [&] {
    if (!guide || !guide->graph) return build_deformation_graph(mesh, std::move(nodes), spacing, params.k);
    DeformationGraph g = *guide->graph;
    for (std::size_t j = 0; j < g.n_nodes(); ++j) g.node_position[j] = mesh.position(g.node_vertex[j]);
    return g;
  }();
  const std::vector<Vec3> rest = mesh.positions();
  const Problem problem{graph, rest, mesh};
  const std::size_t nn = graph.n_nodes();
  rep.nodes = int(nn);
  rep.graph_edges = int(graph.edges.size());
  const bool direct = params.linear_solver == CoarseLinearSolver::Direct;
  SystemPattern pattern = direct ? build_pattern(graph, 12) : SystemPattern{};
  const bool coarse_correction = !direct && params.pcg_coarse_correction;
  SystemPattern precond = coarse_correction ? build_pattern(graph, 4) : SystemPattern{};
  SparseCholesky solver(params.solver);
  rep.seconds_graph = seconds_since(t0) - rep.seconds_correspondences;
  t0 = Clock::now();
  BlockCholesky block_solver;
  if (direct) solver.analyze(pattern.H);
  else if (coarse_correction) block_solver.analyze(graph.neighbor_offset, graph.neighbors);
  bool refactor = true;
  NodeSystem node_system;
  rep.seconds_factorisation += seconds_since(t0);

  std::vector<NodeState> state(nn), trial(nn);
  std::vector<Vec3> node_x(nn), node_n(nn);
  VertexFit vertex_fit = params.vertex_fit_weight > 0 ? build_vertex_fit(problem, params.vertex_fit_weight, params.vertex_fit_spacing * spacing) : VertexFit{};
  std::vector<Vec3> vertex_n(vertex_fit.vertex.size());
  rep.fitted_vertices = int(vertex_fit.vertex.size());
  std::vector<Correspondence> corr, back;
  const TargetSamples samples =
      backward ? sample_target(target, std::size_t(params.backward_samples_per_node) * nn) : TargetSamples{};
  // CoarseParams::backward_vertex_weight: every node's backward matches made at the fitted vertices instead.
  const bool backward_at_vertices = backward_all && !vertex_fit.empty() && params.backward_vertex_weight > 0;
  rep.backward_at_vertices = backward_at_vertices;
  Eigen::VectorXd grad;
  double alpha_reg = params.alpha_reg_start;
  if (rep.coarse_pass_iterations > 0 && params.alpha_reg_start_after_pass > 0) alpha_reg = params.alpha_reg_start_after_pass;
  if (pass_skipped && params.alpha_reg_start_without_pass > 0) alpha_reg = params.alpha_reg_start_without_pass;
  int level_iterations = 0;
  const int per_level =
      rep.coarse_pass_iterations > 0 ? params.max_iterations_per_level_after_pass : params.max_iterations_per_level;
  rep.levels = 1;
  bool first = true;
  for (int it = 0; it < params.max_iterations; ++it) {
    // Correspondences from each node along its (deformed) normal.
    t0 = Clock::now();
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nn, 32), [&](const auto& r) {
      std::vector<Halfedge> ring;
      for (std::size_t j = r.begin(); j != r.end(); ++j) {
        node_x[j] = graph.node_position[j] + state[j].b;
        node_n[j] = skinned_normal(problem, state, graph.node_vertex[j], ring);
      }
    });
    cparams.closest_point = large_motion && rep.levels <= params.closest_point_levels;
    corr = find_correspondences(target, node_x, node_n, cparams);
    if (params.match_override) params.match_override(CoarseMatchRound{CoarseStage::Level, rep.levels, graph.node_vertex}, corr);
    const bool node_backward = backward && !backward_at_vertices;
    if (node_backward) back = find_backward_correspondences(samples, node_x, node_n, params.max_normal_angle_deg);
    if (node_backward && !backward_all)
      for (std::size_t j = 0; j < nn; ++j)
        if (corr[j].valid()) back[j] = Correspondence{};
    if (guide)  // a guided node follows its given match alone
      for (std::size_t j = 0; j < nn; ++j)
        if (guide->match[j].valid()) {
          corr[j] = guide->match[j];
          corr[j].distance = (node_x[j] - corr[j].point).norm();
          if (node_backward) back[j] = Correspondence{};
        }
    const bool fit_vertices = !vertex_fit.empty();
    if (fit_vertices) {  // the vertices' matches along their normals (blended_normal), pruned like the nodes'
      vertex_fit.x.resize(vertex_fit.vertex.size());
      const std::vector<Mat3> transform = normal_transforms(state);
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, vertex_fit.vertex.size(), 256), [&](const auto& r) {
        for (std::size_t q = r.begin(); q != r.end(); ++q) {
          vertex_fit.x[q] = skin(problem, state, vertex_fit.vertex[q].idx);
          vertex_n[q] = blended_normal(problem, transform, vertex_fit.vertex[q].idx, vertex_fit.rest_normal[q]);
        }
      });
      vertex_fit.match = find_correspondences(target, vertex_fit.x, vertex_n, cparams);
      if (params.match_override)
        params.match_override(CoarseMatchRound{CoarseStage::Level, rep.levels, vertex_fit.vertex}, vertex_fit.match);
      if (params.vertex_fit_max_disagreement > 0) {
        // A vertex's match moves it about as its nodes' matches move them (skinning-weighted), or it is pruned: a ray
        // from a part still far from its place may hit another part, and the vertices outnumber the nodes.
        const auto K = std::size_t(graph.k);
        const double limit = params.vertex_fit_max_disagreement * spacing;
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, vertex_fit.vertex.size(), 1024), [&](const auto& r) {
          for (std::size_t q = r.begin(); q != r.end(); ++q) {
            Correspondence& c = vertex_fit.match[q];
            if (!c.valid()) continue;
            const Index v = vertex_fit.vertex[q].idx;
            Vec3 d = Vec3::Zero();
            double wsum = 0;
            for (std::size_t t = 0; t < K; ++t) {
              const Index j = graph.influence_node[v * K + t];
              if (j == kInvalidIndex || !corr[j].valid()) continue;
              const double wt = graph.influence_weight[v * K + t];
              d += wt * (corr[j].point - node_x[j]);
              wsum += wt;
            }
            if (!(wsum > 0) || ((c.point - vertex_fit.x[q]) - d / wsum).norm() > limit) c = Correspondence{};
          }
        });
      }
      if (backward_at_vertices) {  // the target's samples matched to the nearest fitted vertices instead of the nodes
        vertex_fit.back = find_backward_correspondences(samples, vertex_fit.x, vertex_n, params.max_normal_angle_deg);
        vertex_fit.back_scale = params.backward_vertex_weight;
      }
      if (guide) {  // a vertex a guided node skins is left to the node's match
        const auto K = std::size_t(graph.k);
        for (std::size_t q = 0; q < vertex_fit.vertex.size(); ++q)
          for (std::size_t t = 0; t < K; ++t)
            if (const Index j = graph.influence_node[vertex_fit.vertex[q].idx * K + t];
                j != kInvalidIndex && guide->match[j].valid()) {
              vertex_fit.match[q] = Correspondence{};
              if (!vertex_fit.back.empty()) vertex_fit.back[q] = Correspondence{};
            }
      }
    }
    rep.seconds_correspondences += seconds_since(t0);
    const CorrespondenceCounts counts = count_correspondences(corr);
    rep.correspondences = counts.ok;
    rep.pruned_no_hit = counts.no_hit;
    rep.pruned_normal = counts.normal_angle;
    rep.pruned_distance = counts.too_far;

    // One Gauss–Newton step on the total energy.
    t0 = Clock::now();
    const Weights w{params.alpha_fit * params.alpha_point * inv_d2,
                    params.alpha_fit * params.alpha_plane * inv_d2,
                    alpha_reg,
                    alpha_reg * params.smooth_weight * inv_d2,
                    params.damping,
                    params.damping * inv_d2,
                    params.backward_weight};
    const NodeMatches matches{corr, back};
    const double fit_scale = params.alpha_fit > 0 ? 1.0 / params.alpha_fit : 0.0;
    const VertexFit* vertices = fit_vertices ? &vertex_fit : nullptr;
    const Energy before = evaluate_energy(problem, state, matches, w, fit_scale, vertices);
    if (first) {
      rep.energy_start = before.total;
      rep.fit_start = before.fit;
      first = false;
    }
    assemble(problem, state, matches, vertices, w, direct ? &pattern : nullptr, coarse_correction ? &precond : nullptr,
             direct ? nullptr : &node_system, grad);
    rep.seconds_assembly += seconds_since(t0);
    if (direct || (coarse_correction && (refactor || params.refactor_each_round))) {
      t0 = Clock::now();
      if (direct) solver.factorize(pattern.H);
      else block_solver.factorize(precond.H);
      ++rep.factorisations;
      rep.factor_nonzeros = direct ? solver.factor_nonzeros() : block_solver.factor_nonzeros();
      refactor = false;
      rep.seconds_factorisation += seconds_since(t0);
    }
    t0 = Clock::now();
    Eigen::VectorXd delta;
    int pcg_iterations = 0;
    if (direct) delta = solver.solve(Eigen::VectorXd(-grad));
    else
      pcg_iterations = preconditioned_cg(graph, node_system, coarse_correction ? &block_solver : nullptr, -grad, params.pcg_tolerance,
                                         params.max_pcg_iterations, delta);
    rep.pcg_iterations += pcg_iterations;
    rep.seconds_solve += seconds_since(t0);

    // Accept the step, halving it while it raises the energy (the rigidity term is not quadratic).
    t0 = Clock::now();
    Energy after = before;
    bool accepted = false;
    double step = 0;
    // With `retract_rotations` the rotational part W A of each dA (W = skew(dA A^T)) is taken along the
    // rotation exp(t W) A instead of the line A + t W A, which leaves the rotations quadratically in t.
    std::vector<Vec3> spin(params.retract_rotations ? nn : 0);
    for (std::size_t j = 0; j < spin.size(); ++j) {
      const Mat3 M = Eigen::Map<const Mat3>(delta.data() + 12 * j) * state[j].A.transpose();
      spin[j] = 0.5 * Vec3(M(2, 1) - M(1, 2), M(0, 2) - M(2, 0), M(1, 0) - M(0, 1));
    }
    for (double t = 1.0; t >= 1.0 / 16; t *= 0.5) {
      for (std::size_t j = 0; j < nn; ++j) {
        const auto dj = delta.segment<12>(Eigen::Index(12 * j));
        const Mat3 dA = Eigen::Map<const Mat3>(dj.data());
        trial[j].A = state[j].A + t * dA;
        trial[j].b = state[j].b + t * dj.tail<3>();
        if (spin.empty()) continue;
        const double angle = spin[j].norm();
        if (!(angle > 0)) continue;
        Mat3 W;
        W << 0, -spin[j].z(), spin[j].y(), spin[j].z(), 0, -spin[j].x(), -spin[j].y(), spin[j].x(), 0;
        const Mat3 R = Eigen::AngleAxisd(t * angle, spin[j] / angle).toRotationMatrix();
        trial[j].A = R * state[j].A + t * (dA - W * state[j].A);
      }
      const Energy e = evaluate_energy(problem, trial, matches, w, fit_scale, vertices);
      if (e.total <= before.total) {
        after = e;
        state.swap(trial);
        accepted = true;
        step = t;
        break;
      }
    }
    // Convergence measures in lengths (deterministic: serial, node order): the largest node motion of
    // the step and the mean distance of the nodes to their correspondences after it.
    double motion = 0, fit_distance = 0;
    if (accepted)  // `trial` now holds the state before the step
      for (std::size_t j = 0; j < nn; ++j)
        motion = std::max(motion, (state[j].A - trial[j].A).norm() * spacing + (state[j].b - trial[j].b).norm());
    for (std::size_t j = 0; j < nn; ++j)
      if (corr[j].valid()) fit_distance += (graph.node_position[j] + state[j].b - corr[j].point).norm();
    fit_distance /= double(std::max<std::size_t>(1, counts.ok));
    rep.mean_fit_distance = fit_distance;
    rep.seconds_assembly += seconds_since(t0);
    rep.iterations = it + 1;
    rep.energy_history.push_back(after.total);
    rep.rounds.push_back({alpha_reg, before.total, after.total, motion / edge, fit_distance / edge, step, pcg_iterations, counts.ok});
    rep.energy_end = after.total;
    rep.fit_end = after.fit;
    rep.alpha_reg_end = alpha_reg;
    ++level_iterations;

    // Converged: the step no longer lowers the energy for the current correspondences, or nothing
    // moves. (Energies of successive rounds are not compared: they are over different correspondence
    // sets, and a round that gains correspondences raises the energy while making progress.)
    const bool converged = !accepted ||
                           before.total - after.total <= params.convergence_tolerance * before.total ||
                           motion <= params.step_tolerance * edge || motion < params.stall_ratio * fit_distance;
    if (converged || level_iterations >= per_level) {
      if (params.observer) {
        std::vector<Vec3> skinned = mesh.positions();
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, skinned.size(), 1024), [&](const auto& r) {
          for (std::size_t v = r.begin(); v != r.end(); ++v)
            if (!mesh.is_deleted(Vertex(Index(v)))) skinned[v] = skin(problem, state, Index(v));
        });
        params.observer(CoarseSnapshot{CoarseStage::Level, alpha_reg, level_iterations, fit_distance / edge, skinned});
      }
      if (converged && fit_distance <= params.fit_tolerance * edge) break;
      alpha_reg /= 10;
      level_iterations = 0;
      refactor = true;
      if (alpha_reg < params.alpha_reg_min * (1 - 1e-12)) break;
      ++rep.levels;
    }
  }

  // Carry the node transforms to every vertex by linear blend skinning.
  t0 = Clock::now();
  auto& pos = mesh.positions();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, pos.size(), 1024), [&](const auto& r) {
    for (std::size_t v = r.begin(); v != r.end(); ++v)
      if (!mesh.is_deleted(Vertex(Index(v)))) pos[v] = skin(problem, state, Index(v));
  });
  rep.seconds_assembly += seconds_since(t0);
  if (built) *built = std::make_shared<const DeformationGraph>(graph);
  rep.seconds_total = seconds_since(t_total);
  return rep;
}

}  // namespace
}  // namespace topotrack
