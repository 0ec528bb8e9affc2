#include "kernels/gen/gen_sequence.hpp"

#include <chrono>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "io/atomic_file.hpp"
#include "io/error.hpp"
#include "io/mesh_reader.hpp"
#include "io/ply_writer.hpp"
#include "io/sequence.hpp"
#include "kernels/gen/resurface.hpp"
#include "kernels/gen/synthetic.hpp"
#include "kernels/mesh/mesh_convert.hpp"
#include "kernels/mesh/mesh_queries.hpp"

namespace topotrack {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

std::string numbered(const std::string& prefix, int n, const std::string& ext) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%04d", n);
  return prefix + buf + ext;
}

// Count and check: a generated frame must be a closed 2-manifold (from_triangles + validate throw otherwise).
void measure(const MeshData& mesh, GenFrameReport& r) {
  r.vertices = mesh.vertex_count();
  r.triangles = mesh.triangle_count();
  if (mesh.triangles.empty()) return;
  SurfaceMesh s = to_surface_mesh(mesh);
  s.validate(true);
  r.components = long(connected_components(s));
  r.genus = genus(s);
}

void ensure_dir(const fs::path& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir)) TT_THROW(IoError, dir.string() << ": cannot create folder: " << ec.message());
}

nlohmann::json frames_json(const GenReport& report) {
  nlohmann::json a = nlohmann::json::array();
  for (const auto& f : report.frames) {
    nlohmann::json j{{"frame", f.frame},        {"file", f.file},     {"vertices", f.vertices},
                     {"triangles", f.triangles}, {"components", f.components}, {"genus", f.genus},
                     {"seconds", f.seconds}};
    if (!f.source_file.empty()) {
      j["source"] = f.source_file;
      j["voids_filled"] = f.voids_filled;
    }
    a.push_back(j);
  }
  return a;
}

// The file name of a source frame without its frame number and extension: "samba.0001.ply" -> "samba.".
std::string stem_prefix(const fs::path& p) {
  std::string s = p.stem().string();
  while (!s.empty() && std::isdigit(static_cast<unsigned char>(s.back()))) s.pop_back();
  return s.empty() ? "frame." : s;
}

GenReport generate_synthetic(const GenParams& params, const fs::path& dir, nlohmann::json& info) {
  SyntheticParams sp;
  sp.kind = synthetic_kind_from_name(params.kind);
  sp.frames = params.frames == 0 ? 60 : params.frames;
  sp.resolution = params.resolution;
  sp.seed = params.seed;
  const SyntheticScene scene(sp);
  GenReport report;
  report.kind = params.kind;
  report.resolution = scene.resolution();
  report.voxel_size = scene.voxel_size();
  const std::string prefix = params.kind + ".";
  if (params.last_frame < 0) TT_THROW(InvalidInput, params.kind << ": last frame must be >= 0, got " << params.last_frame);
  const int last = params.last_frame > 0 ? std::min(params.last_frame, scene.frames()) : scene.frames();
  for (int n = 1; n <= last; ++n) {
    const auto t0 = Clock::now();
    GenFrameReport r;
    r.frame = n;
    r.file = numbered(prefix, n, ".ply");
    const MeshData mesh = scene.frame_mesh(n);
    measure(mesh, r);
    write_ply(dir / r.file, mesh);
    r.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
    report.frames.push_back(r);
    if (params.progress) params.progress(r, last);
  }
  const std::string truth = scene.ground_truth().dump(1);
  write_file_atomic(dir / "ground_truth.json", truth);
  info["ground_truth"] = "ground_truth.json";
  info["bounding_box"] = {{"min", {scene.box().min.x(), scene.box().min.y(), scene.box().min.z()}},
                          {"max", {scene.box().max.x(), scene.box().max.y(), scene.box().max.z()}}};
  return report;
}

