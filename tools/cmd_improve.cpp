// topotrack improve IN -o OUT [--edge-length L] [--events FILE] [--json]: ImproveMesh (§4.1) on one closed
// mesh, with the re-sampling events of §4.4.
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>

#include "io/event_file.hpp"
#include "io/obj_writer.hpp"
#include "kernels/improve/improve.hpp"
#include "kernels/mesh/mesh_convert.hpp"
#include "tools/cli_common.hpp"
#include "tools/commands.hpp"

namespace topotrack::cli {
namespace {

struct ImproveOptions {
  std::string input, output, events;
  ImproveParams params;
  bool json = false;
};

nlohmann::json to_json(const ImproveOptions& opt, std::size_t vertices_in, std::size_t vertices_out,
                       const ImproveReport& r) {
  const QualityStats& q = r.quality;
  nlohmann::json j;
  j["input"] = opt.input;
  j["output"] = opt.output;
  if (!opt.events.empty()) j["events"] = opt.events;
  j["vertices_in"] = vertices_in;
  j["vertices_out"] = vertices_out;
  j["splits"] = r.splits;
  j["collapses"] = r.collapses;
  j["flips"] = r.flips;
  j["iterations"] = r.iterations;
  j["edge_length_bounds"] = {r.min_edge_length, r.max_edge_length};
  j["quality"] = {{"min_angle_deg", q.min_angle_deg},
                  {"share_below_10deg", q.share_below_10deg},
                  {"below_2deg", q.below_2deg},
                  {"min_dihedral_deg", q.min_dihedral_deg},
                  {"dihedral_below_45deg", q.dihedral_below_45deg},
                  {"edge_length", {{"min", q.edge_length.min}, {"mean", q.edge_length.mean}, {"max", q.edge_length.max}}}};
  j["seconds"] = {{"scan", r.seconds_scan},       {"split", r.seconds_split},
                  {"collapse", r.seconds_collapse}, {"bad_triangles", r.seconds_bad_triangles},
                  {"folds", r.seconds_folds},       {"finish", r.seconds_finish},
                  {"total", r.seconds}};
  return j;
}

void run_improve(const ImproveOptions& opt) {
  SurfaceMesh mesh = load_surface_mesh(opt.input, /*require_closed=*/true);
  const std::size_t vertices_in = mesh.n_vertices();
  EventList events;
  const ImproveReport r = improve_mesh(mesh, opt.params, opt.events.empty() ? nullptr : &events);
  write_mesh(opt.output, to_mesh_data(mesh));
  if (!opt.events.empty()) write_events(opt.events, events);
  if (opt.json) {
    std::cout << to_json(opt, vertices_in, mesh.n_vertices(), r).dump(2) << "\n";
    return;
  }
  std::printf("%s: %zu -> %zu vertices, %zu splits, %zu collapses, %zu flips, min angle %.2f deg, %.3f s\n",
              opt.output.c_str(), vertices_in, mesh.n_vertices(), r.splits, r.collapses, r.flips,
              r.quality.min_angle_deg, r.seconds);
}

void add_improve_command(CLI::App& app) {
  auto opt = std::make_shared<ImproveOptions>();
  opt->params.measure_quality = true;  // the summary and the JSON report print it
  CLI::App* sub = app.add_subcommand("improve", "ImproveMesh (§4.1): split long edges, collapse short edges and "
                                                "edges of bad triangles or folds, flip where flat");
  sub->add_option("IN", opt->input, "closed mesh (OBJ or PLY)")->required();
  sub->add_option("-o,--output", opt->output, "output mesh (.ply keeps the vertex ids, .obj)")->required();
  sub->add_option("--edge-length", opt->params.target_edge_length,
                  "target edge length L (bounds L/sqrt(ratio), L*sqrt(ratio)); default: mean edge length")
      ->check(CLI::PositiveNumber);
  sub->add_option("--events", opt->events, "write the event list (§4.4) to this file");
  sub->add_flag("--json", opt->json, "print a JSON report instead of the one-line summary");
  sub->callback([opt] { run_improve(*opt); });
}

}  // namespace

TOPOTRACK_COMMAND(30, add_improve_command);

}  // namespace topotrack::cli
