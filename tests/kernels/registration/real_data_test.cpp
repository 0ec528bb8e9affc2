// End-to-end alignment on the real sequences with ground truth (slow label): frame k onto a re-sampled
// frame k + 15 (large motion), the targets of the registration issue.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <utility>
#include <vector>

#include "kernels/registration/coarse.hpp"
#include "kernels/registration/fine.hpp"
#include "kernels/registration/intrinsic_matches.hpp"
#include "kernels/registration/large_motion.hpp"
#include "kernels/registration/projection.hpp"
#include "tests/kernels/registration/real_data.hpp"

namespace topotrack {
namespace {

struct Figures {
  test::AlignmentError unaligned, aligned, projected;
  RelaxReport relax;  // the fine stage's relaxation on the target
};

// Environment knobs for comparisons: TOPOTRACK_TEST_CHOLESKY=eigen, TOPOTRACK_TEST_DIRECT=1,
// TOPOTRACK_TEST_RETRACT=0|1 (retract_rotations), TOPOTRACK_TEST_CHECK_FIT=0|1 (check_fit_first), and
// TOPOTRACK_TEST_<NAME>=value for the CoarseParams below (MAX_PCG: max_pcg_iterations, NODE_SPACING:
// node_spacing_factor, ALPHA_POINT / ALPHA_PLANE: alpha_point / alpha_plane), TOPOTRACK_TEST_HISTORY=1
// (per-round figures), TOPOTRACK_TEST_RIGID_TRUTH=1 (the error of the best rigid motion: pcow 9.5%, elephant 6.0%),
// TOPOTRACK_TEST_INTRINSIC=0|1, TOPOTRACK_TEST_INTRINSIC_PASSES=n (CoarseParams::intrinsic_full_graph,
// intrinsic_passes), TOPOTRACK_TEST_INTRINSIC_ANCHORS=n, TOPOTRACK_TEST_INTRINSIC_MISPLACED=x, TOPOTRACK_TEST_FINE_ROUNDS=n, TOPOTRACK_TEST_FINE_MAX_ROUNDS=n, TOPOTRACK_TEST_FINE_MORE_RESIDUAL=x, TOPOTRACK_TEST_FINE_NORMAL_ANGLE=deg,
// TOPOTRACK_TEST_FINE_NORMAL_DISPLACEMENT=0|1 (FineParams), TOPOTRACK_TEST_WRITE_ERRORS=prefix (test::write_error_meshes), TOPOTRACK_TEST_DENSE_SPACING=x (0: no denser graph),
// TOPOTRACK_TEST_VERTEX_FIT=x (0: the nodes' fit alone), TOPOTRACK_TEST_VERTEX_FIT_SPACING=x, TOPOTRACK_TEST_VERTEX_FIT_DISAGREE=x
// (CoarseParams::vertex_fit_weight, vertex_fit_spacing, vertex_fit_max_disagreement),
// TOPOTRACK_TEST_DENSE_ALPHA=x (dense_spacing_factor, dense_alpha_reg), TOPOTRACK_TEST_ALPHA_START_WITHOUT_PASS=x,
// TOPOTRACK_TEST_MIN_NODES=n (0: the paper's spacing on any mesh), TOPOTRACK_TEST_NEAR_PASS_DENSITY=x (0: a quarter at any misfit),
// TOPOTRACK_TEST_NEAR_PASS_MIN_SPACING=x, TOPOTRACK_TEST_NEAR_PASS_PER_LEVEL=n, TOPOTRACK_TEST_TRUTH_STAGE=full|pass
// (the ground truth's matches below in the full graph's rounds or in the passes' only), TOPOTRACK_TEST_TRUTH_SKIP_LEVEL=n,
// TOPOTRACK_TEST_TRUTH_MATCHES=L (each node matched to the closest target point of its ground truth in the
// first L alpha_reg levels of both stages: what the correspondences cost, docs/results.md; the backward matches and the
// intrinsic guide still act beside or over them, so the floor of the representation needs TOPOTRACK_TEST_BACKWARD_WEIGHT=0
// TOPOTRACK_TEST_INTRINSIC=0 TOPOTRACK_TEST_INTRINSIC_PASSES=0 as well), TOPOTRACK_TEST_TRUTH_TO_TARGET=1 (the ground
// truth's mean distance to the re-sampled target), TOPOTRACK_TEST_TRUTH_BELOW=h
// (those matches only for the nodes below h of the source's height), TOPOTRACK_TEST_STAGE_REGIONS=1 (with
// TOPOTRACK_TEST_STAGES: the error regions after every level too), TOPOTRACK_TEST_STRAIN=1 (the mean edge strain against
// the source after the coarse stage and at the end, and the distance to the target: measures without the ground truth;
// TOPOTRACK_TEST_HISTORY also prints the full graph's first and last energies).
// TOPOTRACK_TEST_SOURCE_REFINE=f: the source re-meshed at f of its mean edge length, its ground truth carried along
// (test::refine_source; the bench's sizes 2-4 are 0.85, 0.563, 0.24). TOPOTRACK_TEST_RELAX_ITERATIONS=n (0: no relaxation
// on the target), TOPOTRACK_TEST_RELAX_CG_ITERATIONS=n, TOPOTRACK_TEST_RELAX_PLANE=x (FineParams::relax).
void env_double(const char* name, double& value) {
  if (const char* e = std::getenv(name)) value = std::atof(e);
}
void env_int(const char* name, int& value) {
  if (const char* e = std::getenv(name)) value = std::atoi(e);
}



int last_rounds = 0;       // rounds of the last run_pair
CoarseReport last_coarse;  // its coarse report

Figures run_pair(const std::string& name, int frame, int gap, double edge_factor = 0.8, double source_refine = 0) {
  env_int("TOPOTRACK_TEST_FRAME", frame);  // another start frame, for comparisons (the assertions are for frame 1)
  test::AlignmentPair pair = test::make_pair(name, frame, gap, edge_factor);
  env_double("TOPOTRACK_TEST_SOURCE_REFINE", source_refine);
  if (source_refine > 0) test::refine_source(pair, source_refine);
  const TargetSurface target = TargetSurface::from_mesh(pair.target_mesh);
  Figures f;
  f.unaligned = test::alignment_error(pair.source, pair.truth, target, pair.diagonal);
  if (std::getenv("TOPOTRACK_TEST_RIGID_TRUTH")) {  // the best rigid fit to the ground truth, for reference
    std::vector<Index> all(pair.truth.size());
    for (std::size_t i = 0; i < all.size(); ++i) all[i] = Index(i);
    const test::RigidFit fit = test::best_rigid_fit(pair.source.positions(), pair.truth, all);
    double e = 0;
    for (const Index i : all) e += (fit(pair.source.positions()[i]) - pair.truth[i]).norm();
    std::printf("  best rigid: error %.4f %%, angle %.1f deg, shift %.4f diag\n", 100 * e / double(all.size()) / pair.diagonal,
                fit.angle_deg(), (fit.cy - fit.cx).norm() / pair.diagonal);
  }
  if (std::getenv("TOPOTRACK_TEST_TRUTH_TO_TARGET")) {  // how far the ground truth lies from the re-sampled target
    SurfaceMesh at_truth = pair.source.clone();
    at_truth.positions() = pair.truth;
    const test::AlignmentError t = test::alignment_error(at_truth, pair.truth, target, pair.diagonal);
    std::printf("  ground truth to the target: mean %.4f %% of the diagonal\n", 100 * t.mean_target);
  }
  SurfaceMesh projected = pair.source.clone();
  project_to_closest(projected, target);
  f.projected = test::alignment_error(projected, pair.truth, target, pair.diagonal);
  SurfaceMesh mesh = pair.source.clone();
  CoarseParams params;  // as topotrack align runs it (fine: below)
  FineParams fine;
  use_large_motion_alignment(params, fine);
  if (const char* e = std::getenv("TOPOTRACK_TEST_INTRINSIC")) params.intrinsic_full_graph = std::atoi(e) != 0;
  env_int("TOPOTRACK_TEST_INTRINSIC_PASSES", params.intrinsic_passes);
  env_int("TOPOTRACK_TEST_INTRINSIC_ANCHORS", params.intrinsic.anchors);
  env_double("TOPOTRACK_TEST_INTRINSIC_MISPLACED", params.intrinsic.misplaced_spacings);
  if (const char* e = std::getenv("TOPOTRACK_TEST_CHOLESKY"); e && std::string(e) == "eigen")
    params.solver = CholeskyBackend::EigenLDLT;
  if (std::getenv("TOPOTRACK_TEST_DIRECT")) params.linear_solver = CoarseLinearSolver::Direct;
  env_double("TOPOTRACK_TEST_PCG_TOLERANCE", params.pcg_tolerance);
  env_double("TOPOTRACK_TEST_STEP_TOLERANCE", params.step_tolerance);
  env_double("TOPOTRACK_TEST_FIT_TOLERANCE", params.fit_tolerance);
  env_double("TOPOTRACK_TEST_STALL_RATIO", params.stall_ratio);
  env_double("TOPOTRACK_TEST_CONVERGENCE_TOLERANCE", params.convergence_tolerance);
  env_double("TOPOTRACK_TEST_ALPHA_REG_START", params.alpha_reg_start);
  env_double("TOPOTRACK_TEST_ALPHA_START_AFTER_PASS", params.alpha_reg_start_after_pass);
  env_double("TOPOTRACK_TEST_ALPHA_START_WITHOUT_PASS", params.alpha_reg_start_without_pass);
  env_double("TOPOTRACK_TEST_ALPHA_POINT", params.alpha_point);
  env_double("TOPOTRACK_TEST_ALPHA_PLANE", params.alpha_plane);
  env_double("TOPOTRACK_TEST_ALPHA_REG_MIN", params.alpha_reg_min);
  env_double("TOPOTRACK_TEST_VERTEX_FIT", params.vertex_fit_weight);
  env_double("TOPOTRACK_TEST_VERTEX_FIT_SPACING", params.vertex_fit_spacing);
  env_double("TOPOTRACK_TEST_VERTEX_FIT_DISAGREE", params.vertex_fit_max_disagreement);
  env_double("TOPOTRACK_TEST_DENSE_SPACING", params.dense_spacing_factor);
  env_double("TOPOTRACK_TEST_DENSE_ALPHA", params.dense_alpha_reg);
  env_int("TOPOTRACK_TEST_MIN_NODES", params.min_nodes);
  env_double("TOPOTRACK_TEST_MAX_CLOSEST_RATIO", params.max_closest_ratio);
  env_double("TOPOTRACK_TEST_MAX_NORMAL_ANGLE", params.max_normal_angle_deg);
  env_int("TOPOTRACK_TEST_MAX_ITERATIONS", params.max_iterations);
  env_double("TOPOTRACK_TEST_NODE_SPACING", params.node_spacing_factor);
  env_int("TOPOTRACK_TEST_MAX_PER_LEVEL", params.max_iterations_per_level);
  env_int("TOPOTRACK_TEST_MAX_PCG", params.max_pcg_iterations);
  env_double("TOPOTRACK_TEST_PREALIGN_MISFIT", params.prealign_misfit);
  env_double("TOPOTRACK_TEST_PREALIGN_TRIM", params.prealign.trim_fraction);
  env_double("TOPOTRACK_TEST_AXES_WIN_RATIO", params.prealign.axes_win_ratio);
  env_int("TOPOTRACK_TEST_CLOSEST_LEVELS", params.closest_point_levels);
  env_double("TOPOTRACK_TEST_PASS_DENSITY", params.coarse_pass_density);
  env_double("TOPOTRACK_TEST_NEAR_PASS_DENSITY", params.near_pass_density);
  env_double("TOPOTRACK_TEST_NEAR_PASS_MIN_SPACING", params.near_pass_min_spacing);
  env_int("TOPOTRACK_TEST_NEAR_PASS_PER_LEVEL", params.near_pass_max_iterations_per_level);
  env_double("TOPOTRACK_TEST_PASS_MISFIT", params.coarse_pass_misfit);
  env_int("TOPOTRACK_TEST_PER_LEVEL_AFTER_PASS", params.max_iterations_per_level_after_pass);
  env_double("TOPOTRACK_TEST_PASS_ALPHA_MIN", params.coarse_pass_alpha_reg_min);
  env_double("TOPOTRACK_TEST_PREALIGN_TOLERANCE", params.prealign.tolerance);
  env_int("TOPOTRACK_TEST_PREALIGN_ITERATIONS", params.prealign.max_iterations);
  env_double("TOPOTRACK_TEST_BACKWARD_WEIGHT", params.backward_weight);
  env_double("TOPOTRACK_TEST_BACKWARD_VERTEX_WEIGHT", params.backward_vertex_weight);
  env_double("TOPOTRACK_TEST_BACKWARD_MISFIT", params.backward_misfit);
  env_double("TOPOTRACK_TEST_BACKWARD_ALL_MISFIT", params.backward_all_misfit);
  env_int("TOPOTRACK_TEST_BACKWARD_SAMPLES", params.backward_samples_per_node);
  if (const char* e = std::getenv("TOPOTRACK_TEST_RETRACT")) params.retract_rotations = std::atoi(e) != 0;
  if (const char* e = std::getenv("TOPOTRACK_TEST_CHECK_FIT")) params.check_fit_first = std::atoi(e) != 0;
  if (const char* e = std::getenv("TOPOTRACK_TEST_PREALIGN_SAMPLES")) params.prealign.max_samples = std::size_t(std::atoi(e));
  // Per-stage diagnostics (TOPOTRACK_TEST_STAGES=1): where the error is after each stage.
  const bool stages = std::getenv("TOPOTRACK_TEST_STAGES") != nullptr;
  const PointIndex truth_index(pair.truth);
  const std::vector<int> parts = test::body_parts(pair.source, 8);
  if (stages) {
    std::printf("  %s %d->%d stages:\n", name.c_str(), frame, frame + gap);
    test::print_breakdown("unaligned", test::error_breakdown(pair.source.positions(), pair, target, truth_index));
    test::print_breakdown("projection", test::error_breakdown(projected.positions(), pair, target, truth_index));
    params.observer = [&](const CoarseSnapshot& s) {
      char label[64];
      const char* stage = s.stage == CoarseStage::Prealigned ? "rigid" : s.stage == CoarseStage::LowDensityLevel ? "low"
                          : s.stage == CoarseStage::DenseLevel    ? "dense" : "full";
      std::snprintf(label, sizeof label, "%s a=%g (%d r, fit %.2f)", stage, s.alpha_reg, s.rounds, s.fit_distance);
      test::print_breakdown(label, test::error_breakdown(s.positions, pair, target, truth_index));
      if (std::getenv("TOPOTRACK_TEST_STAGE_REGIONS")) test::print_error_regions(s.positions, pair, 0.015, 4);
    };
  }
  int truth_levels = 0;
  env_int("TOPOTRACK_TEST_TRUTH_MATCHES", truth_levels);
  if (truth_levels > 0)
    params.match_override = [&](const CoarseMatchRound& round, std::vector<Correspondence>& corr) {
      if (round.level > truth_levels) return;
      if (const char* e = std::getenv("TOPOTRACK_TEST_TRUTH_STAGE")) {
        const bool full = round.stage == CoarseStage::Level;
        if ((std::string(e) == "full") != full) return;
      }
      if (const char* e = std::getenv("TOPOTRACK_TEST_TRUTH_SKIP_LEVEL"); e && round.level == std::atoi(e)) return;
      const BoundingBox box = bounding_box(pair.source);
      double below = 2;
      env_double("TOPOTRACK_TEST_TRUTH_BELOW", below);
      for (std::size_t j = 0; j < round.nodes.size(); ++j) {
        const Vec3& p0 = pair.source.positions()[round.nodes[j].idx];
        if ((p0.y() - box.min.y()) / (box.max.y() - box.min.y()) > below) continue;
        const TargetSurface::Hit hit = target.closest_point(pair.truth[round.nodes[j].idx]);
        corr[j].status = CorrespondenceStatus::Ok;
        corr[j].point = hit.point;
        corr[j].normal = hit.normal;
        corr[j].distance = (mesh.positions()[round.nodes[j].idx] - hit.point).norm();
      }
    };
  const CoarseReport c = align_coarse(mesh, target, params);
  if (stages) test::print_breakdown("coarse", test::error_breakdown(mesh.positions(), pair, target, truth_index));
  std::printf("  node spacing %.4f of the diagonal (%.2f mean edge lengths)\n", c.node_spacing / pair.diagonal,
              c.node_spacing / mean_edge_length(pair.source));
  std::printf("  misfit %.4f of the diagonal, low-density pass %d rounds, prealigned %d (%d ICP steps, axes won %d, %.4f -> %.4f, %.3f s of %.3f s); "
              "intrinsic: %zu full-graph nodes misplaced, %d guided passes, %.3f s\n", c.misfit_start, c.coarse_pass_iterations,
              int(c.prealigned), c.prealign.iterations, int(c.prealign.axes_won), c.prealign.distance_start / pair.diagonal,
              c.prealign.distance_end / pair.diagonal, c.prealign.seconds, c.seconds_prealign, c.intrinsic_full_graph_misplaced, c.intrinsic_passes,
              c.seconds_intrinsic);
  env_int("TOPOTRACK_TEST_FINE_ROUNDS", fine.rounds);
  env_int("TOPOTRACK_TEST_FINE_MAX_ROUNDS", fine.max_rounds);
  env_double("TOPOTRACK_TEST_FINE_MORE_RESIDUAL", fine.more_rounds_residual);
  env_double("TOPOTRACK_TEST_FINE_MORE_TOLERANCE", fine.more_rounds_tolerance);
  env_double("TOPOTRACK_TEST_FINE_NORMAL_ANGLE", fine.max_normal_angle_deg);
  if (const char* e = std::getenv("TOPOTRACK_TEST_FINE_NORMAL_DISPLACEMENT")) fine.normal_displacement = std::atoi(e) != 0;
  const double coarse_strain = test::mean_edge_strain(pair.source, mesh.positions());
  env_int("TOPOTRACK_TEST_RELAX_ITERATIONS", fine.relax.iterations);
  env_int("TOPOTRACK_TEST_RELAX_CG_ITERATIONS", fine.relax.cg_iterations);
  env_double("TOPOTRACK_TEST_RELAX_PLANE", fine.relax.plane_weight);
  const FineReport fr = align_fine(mesh, target, fine, pair.source.positions());
  f.aligned = test::alignment_error(mesh, pair.truth, target, pair.diagonal);
  f.relax = fr.relax;
  if (const char* e = std::getenv("TOPOTRACK_TEST_WRITE_ERRORS")) test::write_error_meshes(e, pair, mesh.positions());
  // TOPOTRACK_TEST_INTRINSIC_PRECISION=s: how far from its ground truth the intrinsic matches place each node of a
  // Poisson-disk sampling at s diagonals, with the anchors (and nodes) at their ground truth and at the result.
  if (const char* e = std::getenv("TOPOTRACK_TEST_INTRINSIC_PRECISION")) {
    const EdgeGraph rest = edge_graph(pair.source);
    const EdgeGraph tg = edge_graph(target.positions(), target.triangles());
    const double spacing = std::atof(e) * pair.diagonal;
    const std::vector<Index> nodes = poisson_disk_samples(rest, spacing);
    std::vector<Vec3> x0(nodes.size());
    for (std::size_t j = 0; j < nodes.size(); ++j) x0[j] = pair.source.positions()[nodes[j]];
    const IntrinsicAnchors anchors = intrinsic_anchors(rest, nodes, x0, params.intrinsic.anchors);
    IntrinsicParams ip = params.intrinsic;
    ip.misplaced_spacings = 0;
    for (int which = 0; which < 2; ++which) {
      const auto& at = which == 0 ? pair.truth : mesh.positions();
      std::vector<Vec3> ax(anchors.anchor.size()), nx(nodes.size());
      for (std::size_t a = 0; a < ax.size(); ++a) ax[a] = at[anchors.anchor[a]];
      for (std::size_t j = 0; j < nodes.size(); ++j) nx[j] = at[nodes[j]];
      const IntrinsicMatches im = intrinsic_matches(anchors, ax, nodes, nx, target, tg, spacing, ip);
      std::vector<double> err;
      for (std::size_t j = 0; j < nodes.size(); ++j)
        if (im.match[j].valid()) err.push_back((im.match[j].point - pair.truth[nodes[j]]).norm() / pair.diagonal);
      std::sort(err.begin(), err.end());
      double mean = 0;
      for (double v : err) mean += v;
      std::printf("  intrinsic places, anchors at the %s: %zu of %zu nodes placed, kept %zu of %zu anchors, scale %.3f; "
                  "error mean %.3f %% median %.3f %% p90 %.3f %%\n", which == 0 ? "ground truth" : "result", err.size(),
                  nodes.size(), im.kept, im.anchors, im.scale, 100 * mean / double(std::max<std::size_t>(1, err.size())),
                  err.empty() ? 0.0 : 100 * err[err.size() / 2], err.empty() ? 0.0 : 100 * err[err.size() * 9 / 10]);
    }
  }
  if (stages) {
    test::print_breakdown("fine", test::error_breakdown(mesh.positions(), pair, target, truth_index));
    std::printf("  edge strain |l' - l| / l: aligned %.4f, ground truth %.4f\n", test::mean_edge_strain(pair.source, mesh.positions()),
                test::mean_edge_strain(pair.source, pair.truth));
    std::printf("  unaligned"); test::print_parts(pair.source.positions(), pair, parts);
    std::printf("  aligned  "); test::print_parts(mesh.positions(), pair, parts);
    test::print_error_regions(mesh.positions(), pair, 0.015, 5);
  }
  std::printf("  coarse phases: graph %.3f correspondences %.3f assembly %.3f factorisation %.3f solve %.3f; "
              "pcg %d, factorisations %d, edges %d, last round %zu ok %zu no-hit %zu normal %zu far; fine %zu matched %zu pruned, %d rounds, residual %.5f%%\n",
              c.seconds_graph, c.seconds_correspondences, c.seconds_assembly, c.seconds_factorisation,
              c.seconds_solve, c.pcg_iterations, c.factorisations, c.graph_edges, c.correspondences, c.pruned_no_hit, c.pruned_normal,
              c.pruned_distance, fr.correspondences, fr.pruned, fr.rounds, 100 * fr.mean_residual);
  std::printf("  relax: %d iterations, %d cg, energy %.6g -> %.6g, seconds setup %.3f closest %.3f rotations %.3f solve %.3f total %.3f\n",
              fr.relax.iterations, fr.relax.cg_iterations, fr.relax.energy_start, fr.relax.energy_end, fr.relax.seconds_setup,
              fr.relax.seconds_closest, fr.relax.seconds_rotations, fr.relax.seconds_solve, fr.relax.seconds_total);
  std::printf("%s %d->%d: %d nodes %d rounds %d levels alpha_reg %g, fine %d cg; truth error %% of diag: unaligned %.4f "
              "projection %.4f aligned %.4f; distance to target: projection %.5f aligned %.5f; %.3f s coarse, "
              "%.3f s fine\n",
              name.c_str(), frame, frame + gap, c.nodes, c.iterations, c.levels, c.alpha_reg_end, fr.cg_iterations,
              100 * f.unaligned.mean_truth, 100 * f.projected.mean_truth, 100 * f.aligned.mean_truth,
              100 * f.projected.mean_target, 100 * f.aligned.mean_target, c.seconds_total, fr.seconds_total);
  if (std::getenv("TOPOTRACK_TEST_STRAIN"))  // a measure of the result that needs no ground truth
    std::printf("  strain %.5f (ground truth %.5f), distance to target %.5f %%, strain after the coarse stage %.5f\n",
                test::mean_edge_strain(pair.source, mesh.positions()), test::mean_edge_strain(pair.source, pair.truth),
                100 * f.aligned.mean_target, coarse_strain);
  if (std::getenv("TOPOTRACK_TEST_HISTORY")) {
    std::printf("  rounds (alpha_reg, fit distance in edges, correspondences, motion):");
    for (const CoarseRound& r : c.rounds) std::printf(" [%g %.2f %zu %.2f]", r.alpha_reg, r.fit_distance, r.correspondences, r.motion);
    std::printf("\n  mean node fit distance %.4f mean edge lengths; energy %.6g -> %.6g, E_fit %.6g -> %.6g\n",
                c.mean_fit_distance / mean_edge_length(pair.source), c.energy_start, c.energy_end, c.fit_start, c.fit_end);
  }
  last_rounds = c.iterations;
  last_coarse = c;
  return f;
}

// Large motion, frame k onto k + 15, once per re-sampling of the target (improve_mesh at 0.78-0.82 of its
// mean edge length): which part a swinging leg lands on (pcow, elephant) turns on details of the target's
// triangles, so one re-sampling is one draw: at b4100c4 the elephant gave 3.09 / 2.95 / 3.20 / 3.05 / 3.33%
// and pcow 4.50 / 3.12 / 3.12 / 3.02 / 3.81%, samba 0.151-0.153% (docs/results.md).
// The figures of the run with the median error are returned (last_coarse: its report);
// TOPOTRACK_TEST_EDGE_FACTOR=x runs that one re-sampling only (the figures in the comments below that
// name no median are of one re-sampling at 0.8 from before these medians).
Figures run_resampled(const std::string& name, int frame, int gap) {
  std::vector<double> factors = {0.78, 0.79, 0.8, 0.81, 0.82};
  if (const char* e = std::getenv("TOPOTRACK_TEST_EDGE_FACTOR")) factors = {std::atof(e)};
  std::vector<std::pair<Figures, CoarseReport>> runs;
  for (const double factor : factors) {
    const Figures f = run_pair(name, frame, gap, factor);
    runs.emplace_back(f, last_coarse);
  }
  std::vector<std::size_t> order(runs.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return runs[a].first.aligned.mean_truth < runs[b].first.aligned.mean_truth;
  });
  std::printf("%s %d->%d, target re-sampled at", name.c_str(), frame, frame + gap);
  for (const double factor : factors) std::printf(" %.2f", factor);
  std::printf(" of its edge length: truth error %% of diag");
  for (const auto& [f, c] : runs) std::printf(" %.4f", 100 * f.aligned.mean_truth);
  const std::size_t median = order[order.size() / 2];
  std::printf("; median %.4f\n", 100 * runs[median].first.aligned.mean_truth);
  last_coarse = runs[median].second;
  return runs[median].first;
}

// The targets are 0.35% of the diagonal and a fifth of the unaligned error for the ground-truth
// error, 0.1% for the distance to the target. Measured (see the printed figures) they are met only
// where the motion stays within the capture range of the correspondences (samba); where it does not
// (pcow: the best rigid motion alone leaves 9.5%, elephant: 6.0%), the rigid pre-alignment and the
// low-density pass lower the error; these assertions guard what the implementation achieves.
void expect_improvement(const Figures& f, double max_ratio_to_unaligned) {
  EXPECT_LE(f.aligned.mean_truth, max_ratio_to_unaligned * f.unaligned.mean_truth);
  EXPECT_GT(f.projected.mean_truth, f.aligned.mean_truth);
}

#define TOPOTRACK_REQUIRE_DATA(name)                                                          \
  if (!std::filesystem::exists(test::data_frame(name, 16))) GTEST_SKIP() << "no " << name << " data"

TEST(RealData, SambaLargeMotion) {
  TOPOTRACK_REQUIRE_DATA("samba");
  const Figures f = run_resampled("samba", 1, 15);
  // Measured 2026-12-07 (the relaxation on the target, kLargeMotionRelaxIterations): median 0.0810% of the diagonal
  // (0.0798-0.0827% over the five re-samplings), 0.131 of the unaligned 0.617%; 0.0863% without it
  // (TOPOTRACK_TEST_RELAX_ITERATIONS=0; 2026-12-03, after f19d070), 0.119% also without the vertices' fit
  // (TOPOTRACK_TEST_VERTEX_FIT=0), 0.138% also without the denser graph, 0.152% with alpha_reg down to 0.1 only.
  expect_improvement(f, 0.16);  // issue 4's fifth
  EXPECT_LE(f.aligned.mean_truth, 0.0009);
  EXPECT_EQ(f.relax.iterations, kLargeMotionRelaxIterations);
  EXPECT_GT(last_coarse.fitted_vertices, 3 * last_coarse.nodes);  // half a node spacing apart: measured 1,407 for 415 nodes
  EXPECT_LE(f.aligned.mean_target, 0.001);
}
// The benchmark's 98k size (bench/registration size 4): samba's source re-meshed at 0.24 of its mean edge length, its
// ground truth carried along (test::refine_source), one re-sampling of the target at 0.8.
TEST(RealData, SambaLargeMotionRemeshed) {
  TOPOTRACK_REQUIRE_DATA("samba");
  const Figures f = run_pair("samba", 1, 15, 0.8, 0.24);
  // Measured 2026-12-07: 0.0547% of the diagonal, 0.094 of the unaligned 0.581%; 0.0798% without the relaxation on the
  // target (2026-12-03), 0.0797% with 15 PCG iterations and the coarse correction in the denser graph, 0.0838% without
  // the denser graph, 0.0978% without the vertices' fit.
  expect_improvement(f, 0.16);
  EXPECT_LE(f.aligned.mean_truth, 0.0007);
  EXPECT_LE(f.aligned.mean_target, 0.001);
  EXPECT_GT(last_coarse.nodes, 3000);        // measured 3,230 (the source's 97,814 vertices)
  EXPECT_GT(last_coarse.dense.nodes, 7000);  // measured 7,963
  EXPECT_EQ(last_coarse.dense.factorisations, 0);  // block Jacobi alone (CoarseParams::dense_max_pcg_iterations)
  EXPECT_LE(last_coarse.dense.pcg_iterations, 3 * last_coarse.dense.rounds);
}
TEST(RealData, PcowLargeMotion) {
  TOPOTRACK_REQUIRE_DATA("pcow");
  // Median 2.25% of 26.7% (2026-12-07, the relaxation on the target; 2.03-2.44% over the five re-samplings; distance to
  // the target 0.026%, 0.025-0.028%). Median 2.40% of 26.7% (2026-12-04, the backward matches at the fitted vertices, kLargeMotionBackwardVertexWeight;
  // 2.16-2.51% over the five re-samplings; distance to the target 0.038%, 0.036-0.040%; the ten-run sum 26.35 -> 25.73
  // and the other pairs' 28.77 -> 27.80, docs/results.md). Median 2.28% of 26.7% (2026-12-03 after f19d070, with the vertices' fit, kLargeMotionVertexFitWeight; 2.28-2.68% over
  // the five re-samplings; distance to the target 0.039%, 0.032-0.044%; 2.37% before f19d070). Median 2.46% (2026-12-02, a graph of at least 300 nodes: 284 instead of the paper's spacing's 137,
  // CoarseParams::min_nodes; 2.41% with 350, 2.57% with 250; 3.46% with the paper's spacing, TOPOTRACK_TEST_MIN_NODES=0,
  // the full graph from alpha_reg 10 to 0.01; 3.49% from 1000 to 0.1;
  // 3.47% on 2026-12-01; 3.50% with one fine round; 3.12% at 78d1eea, whose
  // re-sampled targets differ; one re-sampling at 0.8 before b4100c4: 3.25%; misfit 5.1% of the diagonal:
  // pre-aligned, then the low-density pass, both with the backward matches at every node); 9.13% without
  // them (TOPOTRACK_TEST_BACKWARD_WEIGHT=0),
  // 4.32% with them at the pruned nodes only (TOPOTRACK_TEST_BACKWARD_ALL_MISFIT=1),
  // 9.29% also without the rotation retraction (TOPOTRACK_TEST_RETRACT=0); 15.3% with the paper's
  // scheme alone without the retraction (TOPOTRACK_TEST_PREALIGN_MISFIT=0 TOPOTRACK_TEST_PASS_MISFIT=0
  // TOPOTRACK_TEST_BACKWARD_WEIGHT=0 TOPOTRACK_TEST_RETRACT=0). TOPOTRACK_TEST_STAGES=1 prints where the
  // error is after each stage: without the backward matches the pre-alignment leaves 11.3%, the
  // low-density pass 10.2% and the full graph 9.7% with 44% of the vertices still off the target
  // (the head and a hind leg that no normal ray reaches); with them 6.1%, 3.4% and 25% off.
  const Figures f = run_resampled("pcow", 1, 15);
  expect_improvement(f, 0.12);
  EXPECT_EQ(f.relax.iterations, kLargeMotionRelaxIterations);
  EXPECT_GT(last_coarse.nodes, 250);  // the mesh's 2,904 vertices give 137 nodes at four mean edge lengths
  EXPECT_TRUE(last_coarse.prealigned);
  EXPECT_TRUE(last_coarse.backward_all);
  EXPECT_GT(last_coarse.coarse_pass_iterations, 0);
  // Issue 4's 0.1%: measured 0.047% (0.041-0.049% over the five re-samplings; 0.061% with the paper's spacing,
  // 8 fine rounds; 0.052-0.103% over the five re-samplings, 0.047-0.088% from
  // alpha_reg 1000 to 0.1), 0.29% with the
  // paper's one fine round (TOPOTRACK_TEST_FINE_MAX_ROUNDS=1), 0.72% without the backward matches.
  EXPECT_LE(f.aligned.mean_target, 0.001);
}
// The rigid pre-alignment's principal-axes starts (RigidIcpParams::axes_win_ratio) on the pairs that decide them.
// pcow 57 -> 72 (the cow turned 102 degrees, 0.74 diagonals away) is lost from the identity and the centroids: a
// wrong pose, from which `align` ended 52 % of the diagonal from the truth (4.8 % from the axes' pose). It is found
// from the axes. At 33 -> 48 an axes end turned 150 degrees off the right pose fits the trimmed 80 % slightly better
// than the right pose, and the margin keeps the right one.
TEST(RealData, PcowRigidPreAlignmentTakesTheAxesStartsOnlyByAClearMargin) {
  TOPOTRACK_REQUIRE_DATA("pcow");
  const auto rigid_error = [](int frame, double ratio, RigidIcpReport& rep) {
    const test::AlignmentPair pair = test::make_pair("pcow", frame, 15);
    const TargetSurface target = TargetSurface::from_mesh(pair.target_mesh);
    SurfaceMesh mesh = pair.source.clone();
    RigidIcpParams params = CoarseParams{}.prealign;
    params.axes_win_ratio = ratio;
    rep = align_rigid(mesh, target, params);
    double e = 0;
    for (std::size_t v = 0; v < pair.truth.size(); ++v) e += (mesh.positions()[v] - pair.truth[v]).norm();
    return e / double(pair.truth.size()) / pair.diagonal;
  };
  RigidIcpReport rep;
  // Measured: 0.169 of the diagonal with the axes (the best rigid motion, from the truth: 0.173), 0.606 without.
  const double without = rigid_error(57, 0, rep);
  EXPECT_FALSE(rep.axes_won);
  const double with = rigid_error(57, RigidIcpParams{}.axes_win_ratio, rep);
  EXPECT_TRUE(rep.axes_won);
  EXPECT_EQ(rep.axes_starts, 4);
  EXPECT_LT(with, 0.25);
  EXPECT_GT(without, 0.4);
  // Measured: 0.156 (the centroids' end, trimmed distance 1.63 % of the diagonal) against the axes' 0.226 (1.55 %).
  const double tie = rigid_error(33, RigidIcpParams{}.axes_win_ratio, rep);
  std::printf("pcow rigid pre-alignment, error of the diagonal: 57 -> 72 %.4f (without the axes %.4f), 33 -> 48 %.4f\n",
              with, without, tie);
  EXPECT_FALSE(rep.axes_won);
  EXPECT_LT(tie, 0.2);
}
// The tracker's case: consecutive frames. The absolute convergence tests (step_tolerance,
// fit_tolerance) end the alpha_reg schedule early once nothing is left to fit.
TEST(RealData, SambaConsecutiveFrames) {
  TOPOTRACK_REQUIRE_DATA("samba");
  const Figures f = run_pair("samba", 1, 1);
  EXPECT_LE(f.aligned.mean_truth, f.unaligned.mean_truth);
  EXPECT_LE(f.aligned.mean_target, 0.001);
  // Measured 0: the nodes are found fitted before the first step (check_fit_first; truth error 0.0549%
  // of the diagonal, 0.0604% after the 3 rounds that ran before, 12 with the full alpha_reg schedule).
  EXPECT_LE(last_rounds, 6);
  EXPECT_EQ(last_coarse.coarse_pass_iterations, 0);  // misfit 0.02% of the diagonal: the paper's scheme
  EXPECT_FALSE(last_coarse.prealigned);
  EXPECT_FALSE(last_coarse.backward);
}
TEST(RealData, ElephantLargeMotion) {
  TOPOTRACK_REQUIRE_DATA("elephant");
  // Median 0.705% of 6.25% (2026-12-07, the relaxation on the target; 0.689-0.828% over the five re-samplings; distance
  // to the target 0.0036%, 0.0035-0.0044%). Median 0.856% of 6.25% (2026-12-03 after f19d070, with the vertices' fit, kLargeMotionVertexFitWeight; 0.795-0.936%
  // over the five re-samplings; distance to the target 0.022%, 0.021-0.028%; 0.864% before f19d070). Median 0.90% (2026-12-02, the pass at 4/9 of the full graph's density, kLargeMotionNearPassDensity;
  // 1.08% at a quarter, TOPOTRACK_TEST_NEAR_PASS_DENSITY=0; 1.20% without the guided pass, 5.04% without either
  // intrinsic stage, the figures below are at a quarter).
  // 1.08% (the full graph from alpha_reg 10 to 0.01; 1.11% from 1000 to 0.1),
  // with one guided low-density pass on the first pass's graph and the
  // intrinsic matches in the full graph; 1.41% without the guided pass (1.44% before), TOPOTRACK_TEST_INTRINSIC_PASSES=0;
  // 3.34% without either (3.42% before), TOPOTRACK_TEST_INTRINSIC=0 TOPOTRACK_TEST_INTRINSIC_PASSES=0, and 3.40% then with one
  // fine round), 3.88% at 78d1eea (3.09% at b4100c4, whose re-sampled targets differ; one re-sampling at
  // 0.8 before b4100c4: 3.41%; misfit 0.57%: the low-density
  // pass and backward matches at the pruned nodes, no pre-alignment); 4.27% without the backward matches
  // (TOPOTRACK_TEST_BACKWARD_WEIGHT=0;
  // 4.13% before the rotation retraction), 4.02% with them at every node
  // (TOPOTRACK_TEST_BACKWARD_ALL_MISFIT=0); 5.09% with the paper's scheme alone.
  // TOPOTRACK_TEST_STAGES=1 (without the backward matches): the median error is 0.56%, the mean is
  // the two legs that swing (feet 10% apart in the ground truth: 9-10% left after alignment, 9% of the
  // vertices landing on another part).
  const Figures f = run_resampled("elephant", 1, 15);
  expect_improvement(f, 0.2);  // issue 4's fifth: measured 0.113
  EXPECT_LE(f.aligned.mean_truth, 0.0080);
  EXPECT_EQ(f.relax.iterations, kLargeMotionRelaxIterations);
  EXPECT_GT(f.relax.coarse_nodes, 1000);  // the rest shape's graph at the paper's spacing: measured about 2,000
  EXPECT_EQ(last_coarse.intrinsic_passes, 1);  // the first pass left nodes misplaced (every re-sampling)
  EXPECT_GT(last_coarse.intrinsic_full_graph_misplaced, 0u);  // measured 11-31 nodes over the five re-samplings (14-65 at a quarter)
  EXPECT_FALSE(last_coarse.prealigned);
  EXPECT_TRUE(last_coarse.backward);
  EXPECT_FALSE(last_coarse.backward_all);
  EXPECT_GT(last_coarse.coarse_pass_iterations, 0);
  // Issue 4's 0.1%: measured 0.025% (0.022-0.029% over the five re-samplings; at a quarter 0.029%, 0.023-0.029%; 0.027%, 0.024-0.035%, from alpha_reg
  // 1000 to 0.1), 0.13% with one
  // fine round, 0.30% without the pass.
  EXPECT_LE(f.aligned.mean_target, 0.001);
}

}  // namespace
}  // namespace topotrack
