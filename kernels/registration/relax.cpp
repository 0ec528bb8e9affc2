#include "kernels/registration/relax.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <vector>

#include "io/error.hpp"
#include "kernels/mesh/edge_graph.hpp"
#include "kernels/mesh/mesh_queries.hpp"
#include "kernels/registration/deformation_graph.hpp"
#include "kernels/registration/parallel.hpp"

namespace topotrack {
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

using Mat3 = Eigen::Matrix3d;
using Rows3 = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;  // n x 3: a vertex's x, y, z together
inline Vec3 row(const Rows3& m, std::size_t i) { return m.row(Eigen::Index(i)).transpose(); }
inline void set_row(Rows3& m, std::size_t i, const Vec3& v) { m.row(Eigen::Index(i)) = v.transpose(); }

// The mesh's edges as a weighted adjacency by vertex handle index (CSR, one-ring order): cotangent weights of the
// rest shape, clamped to [0.05, 5] (an obtuse triangle's non-positive cotangent would make the energy indefinite)
// and divided by their mean, so that RelaxParams' weights are relative to an average edge's.
struct Adjacency {
  std::vector<Index> offset, neighbor;
  std::vector<double> weight;
  std::vector<double> degree;  // the sum of a vertex's weights (0: not live)
  bool live(std::size_t v) const { return offset[v + 1] > offset[v]; }
};

Adjacency cotangent_adjacency(const SurfaceMesh& mesh, std::span<const Vec3> rest) {
  std::vector<double> edge_weight(mesh.edges_size(), 0.0);
  double sum = 0;
  std::size_t count = 0;
  for (std::size_t e = 0; e < mesh.edges_size(); ++e) {
    if (mesh.is_deleted(Edge(Index(e)))) continue;
    double w = 0;
    for (int side = 0; side < 2; ++side) {
      const Halfedge h = mesh.halfedge(Edge(Index(e)), side);
      if (mesh.is_boundary(h)) continue;
      const Vec3& pi = rest[mesh.from_vertex(h).idx];
      const Vec3& pj = rest[mesh.to_vertex(h).idx];
      const Vec3& pk = rest[mesh.to_vertex(mesh.next(h)).idx];
      const Vec3 a = pi - pk, b = pj - pk;
      const double c = a.cross(b).norm();
      if (c > 0) w += 0.5 * a.dot(b) / c;
    }
    edge_weight[e] = std::clamp(w, 0.05, 5.0);
    sum += edge_weight[e];
    ++count;
  }
  const double scale = count > 0 && sum > 0 ? double(count) / sum : 1.0;
  const std::size_t n = mesh.vertices_size();
  Adjacency a;
  a.offset.assign(n + 1, 0);
  std::vector<Halfedge> ring;
  for (std::size_t v = 0; v < n; ++v) {
    const Vertex vh{Index(v)};
    a.offset[v + 1] = a.offset[v];
    if (mesh.is_deleted(vh) || mesh.is_isolated(vh)) continue;
    mesh.outgoing(vh, ring);
    for (const Halfedge h : ring) {
      a.neighbor.push_back(mesh.to_vertex(h).idx);
      a.weight.push_back(scale * edge_weight[SurfaceMesh::edge(h).idx]);
      ++a.offset[v + 1];
    }
  }
  a.degree.assign(n, 0.0);
  for (std::size_t v = 0; v < n; ++v)
    for (Index q = a.offset[v]; q < a.offset[v + 1]; ++q) a.degree[v] += a.weight[q];
  return a;
}

// The order the iterations number the vertices in: breadth-first over the mesh's edges (kernels/mesh/edge_graph.hpp).
// The global step's products read every neighbour's row, and a mesh's own numbering can put an edge's ends tens of
// thousands of rows apart; in this order they lie near each other, and so do the closest-point queries of one chunk
// of vertices (the stage 1.02 -> 0.77 s at 47k vertices, docs/results.md 2026-12-08).
struct Ordering {
  std::vector<Index> vertex;  // new number -> vertex handle index
  std::vector<Index> number;  // vertex handle index -> new number
};

Ordering breadth_first(const Adjacency& a) {
  Ordering o;
  o.vertex = breadth_first_order(a.offset, a.neighbor);
  o.number.assign(o.vertex.size(), kInvalidIndex);
  for (std::size_t k = 0; k < o.vertex.size(); ++k) o.number[o.vertex[k]] = Index(k);
  return o;
}

// `a` renumbered by `o` (rows in the new order, neighbours by new number, each row's order kept).
Adjacency renumbered(const Adjacency& a, const Ordering& o) {
  const std::size_t n = a.degree.size();
  Adjacency b;
  b.offset.assign(n + 1, 0);
  b.neighbor.reserve(a.neighbor.size());
  b.weight.reserve(a.weight.size());
  b.degree.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Index v = o.vertex[i];
    for (Index q = a.offset[v]; q < a.offset[v + 1]; ++q) {
      b.neighbor.push_back(o.number[a.neighbor[q]]);
      b.weight.push_back(a.weight[q]);
    }
    b.offset[i + 1] = Index(b.neighbor.size());
    b.degree[i] = a.degree[v];
  }
  return b;
}

