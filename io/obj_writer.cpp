#include "io/obj_writer.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <functional>

#include "io/atomic_file.hpp"
#include "io/error.hpp"
#include "io/ply_writer.hpp"

namespace topotrack {

namespace {

constexpr std::size_t kFlushBytes = 1 << 20;

void check(const MeshData& mesh) {
  const std::size_t V = mesh.vertex_count();
  for (std::size_t v = 0; v < V; ++v)
    for (double x : mesh.positions[v])
      if (!std::isfinite(x))
        TT_THROW(InvalidInput, "OBJ output: vertex " << v << " has a non-finite coordinate");
  for (std::size_t f = 0; f < mesh.triangle_count(); ++f)
    for (std::int64_t i : mesh.triangles[f])
      if (i < 0 || static_cast<std::size_t>(i) >= V)
        TT_THROW(InvalidInput, "OBJ output: triangle " << f << " has vertex index " << i << " out of range ("
                                                       << V << " vertices)");
}

// Shortest decimal that reads back to the same double, so OBJ round trips are exact.
template <class T>
void number(std::string& s, T v) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  s.append(buf, r.ptr);
}

void encode(const MeshData& mesh, const std::function<void(std::string_view)>& emit) {
  check(mesh);
  std::string block = "# written by topotrack: " + std::to_string(mesh.vertex_count()) + " vertices, " +
                      std::to_string(mesh.triangle_count()) + " triangles\n";
  auto flush_if_full = [&] {
    if (block.size() >= kFlushBytes) {
      emit(block);
      block.clear();
    }
  };
  for (const auto& x : mesh.positions) {
    block += 'v';
    for (double c : x) {
      block += ' ';
      number(block, c);
    }
    block += '\n';
    flush_if_full();
  }
  for (const auto& t : mesh.triangles) {
    block += 'f';
    for (std::int64_t i : t) {
      block += ' ';
      number(block, i + 1);
    }
    block += '\n';
    flush_if_full();
  }
  emit(block);
}

}  // namespace

std::string encode_obj(const MeshData& mesh) {
  std::string out;
  encode(mesh, [&out](std::string_view s) { out.append(s); });
  return out;
}

void write_obj(const std::filesystem::path& path, const MeshData& mesh) {
  try {
    write_file_atomic(path,
                      [&](AtomicFileWriter& w) { encode(mesh, [&w](std::string_view s) { w.write(s); }); });
  } catch (const InvalidInput& e) {
    TT_THROW(InvalidInput, path.string() << ": " << e.what());
  }
}

void write_mesh(const std::filesystem::path& path, const MeshData& mesh) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  if (ext == ".ply") return write_ply(path, mesh);
  if (ext == ".obj") return write_obj(path, mesh);
  TT_THROW(InvalidInput, path.string()
                             << ": unknown mesh format '" << ext << "' for writing (expected .obj or .ply)");
}

}  // namespace topotrack
