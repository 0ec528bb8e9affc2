#include "kernels/registration/fine.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>

#include "kernels/mesh/mesh_queries.hpp"
#include "kernels/registration/correspondences.hpp"
#include "kernels/registration/parallel.hpp"

namespace topotrack {
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// Vertex adjacency by handle index (CSR, neighbours in one-ring order), built in parallel.
struct Adjacency {
  std::vector<Index> offset, neighbor;
};

Adjacency build_adjacency(const SurfaceMesh& mesh) {
  const std::size_t nv = mesh.vertices_size();
  Adjacency a;
  std::vector<Index> valence(nv, 0);
  parallel_each(nv, [&](std::size_t v) {
    const Vertex vh{Index(v)};
    if (!mesh.is_deleted(vh) && !mesh.is_isolated(vh)) valence[v] = Index(mesh.valence(vh));
  });
  a.offset.assign(nv + 1, 0);
  for (std::size_t v = 0; v < nv; ++v) a.offset[v + 1] = a.offset[v] + valence[v];
  a.neighbor.resize(a.offset[nv]);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv, 2048), [&](const auto& r) {
    std::vector<Vertex> ring;
    for (std::size_t v = r.begin(); v != r.end(); ++v) {
      if (valence[v] == 0) continue;
      mesh.one_ring(Vertex(Index(v)), ring);
      for (std::size_t i = 0; i < ring.size(); ++i) a.neighbor[a.offset[v] + i] = ring[i].idx;
    }
  });
  return a;
}

template <int K>
using VecK = Eigen::Matrix<double, K, 1>;

// The normal equations of E_tot: (W + smooth L) d = W (c - x), W the fit weights, L the graph Laplacian
// of the mesh edges; K = 3 for vector displacements, K = 1 for scalar displacements along the normals.
template <int K>
struct System {
  const Adjacency& adj;
  std::vector<double> fit;  // w_i: fit weight where a correspondence exists, else 0
  double smooth = 1;

  VecK<K> apply(const std::vector<VecK<K>>& d, std::size_t i) const {
    VecK<K> out = fit[i] * d[i];
    for (Index q = adj.offset[i]; q < adj.offset[i + 1]; ++q) out += smooth * (d[i] - d[adj.neighbor[q]]);
    return out;
  }
  double diagonal(std::size_t i) const {
    const double dg = fit[i] + smooth * double(adj.offset[i + 1] - adj.offset[i]);
    return dg > 0 ? dg : 1.0;
  }
};

template <int K, class F>
VecK<K> deterministic_sum_k(std::size_t n, F&& term) {
  if constexpr (K == 3) {
    return deterministic_sum(n, term);
  } else {
    const Vec3 s = deterministic_sum(n, [&](std::size_t i) { return Vec3(term(i)[0], 0, 0); });
    return VecK<K>(s[0]);
  }
}

struct CgResult {
  int iterations = 0;
  double residual = 0;
};