constexpr double kCoarseSpacing = 4;  // the coarse level's node spacing in mean edge lengths (§4.2's)

// The coarse level of the global step's two-level preconditioner: the deformation graph of the rest shape (§4.2's
// sampling and skinning at the paper's node spacing) as the coarse space, its skinning weights the prolongation P
// (a smooth partition of unity), and the Galerkin matrix P^T (L + shift I) P of the weighted Laplacian, per
// coordinate, factored once. A direct Cholesky of L itself served as well per iteration but its fill grows faster
// than the mesh (98k vertices: 3.5 s for the stage against 2.5 s; docs/results.md, 2026-12-07).
class CoarseLevel {
public:
  //! `a` by new number (`o`); `mesh` and `rest` by vertex handle index.
  CoarseLevel(const SurfaceMesh& mesh, std::span<const Vec3> rest, const Adjacency& a, const Ordering& o, double shift) {
    SurfaceMesh at_rest = mesh.clone();
    std::copy(rest.begin(), rest.end(), at_rest.positions().begin());
    const DeformationGraph g = build_deformation_graph(at_rest, kCoarseSpacing * mean_edge_length(at_rest), 4);
    const std::size_t n = a.degree.size(), m = g.n_nodes(), K = std::size_t(g.k);
    // P by rows (a vertex's nodes) and by columns (a node's vertices), for the parallel prolongation and restriction.
    row_offset_.assign(n + 1, 0);
    col_offset_.assign(m + 1, 0);
    for (std::size_t v = 0; v < n; ++v) {
      row_offset_[v + 1] = row_offset_[v];
      if (!a.live(v)) continue;
      const std::size_t h = o.vertex[v];
      for (std::size_t t = 0; t < K; ++t)
        if (const Index j = g.influence_node[h * K + t]; j != kInvalidIndex) {
          row_node_.push_back(j);
          row_weight_.push_back(g.influence_weight[h * K + t]);
          ++row_offset_[v + 1];
          ++col_offset_[j + 1];
        }
    }
    for (std::size_t j = 0; j < m; ++j) col_offset_[j + 1] += col_offset_[j];
    col_vertex_.resize(row_node_.size());
    col_weight_.resize(row_node_.size());
    std::vector<Index> fill(col_offset_.begin(), col_offset_.end() - 1);
    for (std::size_t v = 0; v < n; ++v)  // vertices ascending within each node's column
      for (Index q = row_offset_[v]; q < row_offset_[v + 1]; ++q) {
        const Index at = fill[row_node_[q]]++;
        col_vertex_[at] = Index(v);
        col_weight_[at] = row_weight_[q];
      }
    std::vector<Eigen::Triplet<double>> t;
    for (std::size_t v = 0; v < n; ++v)
      for (Index q = row_offset_[v]; q < row_offset_[v + 1]; ++q) t.emplace_back(Eigen::Index(v), Eigen::Index(row_node_[q]), row_weight_[q]);
    Eigen::SparseMatrix<double> P{Eigen::Index(n), Eigen::Index(m)};
    P.setFromTriplets(t.begin(), t.end());
    t.clear();
    for (std::size_t v = 0; v < n; ++v) {
      t.emplace_back(Eigen::Index(v), Eigen::Index(v), a.degree[v] + shift);
      for (Index q = a.offset[v]; q < a.offset[v + 1]; ++q) t.emplace_back(Eigen::Index(v), Eigen::Index(a.neighbor[q]), -a.weight[q]);
    }
    Eigen::SparseMatrix<double> S{Eigen::Index(n), Eigen::Index(n)};
    S.setFromTriplets(t.begin(), t.end());
    const Eigen::SparseMatrix<double> SP = S * P;
    const Eigen::SparseMatrix<double> coarse = Eigen::SparseMatrix<double>(P.transpose()) * SP;
    llt_.compute(coarse);
    if (llt_.info() != Eigen::Success) TT_THROW(SolverError, "relax_on_target: the coarse level's factorisation failed");
    nodes_ = m;
  }
  std::size_t nodes() const { return nodes_; }
  //! b <- P (P^T S P)^-1 P^T b, the three coordinates at once.
  void correct(Rows3& b) const {
    Eigen::MatrixXd c(Eigen::Index(nodes_), 3);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nodes_, 256), [&](const auto& r) {
      for (std::size_t j = r.begin(); j != r.end(); ++j) {
        Vec3 s = Vec3::Zero();
        for (Index q = col_offset_[j]; q < col_offset_[j + 1]; ++q) s += col_weight_[q] * row(b, col_vertex_[q]);
        c.row(Eigen::Index(j)) = s.transpose();
      }
    });
    const Eigen::MatrixXd y = llt_.solve(c);
    parallel_each(std::size_t(b.rows()), [&](std::size_t v) {
      Vec3 s = Vec3::Zero();
      for (Index q = row_offset_[v]; q < row_offset_[v + 1]; ++q) s += row_weight_[q] * y.row(Eigen::Index(row_node_[q])).transpose();
      set_row(b, v, s);
    });
  }

