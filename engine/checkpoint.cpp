#include "engine/checkpoint.hpp"

#include <cstring>
#include <string>

#include "io/atomic_file.hpp"
#include "io/error.hpp"
#include "io/mapped_file.hpp"
#include "kernels/mesh/mesh_convert.hpp"

namespace topotrack {
namespace {

constexpr char kMagic[8] = {'T', 'T', 'C', 'H', 'E', 'C', 'K', '1'};
constexpr std::uint32_t kVersion = 2;  // 2: the lattice's origin after the voxel size; 1 is read as origin 0

std::uint64_t fnv1a(const char* p, std::size_t n) {
  std::uint64_t h = 1469598103934665603ull;
  for (std::size_t i = 0; i < n; ++i) h = (h ^ std::uint8_t(p[i])) * 1099511628211ull;
  return h;
}

template <class T>
void put(std::string& out, const T& v) {
  out.append(reinterpret_cast<const char*>(&v), sizeof(T));
}

struct Reader {
  const char* p;
  std::size_t n, off = 0;
  const std::filesystem::path& path;
  template <class T>
  T get() {
    if (n - off < sizeof(T)) TT_THROW(InvalidInput, path.string() << ": checkpoint truncated at byte " << off);
    T v;
    std::memcpy(&v, p + off, sizeof(T));
    off += sizeof(T);
    return v;
  }
};

}  // namespace

void write_checkpoint(const std::filesystem::path& path, const Checkpoint& c) {
  std::vector<Vec3> pos;
  std::vector<std::array<Index, 3>> tris;
  std::vector<Vertex> verts;
  extract_triangles(c.mesh, pos, tris, &verts);
  std::string out;
  out.reserve(64 + pos.size() * 32 + tris.size() * 12);
  out.append(kMagic, 8);
  put(out, kVersion);
  put(out, std::int64_t(c.frame_number));
  put(out, std::int64_t(c.frame_index));
  put(out, c.target_edge_length);
  put(out, c.voxel_size);
  for (int a = 0; a < 3; ++a) put(out, c.lattice_origin[a]);
  put(out, std::uint64_t(c.mesh.next_id()));
  put(out, std::uint64_t(pos.size()));
  put(out, std::uint64_t(tris.size()));
  for (const Vec3& p : pos) {
    put(out, p.x());
    put(out, p.y());
    put(out, p.z());
  }
  for (Vertex v : verts) put(out, std::uint64_t(c.mesh.id(v)));
  for (const auto& t : tris) {
    put(out, t[0]);
    put(out, t[1]);
    put(out, t[2]);
  }
  put(out, fnv1a(out.data(), out.size()));
  write_file_atomic(path, out);
}

Checkpoint read_checkpoint(const std::filesystem::path& path) {
  const MappedFile file(path);
  Reader r{file.data(), file.size(), 0, path};
  if (file.size() < 8 + 8 || std::memcmp(file.data(), kMagic, 8) != 0)
    TT_THROW(InvalidInput, path.string() << ": not a topotrack checkpoint (bad magic)");
  const std::uint64_t stored_hash = [&] {
    std::uint64_t h;
    std::memcpy(&h, file.data() + file.size() - 8, 8);
    return h;
  }();
  if (fnv1a(file.data(), file.size() - 8) != stored_hash)
    TT_THROW(InvalidInput, path.string() << ": checkpoint is corrupt (hash mismatch)");
  r.off = 8;
  r.n = file.size() - 8;
  const auto version = r.get<std::uint32_t>();
  if (version != 1 && version != kVersion)
    TT_THROW(InvalidInput, path.string() << ": unsupported checkpoint version " << version);
  Checkpoint c;
  c.frame_number = long(r.get<std::int64_t>());
  c.frame_index = long(r.get<std::int64_t>());
  c.target_edge_length = r.get<double>();
  c.voxel_size = r.get<double>();
  if (version >= 2) {
    for (int a = 0; a < 3; ++a) c.lattice_origin[a] = r.get<double>();
    if (!c.lattice_origin.allFinite()) TT_THROW(InvalidInput, path.string() << ": checkpoint's lattice origin is not finite");
  }
  const auto next_id = r.get<std::uint64_t>();
  const auto nv = r.get<std::uint64_t>(), nf = r.get<std::uint64_t>();
  if (nv > (r.n - r.off) / 32 || nf > (r.n - r.off) / 12)
    TT_THROW(InvalidInput, path.string() << ": checkpoint counts exceed the file size");
  std::vector<Vec3> pos(nv);
  for (auto& p : pos) {
    const double x = r.get<double>(), y = r.get<double>(), z = r.get<double>();
    p = Vec3(x, y, z);
  }
  std::vector<VertexId> ids(nv);
  for (auto& id : ids) id = r.get<std::uint64_t>();
  std::vector<std::array<Index, 3>> tris(nf);
  for (auto& t : tris) {
    const Index a = r.get<std::uint32_t>(), b = r.get<std::uint32_t>(), d = r.get<std::uint32_t>();
    t = {a, b, d};
  }
  if (r.off != r.n) TT_THROW(InvalidInput, path.string() << ": checkpoint has trailing bytes");
  try {
    c.mesh = SurfaceMesh::from_triangles(pos, tris, ids);
  } catch (const InvalidInput& e) {
    TT_THROW(InvalidInput, path.string() << ": checkpoint mesh is broken: " << e.what());
  }
  c.mesh.set_next_id(next_id);
  return c;
}

}  // namespace topotrack
