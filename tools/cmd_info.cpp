// topotrack info INPUT... [--json]: per frame the counts, topology, closedness and quality of a mesh.
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>

#include "kernels/mesh/mesh_convert.hpp"
#include "kernels/mesh/soup_stats.hpp"
#include "kernels/sdf/extraction_grid.hpp"
#include "tools/cli_common.hpp"
#include "tools/commands.hpp"

namespace topotrack::cli {
namespace {

struct InfoOptions {
  std::vector<std::string> inputs;
  bool json = false;
};

//! The grid the frame was extracted on, spacing 0 when it was not (kernels/sdf/extraction_grid.hpp).
ExtractionGrid grid_of(const MeshData& mesh, const SoupStats& s) {
  return extraction_grid(positions_of(mesh), s.edge_length.mean).value_or(ExtractionGrid{});
}

nlohmann::json to_json(const InputFrame& f, const SoupStats& s, const ExtractionGrid& grid) {
  nlohmann::json j;
  j["file"] = f.path.string();
  if (f.number >= 0) j["frame"] = f.number;
  j["vertices"] = s.vertices;
  j["triangles"] = s.triangles;
  j["components"] = s.components;
  j["euler"] = s.euler;
  j["genus"] = s.genus >= 0 ? nlohmann::json(s.genus) : nlohmann::json();
  j["closed"] = s.closed;
  j["manifold"] = s.manifold;
  j["boundary_edges"] = s.boundary_edges;
  j["non_manifold_edges"] = s.non_manifold_edges;
  j["non_manifold_vertices"] = s.non_manifold_vertices;
  j["inconsistent_edges"] = s.inconsistent_edges;
  j["degenerate_triangles"] = s.degenerate_triangles;
  j["unreferenced_vertices"] = s.unreferenced_vertices;
  j["bbox"] = {{"min", {s.bbox.min.x(), s.bbox.min.y(), s.bbox.min.z()}},
               {"max", {s.bbox.max.x(), s.bbox.max.y(), s.bbox.max.z()}},
               {"diagonal", s.bbox.diagonal()}};
  j["edge_length"] = {{"min", s.edge_length.min}, {"mean", s.edge_length.mean}, {"median", s.edge_length.median},
                      {"max", s.edge_length.max}};
  j["min_angle_deg"] = s.min_angle_deg;
  j["share_min_angle_below_10deg"] = s.share_below_10deg;
  // tracker.extraction_grid: the lattice at half the spacing, through that origin.
  j["extraction_grid"] = grid.spacing > 0 ? nlohmann::json(grid.spacing) : nlohmann::json();
  j["extraction_grid_origin"] = grid.spacing > 0 ? nlohmann::json({grid.origin.x(), grid.origin.y(), grid.origin.z()})
                                                 : nlohmann::json();
  return j;
}

std::string status(const SoupStats& s) {
  std::string out;
  out += s.closed ? "closed" : "open(" + std::to_string(s.boundary_edges) + " bnd)";
  if (s.manifold) out += ",manifold";
  else {
    out += ",NON-MANIFOLD(";
    out += std::to_string(s.non_manifold_edges) + " e," + std::to_string(s.non_manifold_vertices) + " v";
    if (s.inconsistent_edges) out += "," + std::to_string(s.inconsistent_edges) + " flipped";
    out += ")";
  }
  if (s.degenerate_triangles) out += "," + std::to_string(s.degenerate_triangles) + " degenerate";
  return out;
}

void run_info(const InfoOptions& opt) {
  const auto frames = resolve_frames(opt.inputs);
  nlohmann::json all = nlohmann::json::array();
  if (!opt.json)
    std::printf("%-28s %9s %9s %5s %6s %5s  %-24s %10s %30s %8s %6s %10s\n", "file", "vertices", "triangles", "comp",
                "euler", "genus", "status", "bbox-diag", "edge length min/mean/max", "min-ang", "<10deg", "grid");
  for (const auto& f : frames) {
    const MeshData mesh = load_mesh_data(f.path);
    const SoupStats s = analyze_soup(mesh);
    const ExtractionGrid grid = grid_of(mesh, s);
    if (opt.json) {
      all.push_back(to_json(f, s, grid));
      continue;
    }
    char edges[64];
    std::snprintf(edges, sizeof edges, "%.4g/%.4g/%.4g", s.edge_length.min, s.edge_length.mean, s.edge_length.max);
    const std::string genus = s.genus >= 0 ? std::to_string(s.genus) : "-";
    char grid_text[32] = "-";
    if (grid.spacing > 0) std::snprintf(grid_text, sizeof grid_text, "%.7g", grid.spacing);  // origin: --json
    std::printf("%-28s %9zu %9zu %5zu %6ld %5s  %-24s %10.4g %30s %8.2f %5.1f%% %10s\n",
                f.path.filename().string().c_str(), s.vertices, s.triangles, s.components, s.euler, genus.c_str(),
                status(s).c_str(), s.bbox.diagonal(), edges, s.min_angle_deg, 100.0 * s.share_below_10deg, grid_text);
  }
  if (opt.json) std::cout << all.dump(2) << "\n";
}

}  // namespace

namespace {
void add_info_command(CLI::App& app) {
  auto opt = std::make_shared<InfoOptions>();
  CLI::App* sub = app.add_subcommand("info", "Print vertices, triangles, components, Euler characteristic, genus, "
                                             "closedness, bounding box and quality of each frame, and the spacing of the grid "
                                             "it was extracted on when its vertices lie on one (tracker.voxel_size)");
  sub->add_option("INPUT", opt->inputs, "mesh files (OBJ, PLY), folders, globs or frame patterns")->required();
  sub->add_flag("--json", opt->json, "machine-readable JSON instead of a table");
  sub->callback([opt] { run_info(*opt); });
}
}  // namespace

TOPOTRACK_COMMAND(10, add_info_command);

}  // namespace topotrack::cli