// Jacobi-preconditioned CG on the K coordinates at once (same matrix, independent scalars); d holds the
// warm start on entry and the solution on exit.
template <int K>
CgResult solve_cg(const System<K>& sys, const std::vector<VecK<K>>& rhs, std::vector<VecK<K>>& d, int max_iterations,
                  double tolerance) {
  const std::size_t nv = rhs.size();
  std::vector<VecK<K>> r(nv), z(nv), p(nv), Ap(nv);
  parallel_each(nv, [&](std::size_t i) {
    r[i] = rhs[i] - sys.apply(d, i);
    z[i] = r[i] / sys.diagonal(i);
    p[i] = z[i];
  });
  const VecK<K> rhs_norm2 = deterministic_sum_k<K>(nv, [&](std::size_t i) { return VecK<K>(rhs[i].cwiseAbs2()); });
  VecK<K> rz = deterministic_sum_k<K>(nv, [&](std::size_t i) { return VecK<K>(r[i].cwiseProduct(z[i])); });
  VecK<K> r_norm2 = deterministic_sum_k<K>(nv, [&](std::size_t i) { return VecK<K>(r[i].cwiseAbs2()); });
  auto relative = [&](const VecK<K>& rn2) {
    double worst = 0;
    for (int c = 0; c < K; ++c) worst = std::max(worst, rhs_norm2[c] > 0 ? std::sqrt(rn2[c] / rhs_norm2[c]) : 0.0);
    return worst;
  };
  CgResult res;
  while (res.iterations < max_iterations && relative(r_norm2) > tolerance) {
    parallel_each(nv, [&](std::size_t i) { Ap[i] = sys.apply(p, i); });
    const VecK<K> pAp = deterministic_sum_k<K>(nv, [&](std::size_t i) { return VecK<K>(p[i].cwiseProduct(Ap[i])); });
    VecK<K> alpha;
    for (int c = 0; c < K; ++c) alpha[c] = pAp[c] > 0 ? rz[c] / pAp[c] : 0.0;
    parallel_each(nv, [&](std::size_t i) {
      d[i] += alpha.cwiseProduct(p[i]);
      r[i] -= alpha.cwiseProduct(Ap[i]);
      z[i] = r[i] / sys.diagonal(i);
    });
    const VecK<K> rz_new = deterministic_sum_k<K>(nv, [&](std::size_t i) { return VecK<K>(r[i].cwiseProduct(z[i])); });
    r_norm2 = deterministic_sum_k<K>(nv, [&](std::size_t i) { return VecK<K>(r[i].cwiseAbs2()); });
    VecK<K> beta;
    for (int c = 0; c < K; ++c) beta[c] = rz[c] > 0 ? rz_new[c] / rz[c] : 0.0;
    rz = rz_new;
    parallel_each(nv, [&](std::size_t i) { p[i] = z[i] + beta.cwiseProduct(p[i]); });
    ++res.iterations;
  }
  res.residual = relative(r_norm2);
  return res;
}

// One round for displacements with K coordinates: K = 3, d_i in R^3; K = 1, d_i = t_i n_i.
template <int K>
void solve_round(SurfaceMesh& mesh, const Adjacency& adj, const std::vector<Vec3>& normals,
                 const std::vector<Correspondence>& corr, const FineParams& params, double tolerance, FineReport& rep) {
  const std::size_t nv = mesh.vertices_size();
  auto& pos = mesh.positions();
  auto t0 = Clock::now();
  System<K> sys{adj, std::vector<double>(nv, 0.0), params.smooth_weight};
  std::vector<VecK<K>> rhs(nv), d(nv);
  auto target_of = [&](std::size_t i) -> VecK<K> {  // the displacement that reaches c_i
    const Vec3 g = corr[i].point - pos[i];
    if constexpr (K == 3) return g;
    else return VecK<K>(normals[i].dot(g));
  };
  auto lift = [&](const VecK<K>& v, std::size_t i) -> Vec3 {  // displacement in R^3
    if constexpr (K == 3) return v;
    else return v[0] * normals[i];
  };
  parallel_each(nv, [&](std::size_t i) {
    const bool ok = corr[i].valid() && !mesh.is_deleted(Vertex(Index(i)));
    sys.fit[i] = ok ? params.fit_weight : 0.0;
    d[i] = ok ? target_of(i) : VecK<K>::Zero();  // warm start
    rhs[i] = sys.fit[i] * d[i];
  });
  auto energy = [&](const std::vector<VecK<K>>& disp) {
    return deterministic_sum(nv, [&](std::size_t i) {
      double e = sys.fit[i] > 0 ? sys.fit[i] * (pos[i] + lift(disp[i], i) - corr[i].point).squaredNorm() : 0.0;
      for (Index q = adj.offset[i]; q < adj.offset[i + 1]; ++q)
        e += 0.5 * sys.smooth * (disp[i] - disp[adj.neighbor[q]]).squaredNorm();
      return Vec3(e, 0, 0);
    })[0];
  };
  rep.energy_start = energy(std::vector<VecK<K>>(nv, VecK<K>::Zero()));
  rep.seconds_assembly += seconds_since(t0);

  t0 = Clock::now();
  const CgResult cg = solve_cg<K>(sys, rhs, d, params.max_cg_iterations, tolerance);
  rep.cg_iterations += cg.iterations;
  rep.residual = cg.residual;
  rep.energy_end = energy(d);
  std::size_t matched = 0;
  for (std::size_t i = 0; i < nv; ++i) matched += sys.fit[i] > 0;
  rep.mean_residual = deterministic_sum(nv, [&](std::size_t i) {
    return Vec3(sys.fit[i] > 0 ? (pos[i] + lift(d[i], i) - corr[i].point).norm() : 0.0, 0, 0);
  })[0] / double(std::max<std::size_t>(1, matched));
  parallel_each(nv, [&](std::size_t i) {
    const Vec3 step = lift(d[i], i);
    if (!mesh.is_deleted(Vertex(Index(i))) && step.allFinite()) pos[i] += step;
  });
  rep.seconds_solve += seconds_since(t0);
}

}  // namespace

