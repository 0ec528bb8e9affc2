#include "tools/cli_common.hpp"
#include <algorithm>
#include <cctype>
#include <iostream>

#include "io/error.hpp"
#include "io/mesh_reader.hpp"
#include "io/sequence.hpp"
#include "kernels/mesh/mesh_convert.hpp"
#include "kernels/mesh/mesh_queries.hpp"

namespace topotrack::cli {
namespace fs = std::filesystem;

std::vector<InputFrame> resolve_inputs(const std::vector<std::string>& inputs, std::vector<std::string>* warnings) {
  std::vector<InputFrame> frames;
  for (const std::string& in : inputs) {
    std::error_code ec;
    if (fs::is_regular_file(in, ec)) {
      frames.push_back({fs::path(in), -1});
      continue;
    }
    const FrameSequence seq = find_frames(in);
    for (const auto& f : seq.frames) frames.push_back({f.path, f.number});
    if (warnings) warnings->insert(warnings->end(), seq.warnings.begin(), seq.warnings.end());
  }
  return frames;
}

std::vector<InputFrame> resolve_frames(const std::vector<std::string>& inputs) {
  std::vector<std::string> warnings;
  std::vector<InputFrame> frames = resolve_inputs(inputs, &warnings);
  for (const auto& w : warnings) std::cerr << "topotrack: warning: " << w << "\n";
  if (frames.empty()) TT_THROW(InvalidInput, "no frames");
  return frames;
}

std::vector<TrackedFrame> resolve_tracked_frames(const std::vector<std::string>& inputs) {
  std::vector<fs::path> paths;
  std::vector<long> numbers;
  for (const auto& f : resolve_frames(inputs)) {
    paths.push_back(f.path);
    numbers.push_back(f.number);
  }
  return tracked_frames(paths, numbers);
}

std::string sequence_name(const fs::path& first) {
  std::string s = first.stem().string();
  while (!s.empty() && (std::isdigit(static_cast<unsigned char>(s.back())) || s.back() == '.' || s.back() == '_' ||
                        s.back() == '-'))
    s.pop_back();
  return s.empty() ? "frame" : s;
}

MeshData load_mesh_data(const fs::path& path) { return read_mesh(path); }

SurfaceMesh load_surface_mesh(const fs::path& path, bool require_closed) {
  const MeshData data = read_mesh(path);
  if (data.triangles.empty()) TT_THROW(InvalidInput, path.string() << ": no triangles");
  SurfaceMesh mesh;
  try {
    mesh = to_surface_mesh(data);
  } catch (const InvalidInput& e) {
    TT_THROW(InvalidInput, path.string() << ": " << e.what());
  }
  if (require_closed) {
    const std::size_t open = boundary_edge_count(mesh);
    if (open)
      TT_THROW(InvalidInput, path.string() << ": the surface is open (" << open
                                           << " boundary edges); a closed surface is required");
  }
  return mesh;
}

void ensure_directory(const fs::path& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir)) TT_THROW(IoError, dir.string() << ": cannot create folder: " << ec.message());
}

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

nlohmann::json complex_reasons_json(const topology::VerdictCounts& counts) {
  nlohmann::json j = nlohmann::json::object();
  for (int k = 1; k < topology::kVerdictKinds; ++k)
    if (counts[k] > 0) j[topology::verdict_name(topology::CellVerdict(k))] = counts[k];
  return j;
}

}  // namespace topotrack::cli