GenReport generate_resurface(const GenParams& params, const fs::path& dir, nlohmann::json& info) {
  if (params.source.empty()) TT_THROW(UsageError, "resurface needs a source sequence");
  if (params.every < 1) TT_THROW(InvalidInput, "resurface: --every must be >= 1, got " << params.every);
  if (params.frames < 0) TT_THROW(InvalidInput, "resurface: --frames must be >= 0, got " << params.frames);
  const int resolution = params.resolution == 0 ? 128 : params.resolution;
  if (resolution < 8 || resolution > 4096)
    TT_THROW(InvalidInput, "resurface: resolution must be in [8, 4096], got " << params.resolution);
  for (const double o : params.grid_offset)
    if (!(o >= 0 && o < 1)) TT_THROW(InvalidInput, "resurface: a grid offset must be in [0, 1) voxels, got " << o);
  const FrameSequence seq = find_frames(params.source);
  std::vector<SequenceFrame> chosen;
  for (const auto& f : seq.frames) {
    if (params.start >= 0 && f.number >= 0 && f.number < params.start) continue;
    chosen.push_back(f);
  }
  {
    std::vector<SequenceFrame> strided;
    for (std::size_t i = 0; i < chosen.size(); i += std::size_t(params.every)) strided.push_back(chosen[i]);
    chosen.swap(strided);
  }
  if (params.frames > 0 && chosen.size() > std::size_t(params.frames)) chosen.resize(std::size_t(params.frames));
  if (chosen.empty()) TT_THROW(InvalidInput, params.source << ": no source frame from frame " << params.start);

  GenReport report;
  report.kind = "resurface";
  report.resolution = resolution;
  const fs::path truth_dir = dir / "ground_truth";
  ensure_dir(truth_dir);
  const int total = int(chosen.size());
  for (int n = 1; n <= total; ++n) {
    const auto t0 = Clock::now();
    const fs::path& src = chosen[std::size_t(n - 1)].path;
    const MeshData source = read_mesh(src);
    if (n == 1) {
      BoundingBox box;
      for (const auto& p : source.positions) box.extend(Vec3(p[0], p[1], p[2]));
      if (box.empty()) TT_THROW(InvalidInput, src.string() << ": no vertices");
      report.voxel_size = (box.max - box.min).maxCoeff() / resolution;
      if (!(report.voxel_size > 0)) TT_THROW(InvalidInput, src.string() << ": degenerate bounding box");
    }
    GenFrameReport r;
    r.frame = n;
    r.file = numbered("resurface.", n, ".ply");
    r.source_file = src.string();
    MeshData mesh;
    try {
      ResurfaceParams rp;
      rp.voxel_size = report.voxel_size;
      rp.origin = report.voxel_size * Vec3(params.grid_offset[0], params.grid_offset[1], params.grid_offset[2]);
      ResurfaceReport rr;
      mesh = resurface(source, rp, &rr);
      r.voids_filled = rr.voids_filled + rr.islands_removed;
    } catch (const InvalidInput& e) {
      TT_THROW(InvalidInput, src.string() << ": " << e.what());
    }
    measure(mesh, r);
    write_ply(dir / r.file, mesh);
    std::error_code ec;
    const fs::path copy = truth_dir / numbered(stem_prefix(src), n, src.extension().string());
    fs::copy_file(src, copy, fs::copy_options::overwrite_existing, ec);
    if (ec) TT_THROW(IoError, copy.string() << ": cannot copy " << src.string() << ": " << ec.message());
    r.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
    report.frames.push_back(r);
    if (params.progress) params.progress(r, total);
  }
  info["source"] = params.source;
  info["start"] = params.start;
  info["every"] = params.every;
  info["grid_origin"] = {report.voxel_size * params.grid_offset[0], report.voxel_size * params.grid_offset[1],
                         report.voxel_size * params.grid_offset[2]};
  info["ground_truth"] = "ground_truth/";
  if (!seq.warnings.empty()) info["source_warnings"] = seq.warnings;
  return report;
}

}  // namespace

GenReport generate_sequence(const GenParams& params, const fs::path& dir) {
  const auto t0 = Clock::now();
  if (params.kind != "resurface") synthetic_kind_from_name(params.kind);  // UsageError before touching DIR
  if (params.kind != "resurface" && params.grid_offset != std::array<double, 3>{0, 0, 0})
    TT_THROW(UsageError, "gen " << params.kind << ": --grid-offset is for resurface (the synthetic kinds' grids are at 0)");
  ensure_dir(dir);
  nlohmann::json info;
  GenReport report = params.kind == "resurface" ? generate_resurface(params, dir, info)
                                                : generate_synthetic(params, dir, info);
  report.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  info["kind"] = report.kind;
  info["frame_count"] = report.frames.size();
  info["first_frame"] = 1;
  info["pattern"] = report.kind + ".%04d.ply";
  info["resolution"] = report.resolution;
  info["voxel_size"] = report.voxel_size;
  info["seed"] = params.seed;
  info["frames"] = frames_json(report);
  info["seconds"] = report.seconds;
  write_file_atomic(dir / "gen.json", info.dump(1));
  return report;
}

}  // namespace topotrack