private:
  std::size_t nodes_ = 0;
  std::vector<Index> row_offset_, row_node_, col_offset_, col_vertex_;
  std::vector<double> row_weight_, col_weight_;
  Eigen::SimplicialLLT<Eigen::SparseMatrix<double>, Eigen::Lower, Eigen::AMDOrdering<int>> llt_;
};

// The proper rotation R maximising tr(R^T A) (Kabsch): with A = U S V^T, R = U diag(1, 1, det(U V^T)) V^T. A vertex's
// A is a sum over its one-ring, nearly planar, so one singular value is near zero; the two largest singular pairs come
// from the closed-form eigen decomposition of A^T A (u_k = A v_k / s_k) and the third from their cross products, which
// also makes R proper. Written by hand: Eigen's JacobiSVD for every vertex in every iteration cost about as much as
// the rest of the local step; it remains the fallback where the second singular value vanishes.
Mat3 fit_rotation(const Mat3& A) {
  Eigen::SelfAdjointEigenSolver<Mat3> eigen;
  eigen.computeDirect(A.transpose() * A);
  const Vec3 v1 = eigen.eigenvectors().col(2), v2 = eigen.eigenvectors().col(1);
  const double s1 = std::sqrt(std::max(0.0, eigen.eigenvalues()(2))), s2 = std::sqrt(std::max(0.0, eigen.eigenvalues()(1)));
  if (s2 > 1e-6 * s1 && s1 > 0) {
    const Vec3 u1 = (A * v1 / s1).normalized();
    Vec3 u2 = A * v2 / s2;
    u2 = (u2 - u1 * u1.dot(u2)).normalized();
    Mat3 U, V;
    U << u1, u2, u1.cross(u2);
    V << v1, v2, v1.cross(v2);
    const Mat3 R = U * V.transpose();
    if (R.allFinite()) return R;
  }
  const Eigen::JacobiSVD<Mat3> svd(A, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Mat3 U = svd.matrixU();
  if ((U * svd.matrixV().transpose()).determinant() < 0) U.col(2) = -U.col(2);
  return U * svd.matrixV().transpose();
}

}  // namespace

