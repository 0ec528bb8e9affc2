#pragma once
//! Ground-truth alignment pairs from /work/shared/data: the data sequences keep their connectivity,
//! so vertex i of frame k corresponds to vertex i of frame k + gap. The target is frame k + gap
//! re-sampled (different connectivity) so that the aligner never sees the correspondence.
//! Header-only; shared by the registration tests and benchmark.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "io/mesh_reader.hpp"
#include "kernels/improve/improve.hpp"
#include "kernels/mesh/mesh_convert.hpp"
#include "kernels/mesh/mesh_queries.hpp"
#include "kernels/raycast/target_surface.hpp"

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

}  // namespace topotrack::test
