// topotrack export FRAMES -o OUT: for hosts that demand a fixed vertex count, every stretch of frames with
// constant connectivity becomes a base mesh plus a PC2 point cache (Blender's Mesh Cache modifier reads it).
#include <cstdio>
#include <nlohmann/json.hpp>

#include "io/atomic_file.hpp"
#include "io/error.hpp"
#include "io/obj_writer.hpp"
#include "io/ply_writer.hpp"
#include "kernels/propagate/frame_geometry.hpp"
#include "io/pc2.hpp"
#include "tools/cli_common.hpp"
#include "tools/commands.hpp"

namespace topotrack::cli {
namespace {
namespace fs = std::filesystem;

struct ExportOptions {
  std::vector<std::string> inputs;
  std::string out;
  std::string format = "obj";
  double fps_scale = 1;
  bool quiet = false;
};

struct Stretch {
  std::size_t begin = 0, end = 0;  // frame indices [begin, end)
};

void run_export(const ExportOptions& opt) {
  if (opt.format != "obj" && opt.format != "ply") TT_THROW(UsageError, "--format must be obj or ply");
  const auto frames = resolve_frames(opt.inputs);
  const fs::path out(opt.out);
  ensure_directory(out);

  // Pass 1: where the connectivity changes.
  std::vector<Stretch> stretches;
  FrameGeometry prev;
  for (std::size_t k = 0; k < frames.size(); ++k) {
    FrameGeometry g = read_frame_file(frames[k].path, false).geometry;
    if (g.positions.empty()) TT_THROW(InvalidInput, frames[k].path.string() << ": no vertices");
    const bool same = k > 0 && g.positions.size() == prev.positions.size() &&
                      match_connectivity(prev.ids, prev.triangles, g.ids, g.triangles).has_value();
    if (!same) stretches.push_back({k, k});
    stretches.back().end = k + 1;
    prev = std::move(g);
    if (!opt.quiet) std::fprintf(stderr, "\rexport: scanned %zu/%zu frames", k + 1, frames.size());
  }
  if (!opt.quiet) std::fprintf(stderr, "\n");

  // Pass 2: a base mesh and a cache per stretch, vertices in the base mesh's order.
  const std::string name = sequence_name(frames[0].path);
  nlohmann::json list = nlohmann::json::array();
  for (const Stretch& s : stretches) {
    const FrameFile base_frame = read_frame_file(frames[s.begin].path, false);
    const MeshData& base_data = base_frame.data;
    const FrameGeometry& base = base_frame.geometry;
    const long first = frames[s.begin].number >= 0 ? frames[s.begin].number : long(s.begin);
    const long last = frames[s.end - 1].number >= 0 ? frames[s.end - 1].number : long(s.end - 1);
    char stem[256];
    std::snprintf(stem, sizeof stem, "%s.%04ld-%04ld", name.c_str(), first, last);
    const fs::path mesh_path = out / (std::string(stem) + "." + opt.format);
    const fs::path cache_path = out / (std::string(stem) + ".pc2");
    MeshData plain;
    plain.positions = base_data.positions;
    plain.triangles = base_data.triangles;
    if (opt.format == "obj")
      write_obj(mesh_path, plain);
    else
      write_ply(mesh_path, plain);
    Pc2Header h;
    h.points = std::int32_t(base.positions.size());
    h.start_frame = float(first);
    h.sample_rate = float(opt.fps_scale);
    h.samples = std::int32_t(s.end - s.begin);
    Pc2Writer writer(cache_path, h);
    std::vector<std::array<double, 3>> sample(base.positions.size());
    writer.add_sample(base_data.positions);
    for (std::size_t k = s.begin + 1; k < s.end; ++k) {
      const FrameFile f = read_frame_file(frames[k].path, false);
      const auto map = match_connectivity(base.ids, base.triangles, f.geometry.ids, f.geometry.triangles);
      if (!map) TT_THROW(InvalidInput, frames[k].path.string() << ": connectivity changed while exporting (file "
                                                                  "rewritten?)");
      for (std::size_t i = 0; i < sample.size(); ++i) sample[i] = f.data.positions[(*map)[i]];
      writer.add_sample(sample);
    }
    writer.commit();
    list.push_back({{"first_frame", first},
                    {"last_frame", last},
                    {"frames", s.end - s.begin},
                    {"vertices", base.positions.size()},
                    {"triangles", base.triangles.size()},
                    {"mesh", mesh_path.filename().string()},
                    {"cache", cache_path.filename().string()}});
  }
  const nlohmann::json manifest = {
      {"format", "PC2 point caches: char[12] POINTCACHE2\\0, int32 version 1, int32 points, float32 start frame, "
                 "float32 sample rate, int32 samples, then float32 x y z per point per sample"},
      {"usage", "import the mesh keeping vertex order, add a Mesh Cache modifier (format PC2) with the cache"},
      {"stretches", list}};
  write_file_atomic(out / "export.json", manifest.dump(2) + "\n");
  std::printf("export: %zu frames in %zu stretches of constant connectivity into %s\n", frames.size(),
              stretches.size(), out.string().c_str());
}

void add_export_command(CLI::App& app) {
  auto opt = std::make_shared<ExportOptions>();
  CLI::App* sub = app.add_subcommand(
      "export", "Export stretches of frames with constant connectivity as a base mesh plus a PC2 point cache "
                "(for hosts that need a fixed vertex count)");
  sub->add_option("FRAMES", opt->inputs, "frames (tracked output or any sequence)")->required();
  sub->add_option("-o,--output", opt->out, "output folder")->required();
  sub->add_option("--format", opt->format, "base mesh format: obj or ply")->capture_default_str();
  sub->add_option("--sample-rate", opt->fps_scale, "frames between cache samples (PC2 header)")->capture_default_str();
  sub->add_flag("-q,--quiet", opt->quiet, "no progress line");
  sub->callback([opt] { run_export(*opt); });
}

}  // namespace

TOPOTRACK_COMMAND(110, add_export_command);

}  // namespace topotrack::cli