RelaxReport relax_on_target(SurfaceMesh& mesh, std::span<const Vec3> rest, const TargetSurface& target,
                            const RelaxParams& params) {
  const auto t_total = Clock::now();
  if (params.iterations < 0 || !(params.plane_weight > 0) || !(params.point_weight > 0) || params.cg_iterations < 1 ||
      !std::isfinite(params.plane_weight) || !std::isfinite(params.point_weight) || !(params.max_distance > 0))
    TT_THROW(InvalidInput, "relax_on_target: invalid parameters");
  const std::size_t n = mesh.vertices_size();
  if (rest.size() != n)
    TT_THROW(InvalidInput, "relax_on_target: " << rest.size() << " rest positions for " << n << " vertices");
  RelaxReport rep;
  if (params.iterations == 0 || mesh.n_vertices() == 0) return rep;
  for (const Vec3& p : rest)
    if (!p.allFinite()) TT_THROW(InvalidInput, "relax_on_target: a rest position is not finite");

  auto t0 = Clock::now();
  const double lambda = params.plane_weight, beta = params.point_weight;
  const Adjacency by_handle = cotangent_adjacency(mesh, rest);
  const Ordering order = breadth_first(by_handle);
  const Adjacency adj = renumbered(by_handle, order);
  const CoarseLevel coarse(mesh, rest, adj, order, lambda * beta);
  // Everything below by new number: x and p_rest, the positions and the rest shape, copied in (x back at the end).
  std::vector<Vec3> x(n), p_rest(n);
  for (std::size_t i = 0; i < n; ++i) {
    x[i] = mesh.positions()[order.vertex[i]];
    p_rest[i] = rest[order.vertex[i]];
  }
  rep.seconds_setup = seconds_since(t0);

  std::vector<Mat3> R(n, Mat3::Identity()), M(n, Mat3::Identity()), M_inverse(n, Mat3::Identity());
  std::vector<TargetSurface::Hit> hit(n);
  std::vector<Vec3> moved(n, Vec3::Zero());  // how far each vertex went since its closest point was found
  const double diagonal = target.bbox_diagonal(), max_distance = params.max_distance * diagonal;
  // A vertex is fitted (has the point-to-plane term) while its closest point lies within max_distance, as the fine
  // stage prunes its rays; a component none of whose vertices is fitted at the start stays where it is, as the fine
  // stage leaves it (there is nothing to slide it along), and so do vertices in no triangle.
  std::vector<char> moving(n, 0), fitted(n, 0);
  // The global step's system (L (x) I + lambda (n n^T + beta I)) x = b, by vertex: M_i, the 3 x 3 diagonal block, and
  // the edges' -w_ij I. Vectors are n x 3 (vertex i's x, y, z in row i); a vertex that is not live keeps its row.
  Rows3 rhs(n, 3), sol(n, 3), r(n, 3), z(n, 3), p(n, 3), Ap(n, 3), t(n, 3), u(n, 3);
  const auto apply = [&](const Rows3& v, Rows3& out) {
    parallel_each(n, [&](std::size_t i) {
      if (!moving[i]) return set_row(out, i, row(v, i));
      Vec3 o = M[i] * row(v, i);
      for (Index q = adj.offset[i]; q < adj.offset[i + 1]; ++q) o -= adj.weight[q] * row(v, adj.neighbor[q]);
      set_row(out, i, o);
    });
  };
  // Symmetric two-level preconditioner: block Jacobi (the 3 x 3 blocks, which hold the stiff point-to-plane term),
  // the coarse level's correction of the residual's part along the surface (the point-to-plane term leaves that
  // direction to the Laplacian alone), block Jacobi again.
  const auto along_surface = [&](std::size_t i, const Vec3& v) {
    if (!fitted[i]) return v;
    const Vec3& nn = hit[i].normal;
    return Vec3(v - nn * nn.dot(v));
  };
  const auto precondition = [&](const Rows3& res, Rows3& out) {
    parallel_each(n, [&](std::size_t i) { set_row(out, i, moving[i] ? Vec3(M_inverse[i] * row(res, i)) : row(res, i)); });
    apply(out, t);
    parallel_each(n, [&](std::size_t i) {
      const Vec3 ri = row(res, i) - row(t, i);
      set_row(u, i, moving[i] ? along_surface(i, ri) : ri);
    });
    coarse.correct(u);
    parallel_each(n, [&](std::size_t i) {
      if (moving[i]) set_row(out, i, row(out, i) + along_surface(i, row(u, i)));
    });
    apply(out, t);
    parallel_each(n, [&](std::size_t i) {
      if (moving[i]) set_row(out, i, row(out, i) + M_inverse[i] * (row(res, i) - row(t, i)));
    });
  };
  const auto dot = [&](const Rows3& a, const Rows3& b) {
    return deterministic_sum(n, [&](std::size_t i) { return Vec3(row(a, i).dot(row(b, i)), 0, 0); })[0];
  };
  // The energy at x for the current rotations and correspondences.
  const auto energy = [&] {
    return deterministic_sum(n, [&](std::size_t i) {
      if (!moving[i]) return Vec3::Zero().eval();
      double e = 0;
      for (Index q = adj.offset[i]; q < adj.offset[i + 1]; ++q) {
        const Index j = adj.neighbor[q];
        e += 0.5 * adj.weight[q] * ((x[i] - x[j]) - 0.5 * (R[i] + R[j]) * (p_rest[i] - p_rest[j])).squaredNorm();
      }
      if (!fitted[i]) return Vec3(e, 0, 0);
      const Vec3 d = x[i] - hit[i].point;
      const double dn = hit[i].normal.dot(d);
      return Vec3(e + lambda * (dn * dn + beta * d.squaredNorm()), 0, 0);
    })[0];
  };

  for (int it = 0; it < params.iterations; ++it) {
    // Closest points: after the first iteration within the previous closest point's distance plus the motion
    // since (the same point as an unbounded query, found in a smaller search).
    t0 = Clock::now();
    parallel_each(n, [&](std::size_t i) {
      if (!(it == 0 ? adj.live(i) : moving[i])) return;
      TargetSurface::Hit h;
      if (it > 0) h = target.closest_point(x[i], (hit[i].distance + moved[i].norm()) * (1 + 1e-9) + 1e-12 * diagonal);
      hit[i] = h.hit ? h : target.closest_point(x[i]);
      fitted[i] = hit[i].distance <= max_distance;
      moved[i].setZero();
    });
    if (it == 0) {
      std::vector<Index> component;
      const Index components = connected_components(mesh, &component);
      std::vector<char> reached(components, 0);
      for (std::size_t i = 0; i < n; ++i)
        if (fitted[i]) reached[component[order.vertex[i]]] = 1;
      for (std::size_t i = 0; i < n; ++i) moving[i] = adj.live(i) && reached[component[order.vertex[i]]];
    }
    const Vec3 fit_sum = deterministic_sum(n, [&](std::size_t i) { return Vec3(fitted[i] ? hit[i].distance : 0.0, fitted[i] ? 1.0 : 0.0, 0); });
    rep.fitted = std::size_t(fit_sum[1]);
    rep.mean_distance = fit_sum[1] > 0 ? fit_sum[0] / (fit_sum[1] * diagonal) : 0.0;
    rep.seconds_closest += seconds_since(t0);
    // Local step: each vertex's rotation of its rest edges onto its current ones.
    t0 = Clock::now();
    parallel_each(n, [&](std::size_t i) {
      if (!moving[i]) return;
      Mat3 A = Mat3::Zero();
      for (Index q = adj.offset[i]; q < adj.offset[i + 1]; ++q) {
        const Index j = adj.neighbor[q];
        A += adj.weight[q] * (x[i] - x[j]) * (p_rest[i] - p_rest[j]).transpose();
      }
      R[i] = fit_rotation(A);
    });
    rep.seconds_rotations += seconds_since(t0);
    // Global step: sum_j w_ij (R_i + R_j) / 2 (p_i - p_j) + lambda (n n^T + beta I) c on the right, a few
    // preconditioned conjugate-gradient iterations from x.
    t0 = Clock::now();
    parallel_each(n, [&](std::size_t i) {
      set_row(sol, i, x[i]);
      if (!moving[i]) return set_row(rhs, i, x[i]);
      const Vec3& nn = hit[i].normal;
      const Mat3 fit = fitted[i] ? Mat3(lambda * (nn * nn.transpose() + beta * Mat3::Identity())) : Mat3::Zero();
      M[i] = fit + adj.degree[i] * Mat3::Identity();
      M_inverse[i] = M[i].inverse();
      Vec3 b = fit * hit[i].point;
      for (Index q = adj.offset[i]; q < adj.offset[i + 1]; ++q) {
        const Index j = adj.neighbor[q];
        b += 0.5 * adj.weight[q] * (R[i] + R[j]) * (p_rest[i] - p_rest[j]);
      }
      set_row(rhs, i, b);
    });
    if (it == 0) rep.energy_start = energy();
    apply(sol, Ap);
    parallel_each(n, [&](std::size_t i) { set_row(r, i, row(rhs, i) - row(Ap, i)); });
    precondition(r, z);
    p = z;
    double rz = dot(r, z);
    for (int k = 0; k < params.cg_iterations && rz > 0; ++k) {
      apply(p, Ap);
      const double pAp = dot(p, Ap);
      if (!(pAp > 0)) break;
      const double alpha = rz / pAp;
      parallel_each(n, [&](std::size_t i) {
        set_row(sol, i, row(sol, i) + alpha * row(p, i));
        set_row(r, i, row(r, i) - alpha * row(Ap, i));
      });
      precondition(r, z);
      const double rz_new = dot(r, z), beta_cg = rz_new / rz;
      parallel_each(n, [&](std::size_t i) { set_row(p, i, row(z, i) + beta_cg * row(p, i)); });
      rz = rz_new;
      ++rep.cg_iterations;
    }
    parallel_each(n, [&](std::size_t i) {
      const Vec3 next = row(sol, i);
      if (!moving[i] || !next.allFinite()) return;
      moved[i] += next - x[i];
      x[i] = next;
    });
    rep.seconds_solve += seconds_since(t0);
    rep.iterations = it + 1;
  }
  rep.energy_end = energy();  // reported only: once, at the last step's rotations and correspondences
  for (std::size_t i = 0; i < n; ++i) mesh.positions()[order.vertex[i]] = x[i];
  rep.coarse_nodes = int(coarse.nodes());
  rep.seconds_total = seconds_since(t_total);
  return rep;
}

}  // namespace topotrack
