#pragma once
//! Ground-truth alignment pairs from /work/shared/data: the data sequences keep their connectivity,
//! so vertex i of frame k corresponds to vertex i of frame k + gap. The target is frame k + gap
//! re-sampled (different connectivity) so that the aligner never sees the correspondence.
//! Header-only; shared by the registration tests and benchmark.
#include <Eigen/SVD>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include "io/mesh_reader.hpp"
#include "io/ply_writer.hpp"
#include "kernels/eval/drift.hpp"
#include "kernels/improve/improve.hpp"
#include "kernels/mesh/edge_graph.hpp"
#include "kernels/mesh/mesh_convert.hpp"
#include "kernels/mesh/mesh_queries.hpp"
#include "kernels/raycast/target_surface.hpp"
#include "kernels/spatial/point_index.hpp"

namespace topotrack::test {

inline std::filesystem::path data_frame(const std::string& name, int frame) {
  char file[64];
  std::snprintf(file, sizeof file, "%s.%04d.ply", name.c_str(), frame);
  return std::filesystem::path(TOPOTRACK_SHARED_DIR) / "data" / name / file;
}

inline SurfaceMesh load_frame(const std::string& name, int frame) {
  return to_surface_mesh(read_mesh(data_frame(name, frame)));
}

//! `mesh` re-meshed by improve_mesh at `edge_factor` times its mean edge length: new connectivity.
inline SurfaceMesh resample(const SurfaceMesh& mesh, double edge_factor) {
  SurfaceMesh out = mesh.clone();
  ImproveParams p;
  p.target_edge_length = edge_factor * mean_edge_length(mesh);
  improve_mesh(out, p);
  return out;
}

//! One alignment pair: source frame, ground-truth positions in the target frame, re-sampled target.
struct AlignmentPair {
  SurfaceMesh source;
  std::vector<Vec3> truth;  //!< where each source vertex should land (by handle)
  SurfaceMesh target_mesh;
  double diagonal = 0;      //!< bbox diagonal of the ground-truth frame
};

inline AlignmentPair make_pair(const std::string& name, int frame, int gap, double edge_factor = 0.8) {
  AlignmentPair p;
  p.source = load_frame(name, frame);
  SurfaceMesh gt = load_frame(name, frame + gap);
  p.truth = gt.positions();
  p.diagonal = bounding_box(gt).diagonal();
  p.target_mesh = resample(gt, edge_factor);
  return p;
}

//! The pair with its source re-meshed at `edge_factor` of its mean edge length (the benchmark's larger sizes), each
//! new vertex's ground truth carried from the old source's: its closest point on the old source, at the same
//! barycentric coordinates of the same triangle in the ground-truth frame (expected_by_correspondence).
inline void refine_source(AlignmentPair& pair, double edge_factor) {
  const TargetSurface old = TargetSurface::from_mesh(pair.source);  // no deleted vertices: its indices are the handles
  SurfaceMesh fine = resample(pair.source, edge_factor);
  pair.truth = expected_by_correspondence(fine.positions(), old, pair.truth);
  pair.source = std::move(fine);
}

struct AlignmentError {
  double mean_truth = 0;   //!< mean |x_i - truth_i| / diagonal
  double mean_target = 0;  //!< mean distance of x_i to the target surface / diagonal
};

inline AlignmentError alignment_error(const SurfaceMesh& mesh, const std::vector<Vec3>& truth,
                                      const TargetSurface& target, double diagonal) {
  AlignmentError e;
  std::size_t n = 0;
  for (std::size_t i = 0; i < truth.size() && i < mesh.vertices_size(); ++i) {
    if (mesh.is_deleted(Vertex(Index(i)))) continue;
    e.mean_truth += (mesh.positions()[i] - truth[i]).norm();
    e.mean_target += target.closest_point(mesh.positions()[i]).distance;
    ++n;
  }
  if (n) {
    e.mean_truth /= double(n) * diagonal;
    e.mean_target /= double(n) * diagonal;
  }
  return e;
}


//! Where the error of an alignment is (diagnostics of the registration issue), over live vertices:
//! the ground-truth error's distribution, and three failure modes told apart: "off" vertices are not
//! on the target (distance > 1% of the diagonal); "slid" ones are on it (< 0.5%) yet more than 2% from
//! their ground truth; of those, "wrong part" ones land nearest to the ground truth of a vertex that
//! was more than 10% of the diagonal away from them in the source (another limb, not a slide along
//! their own). Fractions of the live vertices; lengths in % of the diagonal.
struct ErrorBreakdown {
  double mean = 0, median = 0, p90 = 0, mean_target = 0;
  double off = 0, slid = 0, wrong_part = 0;
};

//! Per-vertex ground-truth error (fraction of the diagonal) of positions `x` (by handle index).
inline std::vector<double> truth_errors(std::span<const Vec3> x, const std::vector<Vec3>& truth, double diagonal) {
  std::vector<double> e(std::min(x.size(), truth.size()));
  for (std::size_t i = 0; i < e.size(); ++i) e[i] = (x[i] - truth[i]).norm() / diagonal;
  return e;
}

inline ErrorBreakdown error_breakdown(std::span<const Vec3> x, const AlignmentPair& pair, const TargetSurface& target,
                                      const PointIndex& truth_index) {
  ErrorBreakdown b;
  const std::vector<double> err = truth_errors(x, pair.truth, pair.diagonal);
  std::vector<double> sorted;
  std::size_t n = 0, off = 0, slid = 0, wrong = 0;
  for (std::size_t i = 0; i < err.size(); ++i) {
    if (pair.source.is_deleted(Vertex(Index(i)))) continue;
    ++n;
    sorted.push_back(err[i]);
    b.mean += err[i];
    const double dt = target.closest_point(x[i]).distance / pair.diagonal;
    b.mean_target += dt;
    if (dt > 0.01) ++off;
    else if (dt < 0.005 && err[i] > 0.02) {
      ++slid;
      const Index j = truth_index.nearest(x[i]).index;
      if ((pair.source.positions()[j] - pair.source.positions()[i]).norm() > 0.1 * pair.diagonal) ++wrong;
    }
  }
  if (!n) return b;
  std::sort(sorted.begin(), sorted.end());
  b.mean *= 100.0 / double(n);
  b.mean_target *= 100.0 / double(n);
  b.median = 100 * sorted[n / 2];
  b.p90 = 100 * sorted[std::min(n - 1, n * 9 / 10)];
  b.off = double(off) / double(n);
  b.slid = double(slid) / double(n);
  b.wrong_part = double(wrong) / double(n);
  return b;
}

inline void print_breakdown(const char* stage, const ErrorBreakdown& b) {
  std::printf("    %-22s truth %% mean %7.3f median %7.3f p90 %7.3f | to target %6.3f %% | off %4.1f%% slid %4.1f%% "
              "(wrong part %4.1f%%)\n",
              stage, b.mean, b.median, b.p90, b.mean_target, 100 * b.off, 100 * b.slid, 100 * b.wrong_part);
}

//! Mean relative change of the source's edge lengths |l' - l| / l at positions `x` (by handle index): how far from
//! isometric a deformation is (the elephant's ground truth, frame 1 -> 16: 5 %).
inline double mean_edge_strain(const SurfaceMesh& source, std::span<const Vec3> x) {
  const MeshData d = to_mesh_data(source, false);
  double sum = 0;
  std::size_t n = 0;
  for (const auto& t : d.triangles)
    for (int a = 0; a < 3; ++a) {
      const auto i = std::size_t(t[a]), j = std::size_t(t[(a + 1) % 3]);
      if (i > j) continue;  // each interior edge once (a boundary edge seen from one side only may be skipped)
      const double l0 = (source.positions()[i] - source.positions()[j]).norm();
      if (!(l0 > 0)) continue;
      sum += std::abs((x[i] - x[j]).norm() - l0) / l0;
      ++n;
    }
  return n ? sum / double(n) : 0;
}

//! Diagnostics dump: `prefix`_source.ply, _aligned.ply and _truth.ply, the source's triangles at its rest positions,
//! at `x` and at the ground truth, coloured by the ground-truth error at `x` (blue 0 to red 3 % of the diagonal);
//! ascii, for `topotrack render`.
inline void write_error_meshes(const std::string& prefix, const AlignmentPair& pair, std::span<const Vec3> x) {
  const std::vector<double> err = truth_errors(x, pair.truth, pair.diagonal);
  MeshData out = to_mesh_data(pair.source, false);
  VertexAttribute color{"color", 3, {}};
  for (const double e : err) {
    const float t = float(std::min(1.0, e / 0.03));
    color.values.insert(color.values.end(), {t, 0.2f, 1 - t});
  }
  out.attributes = {color};
  const auto write = [&](const char* name, std::span<const Vec3> at) {
    for (std::size_t i = 0; i < out.positions.size() && i < at.size(); ++i) out.positions[i] = {at[i].x(), at[i].y(), at[i].z()};
    write_ply(prefix + name, out, PlyWriteOptions{true});
  };
  write("_source.ply", pair.source.positions());
  write("_aligned.ply", x);
  write("_truth.ply", pair.truth);
}

//! The source split into `parts` clusters by k-means on its positions (deterministic: farthest-point
//! seeds from vertex 0, 10 Lloyd steps); the cluster of each vertex, by handle index.
inline std::vector<int> body_parts(const SurfaceMesh& source, int parts) {
  const auto& P = source.positions();
  std::vector<Vec3> c{P[0]};
  std::vector<double> d(P.size(), std::numeric_limits<double>::infinity());
  while (int(c.size()) < parts) {
    std::size_t far = 0;
    for (std::size_t i = 0; i < P.size(); ++i) {
      d[i] = std::min(d[i], (P[i] - c.back()).squaredNorm());
      if (d[i] > d[far]) far = i;
    }
    c.push_back(P[far]);
  }
  std::vector<int> label(P.size(), 0);
  for (int it = 0; it < 10; ++it) {
    std::vector<Vec3> sum(c.size(), Vec3::Zero());
    std::vector<int> count(c.size(), 0);
    for (std::size_t i = 0; i < P.size(); ++i) {
      int best = 0;
      for (int k = 1; k < int(c.size()); ++k)
        if ((P[i] - c[k]).squaredNorm() < (P[i] - c[best]).squaredNorm()) best = k;
      label[i] = best;
      sum[best] += P[i];
      ++count[best];
    }
    for (std::size_t k = 0; k < c.size(); ++k)
      if (count[k]) c[k] = sum[k] / count[k];
  }
  return label;
}

//! Mean ground-truth error (% of the diagonal) per body part, with each part's centre in the source's
//! bounding box (0..1 per axis) so that the part can be named.
inline void print_parts(std::span<const Vec3> x, const AlignmentPair& pair, const std::vector<int>& label) {
  const std::vector<double> err = truth_errors(x, pair.truth, pair.diagonal);
  const BoundingBox box = bounding_box(pair.source);
  const int parts = 1 + *std::max_element(label.begin(), label.end());
  std::vector<double> sum(parts, 0);
  std::vector<Vec3> centre(parts, Vec3::Zero());
  std::vector<int> count(parts, 0);
  for (std::size_t i = 0; i < err.size(); ++i) {
    sum[label[i]] += err[i];
    centre[label[i]] += pair.source.positions()[i];
    ++count[label[i]];
  }
  std::printf("    parts (centre in the source bbox: error %%):");
  for (int k = 0; k < parts; ++k) {
    if (!count[k]) continue;
    const Vec3 u = (centre[k] / count[k] - box.min).cwiseQuotient(box.max - box.min);
    std::printf(" (%.2f %.2f %.2f: %.2f)", u.x(), u.y(), u.z(), 100 * sum[k] / count[k]);
  }
  std::printf("\n");
}

//! The best rigid motion (Kabsch, reflection excluded) taking x[v] to y[v] over the vertices `at`: y ~ R (x - cx) + cy.
struct RigidFit {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Vec3 cx = Vec3::Zero(), cy = Vec3::Zero();
  Vec3 operator()(const Vec3& p) const { return R * (p - cx) + cy; }
  double angle_deg() const { return std::acos(std::clamp((R.trace() - 1) / 2, -1.0, 1.0)) * 180 / 3.14159265358979; }
};
inline RigidFit best_rigid_fit(std::span<const Vec3> x, std::span<const Vec3> y, std::span<const Index> at) {
  RigidFit f;
  if (at.empty()) return f;
  for (const Index v : at) { f.cx += x[v]; f.cy += y[v]; }
  f.cx /= double(at.size());
  f.cy /= double(at.size());
  Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
  for (const Index v : at) H += (x[v] - f.cx) * (y[v] - f.cy).transpose();
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
  D(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1 : 1;
  f.R = svd.matrixV() * D * svd.matrixU().transpose();
  return f;
}

//! The regions of the source whose vertices are more than `threshold` (a fraction of the diagonal) from their ground
//! truth, connected over the source's edges: the `shown` largest by summed error, each with its share of the whole
//! error, its mean error, and the angle and the mean error left by the best rigid motion (Kabsch) from `x` to the truth
//! over the region: a region turned as a whole leaves little, a distorted one much. Also |cos| of the angle between that
//! motion's axis and the region's longest principal direction (1: turned about its own length, as a limb twisted), and
//! the region's three principal standard deviations, in diagonals.
inline void print_error_regions(std::span<const Vec3> x, const AlignmentPair& pair, double threshold, int shown) {
  const std::vector<double> err = truth_errors(x, pair.truth, pair.diagonal);
  const EdgeGraph g = edge_graph(pair.source);
  std::vector<int> region(err.size(), -1);
  std::vector<std::vector<Index>> regions;
  double total = 0;
  for (std::size_t v = 0; v < err.size(); ++v) {
    if (pair.source.is_deleted(Vertex(Index(v)))) continue;
    total += err[v];
    if (err[v] < threshold || region[v] >= 0) continue;
    std::vector<Index> stack{Index(v)}, members;
    region[v] = int(regions.size());
    while (!stack.empty()) {
      const Index u = stack.back();
      stack.pop_back();
      members.push_back(u);
      for (Index i = g.offset[u]; i < g.offset[u + 1]; ++i)
        if (const Index w = g.target[i]; region[w] < 0 && err[w] >= threshold) {
          region[w] = int(regions.size());
          stack.push_back(w);
        }
    }
    regions.push_back(std::move(members));
  }
  auto summed = [&](const std::vector<Index>& r) {
    double e = 0;
    for (const Index v : r) e += err[v];
    return e;
  };
  std::sort(regions.begin(), regions.end(), [&](const auto& a, const auto& b) { return summed(a) > summed(b); });
  std::printf("    regions above %.2f %% of the diagonal: %zu\n", 100 * threshold, regions.size());
  const BoundingBox box = bounding_box(pair.source);
  for (std::size_t k = 0; k < regions.size() && int(k) < shown; ++k) {
    const std::vector<Index>& r = regions[k];
    Vec3 centre = Vec3::Zero();
    for (const Index v : r) centre += pair.source.positions()[v];
    centre /= double(r.size());
    const RigidFit fit = best_rigid_fit(x, pair.truth, r);
    double left = 0;
    for (const Index v : r) left += (fit(x[v]) - pair.truth[v]).norm();
    const Vec3 u = (centre - box.min).cwiseQuotient(box.max - box.min);
    Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
    for (const Index v : r) C += (pair.truth[v] - fit.cy) * (pair.truth[v] - fit.cy).transpose();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(C);
    const Eigen::AngleAxisd aa(fit.R);
    const double along = std::abs(aa.axis().dot(eig.eigenvectors().col(2)));
    const auto sd = [&](int i) { return std::sqrt(std::max(0.0, eig.eigenvalues()(i)) / double(r.size())) / pair.diagonal; };
    std::printf("      %zu vertices at (%.2f %.2f %.2f): %.1f %% of the error, mean %.3f %%; best rigid fix turns %.0f deg "
                "(axis along the region %.2f), leaves %.3f %%; extent %.3f %.3f %.3f\n", r.size(), u.x(), u.y(), u.z(),
                100 * summed(r) / total, 100 * summed(r) / double(r.size()), fit.angle_deg(), along,
                100 * left / double(r.size()) / pair.diagonal, sd(2), sd(1), sd(0));
  }
}

}  // namespace topotrack::test
