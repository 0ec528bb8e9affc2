// Tangential drift of the coarse stage (§4.2) over consecutive frames, against ground truth: the
// tracker's case (issue 6: resurfaced pcow drifts 2.7 % of the diagonal over 40 frames, most of it
// over frames 2-6 where the cow squashes hardest). Frame 1 of a real sequence is re-sampled (new
// connectivity), aligned frame after frame onto the re-sampled next frames, and every vertex is
// compared with where its material point lands in the coherent sequence.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "kernels/eval/drift.hpp"
#include "kernels/registration/coarse.hpp"
#include "kernels/registration/fine.hpp"
#include "tests/kernels/registration/real_data.hpp"

namespace topotrack {
namespace {

//! Mean ground-truth error (fraction of the diagonal) after each of `frames` consecutive alignments of
//! `name`'s frame `first` (re-sampled at `edge_factor` of its mean edge length) onto the next frames.
std::vector<double> chained_drift(const std::string& name, int first, int frames, const CoarseParams& params,
                                  double edge_factor, bool fine) {
  const SurfaceMesh coherent_first = test::load_frame(name, first);
  const TargetSurface first_surface = TargetSurface::from_mesh(coherent_first);
  SurfaceMesh mesh = test::resample(coherent_first, edge_factor);
  const double edge = mean_edge_length(mesh);
  std::vector<Vec3> material;
  std::vector<Vertex> live;
  for (Index i = 0; i < mesh.vertices_size(); ++i)
    if (!mesh.is_deleted(Vertex(i))) {
      live.push_back(Vertex(i));
      material.push_back(mesh.position(Vertex(i)));
    }
  std::vector<double> out;
  for (int n = first + 1; n <= first + frames; ++n) {
    const SurfaceMesh coherent = test::load_frame(name, n);
    const SurfaceMesh target_mesh = test::resample(coherent, edge / mean_edge_length(coherent));
    const TargetSurface target = TargetSurface::from_mesh(target_mesh);
    const CoarseReport c = align_coarse(mesh, target, params);
    if (std::getenv("TOPOTRACK_TEST_VERBOSE"))
      std::printf(
          "  frame %d: %d nodes, %d rounds (+%d low-density), misfit %.4f, %.3f s (prealign+pass %.3f, "
          "graph %.3f, correspondences %.3f, assembly %.3f, factorisation %.3f, solve %.3f)\n",
          n, c.nodes, c.iterations, c.coarse_pass_iterations, c.misfit_start, c.seconds_total,
          c.seconds_prealign, c.seconds_graph, c.seconds_correspondences, c.seconds_assembly,
          c.seconds_factorisation, c.seconds_solve);
    if (fine) align_fine(mesh, target);
    const std::vector<Vec3> expected =
        expected_by_correspondence(material, first_surface, coherent.positions());
    std::vector<Vec3> tracked(live.size());
    for (std::size_t i = 0; i < live.size(); ++i) tracked[i] = mesh.position(live[i]);
    out.push_back(drift_stats(tracked, expected).mean / bounding_box(coherent).diagonal());
  }
  return out;
}

void print(const char* label, const std::vector<double>& drift) {
  std::printf("  %-28s", label);
  for (double d : drift) std::printf(" %.3f", 100 * d);
  std::printf(" (%% of the diagonal)\n");
}

#define TOPOTRACK_REQUIRE_DATA(name) \
  if (!std::filesystem::exists(test::data_frame(name, 8))) GTEST_SKIP() << "no " << name << " data"

// profiles/capture.json's node spacing: the drift is set by the node spacing in absolute terms (the
// deformation between nodes is linear blend skinning of affine maps, the squash is not), so a graph
// twice as dense drifts about a third less. Measured until 2026-11-23 (load 6-9, alpha_reg_start 10000, last frame, % of
// the diagonal): edge 0.7 of pcow's, frames 1 -> 7: spacing 4 (the paper's) 2.01, spacing 2 1.30 (1.3 s
// and 4.9 s); edge 0.35 (the tracker's resolution) 1 -> 9: 1.17 and 0.92 (3.5x the coarse time); edge 0.5,
// 1 -> 9: spacing 8 3.30, 4 1.42, 3 1.33, 2.5 1.15, 2 0.96, 1.5 0.94; frames 15 -> 31 at edge 0.35: 2.11
// and 1.12. Worse at spacing 4 (tracker, 15 pcow frames): alpha_reg_min 10 (1.7x the drift) or 1 (1.3x),
// alpha_point 1 (1.25x); here: alpha_point 0.01 (1.3x), smooth_weight 1 or 0.01, k 6 or 8 (1.3x, 1.45x),
// no backward matches (1.8x); no effect: alpha_reg_min 0.01, fit_tolerance 0, max_iterations 100,
// max_pcg_iterations 100.
//
// Since 2026-11-23 profiles/capture.json has the paper's alpha_reg (from 1000) and 8 rounds per level after the
// low-density pass (the library's default: 3). Last frame, spacing 4 / 2: alpha_reg 1000 with 3 rounds
// 1.85 / 1.24, with 8 2.16 / 1.16; alpha_reg 10000 with 3 rounds 2.01 / 1.30, with 8 3.27 / 1.18. (In the
// tracker, with ImproveMesh and the topology steps between frames, 8 rounds lower resurfaced pcow's drift at
// spacing 4 too: 2.61 -> 2.19 %.) TOPOTRACK_TEST_ALPHA_REG_START and TOPOTRACK_TEST_PER_LEVEL_AFTER_PASS
// override the two.
TEST(CoarseDrift, DenserGraphSlidesLessOnPcow) {
  TOPOTRACK_REQUIRE_DATA("pcow");
  CoarseParams paper;  // alpha_reg from 1000 as in profiles/capture.json, 3 rounds per level after the pass
  if (const char* e = std::getenv("TOPOTRACK_TEST_ALPHA_REG_START")) paper.alpha_reg_start = std::atof(e);
  if (const char* e = std::getenv("TOPOTRACK_TEST_PER_LEVEL_AFTER_PASS"))
    paper.max_iterations_per_level_after_pass = std::atoi(e);
  CoarseParams dense = paper;
  dense.node_spacing_factor = 2;
  const std::vector<double> a = chained_drift("pcow", 1, 6, paper, 0.7, true);
  const std::vector<double> b = chained_drift("pcow", 1, 6, dense, 0.7, true);
  print("node spacing 4", a);
  print("node spacing 2", b);
  EXPECT_LE(a.back(), 0.025);
  EXPECT_LE(b.back(), 0.8 * a.back());
  for (std::size_t i = 0; i < a.size(); ++i) EXPECT_LE(b[i], a[i]) << "frame " << i + 2;
}

}  // namespace
}  // namespace topotrack