FineReport align_fine(SurfaceMesh& mesh, const TargetSurface& target, const FineParams& params, std::span<const Vec3> rest) {
  const auto t_total = Clock::now();
  if (!(params.sigma > 0) || !(params.fit_weight > 0) || !(params.smooth_weight >= 0) ||
      params.max_cg_iterations < 0 || !(params.tolerance >= 0) || params.rounds < 1 || params.max_rounds < 1 ||
      !(params.more_rounds_residual >= 0) || !(params.more_rounds_tolerance >= 0))
    TT_THROW(InvalidInput, "align_fine: invalid parameters");
  FineReport rep;
  const std::size_t nv = mesh.vertices_size();
  if (mesh.n_vertices() == 0) return rep;
  BoundingBox scene = bounding_box(mesh);
  scene.extend(target.bounds().min);
  scene.extend(target.bounds().max);
  const double D = scene.diagonal();
  if (!std::isfinite(D)) TT_THROW(InvalidInput, "align_fine: non-finite coordinates");

  auto t0 = Clock::now();
  const Adjacency adj = build_adjacency(mesh);
  rep.seconds_assembly += seconds_since(t0);

  CorrespondenceParams cparams;
  cparams.max_normal_angle_deg = params.max_normal_angle_deg;
  cparams.max_closest_ratio = std::numeric_limits<double>::infinity();
  cparams.max_distance = params.sigma * D;  // "sigma = 0.1 given a scene bounding box diagonal of 1"

  const auto& pos = mesh.positions();
  const int max_rounds = std::max(params.rounds, params.max_rounds);
  std::vector<Correspondence> corr;
  for (int round = 0; round < max_rounds; ++round) {
    const bool further = round >= params.rounds;
    if (further && !(rep.mean_residual > params.more_rounds_residual)) break;
    t0 = Clock::now();
    const std::vector<Vec3> normals = vertex_normals(mesh);
    if (!further) {
      corr = find_correspondences(target, pos, normals, cparams);
    } else {
      // A further round casts again only from the vertices the last step left farther than the threshold from
      // their hits, or without one; the others lie on their hits, which their new rays would find again.
      const double far = params.more_rounds_residual * D;
      std::vector<Index> again;
      for (std::size_t i = 0; i < nv; ++i)
        if (!mesh.is_deleted(Vertex(Index(i))) && (!corr[i].valid() || (pos[i] - corr[i].point).norm() > far))
          again.push_back(Index(i));
      std::vector<Vec3> x(again.size()), n(again.size());
      for (std::size_t k = 0; k < again.size(); ++k) {
        x[k] = pos[again[k]];
        n[k] = normals[again[k]];
      }
      const std::vector<Correspondence> hits = find_correspondences(target, x, n, cparams);
      for (std::size_t k = 0; k < again.size(); ++k) corr[again[k]] = hits[k];
    }
    rep.seconds_raycast += seconds_since(t0);
    std::size_t matched = 0;
    for (std::size_t i = 0; i < nv; ++i)
      if (corr[i].valid() && !mesh.is_deleted(Vertex(Index(i)))) ++matched;
    rep.correspondences = matched;
    rep.pruned = mesh.n_vertices() - matched;
    const double tolerance = further ? params.more_rounds_tolerance : params.tolerance;
    if (params.normal_displacement) solve_round<1>(mesh, adj, normals, corr, params, tolerance, rep);
    else solve_round<3>(mesh, adj, normals, corr, params, tolerance, rep);
    rep.mean_residual /= D;
    rep.rounds = round + 1;
  }
  if (!rest.empty()) {  // the relaxation fits the vertices the fine stage's sigma would match
    RelaxParams relax = params.relax;
    relax.max_distance = params.sigma;
    rep.relax = relax_on_target(mesh, rest, target, relax);
  }
  rep.seconds_total = seconds_since(t_total);
  return rep;
}

}  // namespace topotrack
