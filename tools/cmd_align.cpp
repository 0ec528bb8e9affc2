// topotrack align SOURCE TARGET -o OUT: deform SOURCE onto TARGET by the non-rigid alignment of §4.2
// (coarse deformation graph, then fine per-vertex), or by one stage alone, or by the naive
// closest-point projection of the paper's Fig. 9. OUT keeps SOURCE's vertices, order and ids.
#include <cstdio>
#include <initializer_list>
#include <optional>
#include <span>
#include <utility>
#include <iostream>
#include <nlohmann/json.hpp>

#include "engine/profile.hpp"
#include "io/obj_writer.hpp"
#include "kernels/mesh/mesh_convert.hpp"
#include "kernels/registration/coarse.hpp"
#include "kernels/registration/fine.hpp"
#include "kernels/registration/large_motion.hpp"
#include "kernels/registration/projection.hpp"
#include "tools/cli_common.hpp"
#include "tools/commands.hpp"
#include "tools/heap.hpp"

namespace topotrack::cli {
namespace {

struct AlignOptions {
  std::string source, target, output;
  bool coarse_only = false, fine_only = false, projection_only = false, json = false, no_large_motion = false;
  std::optional<double> graph_density, sigma;  // over the profile's when given
  std::string profile = "default";
  std::vector<std::string> settings;
};

// The coarse and fine parameters of the profile, with --set overrides and the stage options on top.
TrackerParams align_params(const AlignOptions& opt) {
  TrackerParams params = load_profile(opt.profile);
  if (!opt.no_large_motion) use_large_motion_alignment(params.coarse_params, params.fine_params);
  for (const auto& s : opt.settings) apply_setting(params, s);
  if (opt.graph_density) params.coarse_params.graph_density = *opt.graph_density;
  if (opt.sigma) params.fine_params.sigma = *opt.sigma;
  if (opt.no_large_motion) {
    params.coarse_params.prealign_misfit = 0;
    params.coarse_params.coarse_pass_misfit = 0;
    params.coarse_params.backward_weight = 0;
  }
  validate(params);
  return params;
}

TargetSurface load_target(const std::string& path) {
  const MeshData data = load_mesh_data(path);
  const std::vector<Vec3> positions = positions_of(data);
  std::vector<std::array<Index, 3>> triangles(data.triangles.size());
  for (std::size_t f = 0; f < triangles.size(); ++f)
    for (int c = 0; c < 3; ++c) {
      const std::int64_t v = data.triangles[f][c];
      if (v < 0 || std::uint64_t(v) >= positions.size())
        TT_THROW(InvalidInput, path << ": triangle " << f << " has a vertex index out of range");
      triangles[f][c] = Index(v);
    }
  try {
    return TargetSurface(positions, triangles);
  } catch (const InvalidInput& e) {
    TT_THROW(InvalidInput, path << ": " << e.what());
  }
}

// A stage's report as JSON: its figures plus "seconds" per phase.
nlohmann::json stage_json(nlohmann::json figures, std::initializer_list<std::pair<const char*, double>> seconds) {
  for (const auto& [phase, value] : seconds) figures["seconds"][phase] = value;
  return figures;
}

// One graph's rounds by phase (the low-density passes', the denser graph's).
nlohmann::json phases_json(const CoarsePhases& p) {
  return stage_json({{"nodes", p.nodes}, {"rounds", p.rounds}, {"pcg_iterations", p.pcg_iterations}, {"factorisations", p.factorisations}},
                    {{"graph", p.seconds_graph},
                     {"correspondences", p.seconds_correspondences},
                     {"assembly", p.seconds_assembly},
                     {"factorisation", p.seconds_factorisation},
                     {"solve", p.seconds_solve},
                     {"total", p.seconds_total}});
}

nlohmann::json run_coarse(SurfaceMesh& mesh, const TargetSurface& target, const CoarseParams& p) {
  const CoarseReport r = align_coarse(mesh, target, p);
  nlohmann::json rounds = nlohmann::json::array();
  for (const CoarseRound& c : r.rounds)
    rounds.push_back({{"alpha_reg", c.alpha_reg},
                      {"energy_before", c.energy_before},
                      {"energy", c.energy},
                      {"motion", c.motion},
                      {"step", c.step},
                      {"fit_distance", c.fit_distance},
                      {"pcg_iterations", c.pcg_iterations},
                      {"correspondences", c.correspondences}});
  return stage_json({{"nodes", r.nodes},
                     {"graph_edges", r.graph_edges},
                     {"fitted_vertices", r.fitted_vertices},
                     {"iterations", r.iterations},
                     {"levels", r.levels},
                     {"pcg_iterations", r.pcg_iterations},
                     {"alpha_reg_end", r.alpha_reg_end},
                     {"correspondences", r.correspondences},
                     {"pruned", {{"no_hit", r.pruned_no_hit}, {"normal", r.pruned_normal}, {"distance", r.pruned_distance}}},
                     {"mean_fit_distance", r.mean_fit_distance},
                     {"energy_start", r.energy_start},
                     {"energy_end", r.energy_end},
                     {"misfit_start", r.misfit_start},
                     {"coarse_pass_iterations", r.coarse_pass_iterations},
                     {"intrinsic_passes", r.intrinsic_passes},
                     {"intrinsic_misplaced", r.intrinsic_full_graph_misplaced},
                     {"backward", r.backward},
                     {"backward_all", r.backward_all},
                     {"backward_at_vertices", r.backward_at_vertices},
                     {"fitted_at_start", r.fitted_at_start},
                     {"prealign", {{"applied", r.prealigned},
                                   {"iterations", r.prealign.iterations},
                                   {"axes_starts", r.prealign.axes_starts},
                                   {"axes_won", r.prealign.axes_won},
                                   {"distance_start", r.prealign.distance_start},
                                   {"distance_end", r.prealign.distance_end}}},
                     {"low_density", phases_json(r.low_density)},
                     {"dense", phases_json(r.dense)},
                     {"rounds", rounds}},
                    {{"prealign", r.seconds_prealign},
                     {"intrinsic", r.seconds_intrinsic},
                     {"graph", r.seconds_graph},
                     {"correspondences", r.seconds_correspondences},
                     {"assembly", r.seconds_assembly},
                     {"factorisation", r.seconds_factorisation},
                     {"solve", r.seconds_solve},
                     {"total", r.seconds_total}});
}

nlohmann::json run_fine(SurfaceMesh& mesh, const TargetSurface& target, const FineParams& p, std::span<const Vec3> rest) {
  const FineReport r = align_fine(mesh, target, p, rest);
  const RelaxReport& x = r.relax;
  return stage_json({{"cg_iterations", r.cg_iterations},
                     {"rounds", r.rounds},
                     {"mean_residual", r.mean_residual},
                     {"correspondences", r.correspondences},
                     {"pruned", r.pruned},
                     {"residual", r.residual},
                     {"energy_start", r.energy_start},
                     {"energy_end", r.energy_end},
                     {"relax", stage_json({{"iterations", x.iterations},
                                           {"cg_iterations", x.cg_iterations},
                                           {"energy_start", x.energy_start},
                                           {"energy_end", x.energy_end},
                                           {"mean_distance", x.mean_distance}},
                                          {{"setup", x.seconds_setup},
                                           {"closest", x.seconds_closest},
                                           {"rotations", x.seconds_rotations},
                                           {"solve", x.seconds_solve},
                                           {"total", x.seconds_total}})}},
                    {{"raycast", r.seconds_raycast},
                     {"assembly", r.seconds_assembly},
                     {"solve", r.seconds_solve},
                     {"relax", x.seconds_total},
                     {"total", r.seconds_total}});
}

void run_align(const AlignOptions& opt) {
  keep_freed_memory();
  if (int(opt.coarse_only) + int(opt.fine_only) + int(opt.projection_only) > 1)
    TT_THROW(UsageError, "align: --coarse-only, --fine-only and --projection-only exclude each other");
  const TrackerParams params = align_params(opt);
  SurfaceMesh mesh = load_surface_mesh(opt.source);
  const TargetSurface target = load_target(opt.target);
  nlohmann::json j;
  j["source"] = opt.source;
  j["target"] = opt.target;
  j["output"] = opt.output;
  j["vertices"] = mesh.n_vertices();
  if (opt.projection_only) {
    project_to_closest(mesh, target);
    j["mode"] = "projection";
  } else {
    j["mode"] = opt.coarse_only ? "coarse" : opt.fine_only ? "fine" : "coarse+fine";
    const std::vector<Vec3> rest = mesh.positions();  // the source's shape, which the relaxation slides back towards
    if (!opt.fine_only) j["coarse"] = run_coarse(mesh, target, params.coarse_params);
    if (!opt.coarse_only) j["fine"] = run_fine(mesh, target, params.fine_params, rest);
  }
  const std::filesystem::path out(opt.output);
  if (out.has_parent_path()) ensure_directory(out.parent_path());
  write_mesh(out, to_mesh_data(mesh));
  if (opt.json) {
    std::cout << j.dump(2) << "\n";
    return;
  }
  std::printf("%s -> %s: %s, %zu vertices", opt.source.c_str(), opt.output.c_str(),
              j["mode"].get<std::string>().c_str(), mesh.n_vertices());
  if (j.contains("coarse"))
    std::printf("; coarse %d nodes, %d rounds%s, %.3f s", j["coarse"]["nodes"].get<int>(),
                j["coarse"]["iterations"].get<int>(),
                j["coarse"]["prealign"]["applied"].get<bool>() ? " after a rigid pre-alignment" : "",
                j["coarse"]["seconds"]["total"].get<double>());
  if (j.contains("fine"))
    std::printf("; fine %zu matched, %zu pruned%s, %.3f s", j["fine"]["correspondences"].get<std::size_t>(),
                j["fine"]["pruned"].get<std::size_t>(), j["fine"]["relax"]["iterations"].get<int>() > 0 ? ", relaxed on the target" : "",
                j["fine"]["seconds"]["total"].get<double>());
  std::printf("\n");
}

void add_align_command(CLI::App& app) {
  auto opt = std::make_shared<AlignOptions>();
  CLI::App* sub = app.add_subcommand("align", "Deform SOURCE onto TARGET by non-rigid alignment (§4.2); OUT keeps "
                                              "SOURCE's vertices, order and ids");
  sub->add_option("SOURCE", opt->source, "closed mesh to deform (OBJ, PLY)")->required();
  sub->add_option("TARGET", opt->target, "target surface (OBJ, PLY)")->required();
  sub->add_option("-o,--output", opt->output, "output mesh (.ply keeps ids, .obj)")->required();
  sub->add_flag("--coarse-only", opt->coarse_only, "only the coarse deformation-graph stage");
  sub->add_flag("--fine-only", opt->fine_only, "only the fine per-vertex stage");
  sub->add_flag("--projection-only", opt->projection_only,
                "the naive baseline (Fig. 9): move each vertex to its closest point on TARGET");
  sub->add_option("--graph-density", opt->graph_density,
                  "deformation-graph node density relative to the paper's (1, 0.5, 0.25: fast preview)")
      ->check(CLI::Range(1e-3, 1.0));
  sub->add_flag("--no-large-motion", opt->no_large_motion,
                "the paper's scheme alone: no rigid pre-alignment, no low-density first pass, no backward matches, no intrinsic matches, one fine round, no relaxation");
  sub->add_option("--sigma", opt->sigma, "fine-stage pruning distance, fraction of the bbox diagonal")
      ->check(CLI::PositiveNumber);
  sub->add_option("--profile", opt->profile, "bundled profile name or a .json file (default: the paper's values)");
  sub->add_option("--set", opt->settings, "override one coarse.* or fine.* parameter, e.g. --set coarse.alpha_reg_start=100");
  sub->add_flag("--json", opt->json, "print the stage reports as JSON (with the coarse rounds)");
  sub->callback([opt] { run_align(*opt); });
}

}  // namespace

TOPOTRACK_COMMAND(45, add_align_command);

}  // namespace topotrack::cli
