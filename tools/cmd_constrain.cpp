// topotrack constrain MESH TARGET -o OUT [--events FILE] [--voxel-size H] [--json]: ConstrainTopology(M, Θ)
// of §4.3 on one closed mesh. TARGET is a closed mesh (Θ = its signed distance, CalculateSignedDistance) or
// a .vdb level set (the first float grid, its own voxels the cells).
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>
#include <openvdb/io/File.h>

#include "io/event_file.hpp"
#include "io/obj_writer.hpp"
#include "kernels/mesh/mesh_convert.hpp"
#include "kernels/mesh/mesh_queries.hpp"
#include "kernels/sdf/signed_distance.hpp"
#include "kernels/topology/constrain.hpp"
#include "tools/cli_common.hpp"
#include "tools/commands.hpp"

namespace topotrack::cli {
namespace {

struct ConstrainOptions {
  std::string input, target, output, events;
  double voxel_size = 0;  // 0: the mean edge length of MESH
  ConstrainParams params;
  bool json = false;
};

openvdb::FloatGrid::Ptr read_level_set(const std::filesystem::path& path) {
  ensure_openvdb_initialized();
  openvdb::FloatGrid::Ptr grid;
  try {
    openvdb::io::File file(path.string());
    file.open();
    for (auto it = file.beginName(); it != file.endName() && !grid; ++it)
      grid = openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid(it.gridName()));
    file.close();
  } catch (const openvdb::Exception& e) {
    TT_THROW(IoError, path.string() << ": " << e.what());
  }
  if (!grid) TT_THROW(InvalidInput, path.string() << ": no float grid");
  if (!grid->transform().isLinear()) TT_THROW(InvalidInput, path.string() << ": the grid's transform is not linear");
  return grid;
}

void run_constrain(const ConstrainOptions& opt) {
  SurfaceMesh mesh = load_surface_mesh(opt.input, /*require_closed=*/true);
  const std::size_t vertices_in = mesh.n_vertices();
  openvdb::FloatGrid::Ptr theta;
  double voxel = opt.voxel_size;
  std::string ext = std::filesystem::path(opt.target).extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  if (ext == ".vdb") {
    if (voxel > 0) TT_THROW(UsageError, "--voxel-size does not apply to a .vdb target (its voxels are the cells)");
    theta = read_level_set(opt.target);
    voxel = theta->voxelSize()[0];
  } else {
    const SurfaceMesh target = load_surface_mesh(opt.target, /*require_closed=*/true);
    if (voxel <= 0) voxel = mean_edge_length(mesh);
    theta = signed_distance(target, voxel, 3.0, /*exact_sign_band_voxels=*/0.25);  // as the tracker does
  }
  EventList events;
  const ConstrainReport r = constrain_topology(mesh, *theta, opt.params, opt.events.empty() ? nullptr : &events);
  write_mesh(opt.output, to_mesh_data(mesh));
  if (!opt.events.empty()) write_events(opt.events, events);
  if (opt.json) {
    nlohmann::json j;
    j["input"] = opt.input;
    j["target"] = opt.target;
    j["output"] = opt.output;
    if (!opt.events.empty()) j["events"] = opt.events;
    j["voxel_size"] = voxel;
    j["vertices_in"] = vertices_in;
    j["vertices_out"] = mesh.n_vertices();
    j["complex_cells"] = r.complex_cells;
    j["complex_by_reason"] = complex_reasons_json(r.cells_by_verdict);  // before any growth
    j["faces_removed"] = r.faces_removed;
    j["faces_added"] = r.faces_added;
    j["vertices_removed"] = r.vertices_removed;
    j["vertices_added"] = r.vertices_added;
    j["patches_created"] = r.patches_created;
    j["patches_deleted"] = r.patches_deleted;
    j["region_growth"] = r.region_growth;
    j["components"] = {r.components_before, r.components_after};
    j["genus_out"] = genus(mesh);
    j["events_recorded"] = events.size();
    j["seconds"] = {{"cut", r.seconds_cut},         {"classify", r.seconds_classify}, {"replace", r.seconds_replace},
                    {"events", r.seconds_events}, {"total", r.seconds_total}};
    std::cout << j.dump(2) << "\n";
    return;
  }
  std::printf("%s: %zu -> %zu vertices, %zu complex cells, components %d -> %d, genus %ld, %zu events, %.3f s\n",
              opt.output.c_str(), vertices_in, mesh.n_vertices(), r.complex_cells, r.components_before,
              r.components_after, genus(mesh), events.size(), r.seconds_total);
}

void add_constrain_command(CLI::App& app) {
  auto opt = std::make_shared<ConstrainOptions>();
  CLI::App* sub = app.add_subcommand(
      "constrain", "ConstrainTopology (§4.3): give MESH the topology of TARGET, resampling only where they differ");
  sub->add_option("MESH", opt->input, "closed mesh (OBJ or PLY)")->required();
  sub->add_option("TARGET", opt->target, "closed mesh (its signed distance is taken) or a .vdb level set")->required();
  sub->add_option("-o,--output", opt->output, "output mesh (.ply keeps the vertex ids, .obj)")->required();
  sub->add_option("--voxel-size", opt->voxel_size,
                  "voxel size of the signed distance of a mesh TARGET; default: mean edge length of MESH")
      ->check(CLI::PositiveNumber);
  sub->add_option("--events", opt->events, "write the event list (§4.4) to this file");
  sub->add_option("--max-region-growth", opt->params.max_region_growth,
                  "cell layers the replaced region may grow by when a stitch check fails")
      ->check(CLI::NonNegativeNumber);
  sub->add_flag("--json", opt->json, "print a JSON report instead of the one-line summary");
  sub->callback([opt] { run_constrain(*opt); });
}

}  // namespace

TOPOTRACK_COMMAND(47, add_constrain_command);

}  // namespace topotrack::cli
