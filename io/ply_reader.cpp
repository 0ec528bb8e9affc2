#include "io/ply_reader.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>

#include "io/mapped_file.hpp"
#include "io/ply_format.hpp"
#include "io/ply_source.hpp"

namespace topotrack {

namespace {

using namespace ply_detail;

// Where each vertex property goes.
struct Slot {
  enum Kind : std::uint8_t { Skip, Pos, Id, Attr } kind = Skip;
  std::uint8_t comp = 0;
  std::uint32_t attr = 0;
  float scale = 1;
};

struct VertexPlan {
  std::vector<Slot> slots;
  std::vector<VertexAttribute> attrs;
  bool has_ids = false;
};

struct Group {
  std::string name;
  std::vector<int> members;
  bool scale_ints = false;
};

float colour_scale(PlyScalar t) {
  if (t == PlyScalar::U8) return 1.0f / 255.0f;
  if (t == PlyScalar::U16) return 1.0f / 65535.0f;
  return 1.0f;
}

// Scalar property `n` of e that no slot claimed yet, or -1.
int free_scalar(const PlyElement& e, const std::vector<bool>& taken, const std::string& n) {
  const int i = e.find(n);
  return i >= 0 && !e.properties[i].is_list && !taken[i] ? i : -1;
}

// Attribute groups: fixed names first (colour, velocity, normal), then name_0..name_k, then singles.
std::vector<Group> vertex_groups(const PlyElement& e, std::vector<bool>& taken) {
  std::vector<Group> groups;
  auto try_group = [&](const std::string& name, std::vector<std::string> names, const std::string& optional,
                       bool scale) {
    Group g{name, {}, scale};
    for (const auto& n : names) {
      const int i = free_scalar(e, taken, n);
      if (i < 0) return;
      g.members.push_back(i);
    }
    if (const int i = free_scalar(e, taken, optional); !optional.empty() && i >= 0) g.members.push_back(i);
    for (int i : g.members) taken[i] = true;
    groups.push_back(std::move(g));
  };
  try_group("color", {"red", "green", "blue"}, "alpha", true);
  try_group("v", {"vx", "vy", "vz"}, "", false);
  try_group("normal", {"nx", "ny", "nz"}, "", false);
  for (std::size_t i = 0; i < e.properties.size(); ++i) {
    const std::string& n = e.properties[i].name;
    if (taken[i] || e.properties[i].is_list || n.size() < 3 || n.compare(n.size() - 2, 2, "_0") != 0)
      continue;
    const std::string base = n.substr(0, n.size() - 2);
    std::vector<std::string> names;
    for (int k = 0; free_scalar(e, taken, base + "_" + std::to_string(k)) >= 0; ++k)
      names.push_back(base + "_" + std::to_string(k));
    if (names.size() >= 2 && e.find(base) < 0) try_group(base, names, "", false);
  }
  for (std::size_t i = 0; i < e.properties.size(); ++i)
    if (!taken[i] && !e.properties[i].is_list) {
      taken[i] = true;
      groups.push_back(Group{e.properties[i].name, {static_cast<int>(i)}, false});
    }
  std::stable_sort(groups.begin(), groups.end(), [](const Group& a, const Group& b) {
    return *std::min_element(a.members.begin(), a.members.end()) <
           *std::min_element(b.members.begin(), b.members.end());
  });
  return groups;
}

VertexPlan plan_vertex(const PlyElement& e, const std::string& name) {
  VertexPlan plan;
  plan.slots.resize(e.properties.size());
  std::vector<bool> taken(e.properties.size(), false);
  const char* axes[3] = {"x", "y", "z"};
  for (std::uint8_t c = 0; c < 3; ++c) {
    const int i = free_scalar(e, taken, axes[c]);
    if (i < 0)
      TT_THROW(InvalidInput,
               name << ":" << e.line << ": element vertex has no scalar property '" << axes[c] << "'");
    plan.slots[i] = Slot{Slot::Pos, c, 0, 1};
    taken[i] = true;
  }
  if (const int i = free_scalar(e, taken, "id"); i >= 0) {
    plan.slots[i].kind = Slot::Id;
    taken[i] = true;
    plan.has_ids = true;
  }
  for (const Group& g : vertex_groups(e, taken)) {
    const auto a = static_cast<std::uint32_t>(plan.attrs.size());
    plan.attrs.push_back(VertexAttribute{g.name, static_cast<int>(g.members.size()), {}});
    for (std::size_t c = 0; c < g.members.size(); ++c) {
      const PlyScalar t = e.properties[g.members[c]].type;
      plan.slots[g.members[c]] =
          Slot{Slot::Attr, static_cast<std::uint8_t>(c), a, g.scale_ints ? colour_scale(t) : 1.0f};
    }
  }
  return plan;
}

void allocate(const PlyElement& e, VertexPlan& plan, MeshData& mesh) {
  mesh.positions.resize(e.count);
  if (plan.has_ids) mesh.ids.emplace(e.count);
  for (auto& a : plan.attrs) a.values.resize(e.count * static_cast<std::size_t>(a.width));
}

template <class Src>
void read_vertices(Src& src, const PlyElement& e, VertexPlan& plan, MeshData& mesh) {
  allocate(e, plan, mesh);
  for (std::uint64_t v = 0; v < e.count; ++v) {
    src.at.record = v;
    std::array<double, 3> x{};
    for (std::size_t k = 0; k < e.properties.size(); ++k) {
      const PlyProperty& p = e.properties[k];
      const Slot s = plan.slots[k];
      if (p.is_list) {
        src.skip(p.type, src.list_count(p.count_type));
        continue;
      }
      switch (s.kind) {
        case Slot::Skip:
          src.skip(p.type, 1);
          break;
        case Slot::Pos:
          x[s.comp] = src.scalar(p.type);
          if (!std::isfinite(x[s.comp]))
            src.fail("non-finite vertex coordinate in vertex " + std::to_string(v));
          break;
        case Slot::Id:
          (*mesh.ids)[v] = src.integer(p.type);
          break;
        case Slot::Attr: {
          VertexAttribute& a = plan.attrs[s.attr];
          a.values[v * static_cast<std::size_t>(a.width) + s.comp] =
              static_cast<float>(src.scalar(p.type)) * s.scale;
          break;
        }
      }
    }
    mesh.positions[v] = x;
  }
}

// Binary vertex records of fixed size: one bounds check for the whole element, then plain loads.
template <bool Swap>
void read_vertices_fixed(BinarySource<Swap>& src, const PlyElement& e, VertexPlan& plan, MeshData& mesh) {
  const std::size_t stride = e.fixed_stride();
  if (e.count > src.remaining() / stride) {
    src.at.record = src.remaining() / stride;
    src.truncated(src.offset() + src.at.record * stride);
  }
  allocate(e, plan, mesh);
  std::vector<std::size_t> offset(e.properties.size());
  std::size_t o = 0, pos_offset[3] = {0, 0, 0};
  PlyScalar pos_type[3] = {PlyScalar::F32, PlyScalar::F32, PlyScalar::F32};
  for (std::size_t k = 0; k < e.properties.size(); ++k) {
    offset[k] = o;
    if (plan.slots[k].kind == Slot::Pos) {
      pos_offset[plan.slots[k].comp] = o;
      pos_type[plan.slots[k].comp] = e.properties[k].type;
    }
    o += ply_scalar_size(e.properties[k].type);
  }
  const int px = e.find("x");
  const bool packed_xyz = !Swap && e.properties[px].type == PlyScalar::F32 && e.find("y") == px + 1 &&
                          e.find("z") == px + 2 && e.properties[px + 1].type == PlyScalar::F32 &&
                          e.properties[px + 2].type == PlyScalar::F32;
  std::vector<std::size_t> extra;  // properties other than x y z that land somewhere
  for (std::size_t k = 0; k < e.properties.size(); ++k)
    if (plan.slots[k].kind == Slot::Id || plan.slots[k].kind == Slot::Attr) extra.push_back(k);
  const char* base = src.here();
  for (std::uint64_t v = 0; v < e.count; ++v) {
    const char* rec = base + v * stride;
    std::array<double, 3> x;
    if (packed_xyz) {
      float f[3];
      std::memcpy(f, rec + pos_offset[0], sizeof f);
      x = {f[0], f[1], f[2]};
    } else {
      for (int c = 0; c < 3; ++c) x[c] = load_double<Swap>(rec + pos_offset[c], pos_type[c]);
    }
    if (!std::isfinite(x[0]) || !std::isfinite(x[1]) || !std::isfinite(x[2]))
      src.fail_at(src.offset() + v * stride, "non-finite vertex coordinate in vertex " + std::to_string(v));
    mesh.positions[v] = x;
    for (std::size_t k : extra) {
      const Slot s = plan.slots[k];
      const PlyScalar t = e.properties[k].type;
      if (s.kind == Slot::Id) {
        if (!load_int<Swap>(rec + offset[k], t, (*mesh.ids)[v]))
          src.fail_at(src.offset() + v * stride + offset[k], "vertex id is not an integer in int64 range");
      } else {
        VertexAttribute& a = plan.attrs[s.attr];
        a.values[v * static_cast<std::size_t>(a.width) + s.comp] =
            static_cast<float>(load_double<Swap>(rec + offset[k], t)) * s.scale;
      }
    }
  }
  src.advance(e.count * stride);
}

template <class Src>
std::int64_t face_index(Src& src, PlyScalar t, std::int64_t vertex_count) {
  const std::int64_t i = src.integer(t);
  if (i < 0 || i >= vertex_count)
    src.fail("vertex index " + std::to_string(i) + " out of range (" + std::to_string(vertex_count) +
             " vertices)");
  return i;
}

template <class Src>
void read_faces(Src& src, const PlyElement& e, int index_prop, std::int64_t vertex_count, MeshData& mesh) {
  mesh.triangles.reserve(mesh.triangles.size() + e.count);
  for (std::uint64_t f = 0; f < e.count; ++f) {
    src.at.record = f;
    for (std::size_t k = 0; k < e.properties.size(); ++k) {
      const PlyProperty& p = e.properties[k];
      if (!p.is_list) {
        src.skip(p.type, 1);
        continue;
      }
      const std::uint64_t n = src.list_count(p.count_type);
      if (static_cast<int>(k) != index_prop) {
        src.skip(p.type, n);
        continue;
      }
      if (n < 3)
        src.fail("face " + std::to_string(f) + " has " + std::to_string(n) + " vertices (need at least 3)");
      const std::int64_t first = face_index(src, p.type, vertex_count);
      std::int64_t prev = face_index(src, p.type, vertex_count);
      for (std::uint64_t c = 2; c < n; ++c) {
        const std::int64_t cur = face_index(src, p.type, vertex_count);
        mesh.triangles.push_back({first, prev, cur});
        prev = cur;
      }
    }
  }
}

// Binary faces of the usual layout (only `list uchar int|uint vertex_indices`): a tight loop over the mapped
// bytes with the same checks and messages as read_faces.
template <bool Swap>
bool read_faces_fast(BinarySource<Swap>& src, const PlyElement& e, std::int64_t vertex_count,
                     MeshData& mesh) {
  if (e.properties.size() != 1) return false;
  const PlyProperty& p = e.properties[0];
  if (!p.is_list || p.count_type != PlyScalar::U8 || (p.type != PlyScalar::I32 && p.type != PlyScalar::U32))
    return false;
  const bool is_signed = p.type == PlyScalar::I32;
  const char* const begin = src.here();
  const char* const end = begin + src.remaining();
  const char* q = begin;
  const auto at = [&](const char* x) { return src.offset() + static_cast<std::size_t>(x - begin); };
  const auto index = [&](const char* x) -> std::int64_t {
    const std::int64_t i =
        is_signed ? std::int64_t{load<std::int32_t, Swap>(x)} : std::int64_t{load<std::uint32_t, Swap>(x)};
    if (i < 0 || i >= vertex_count)
      src.fail_at(at(x), "vertex index " + std::to_string(i) + " out of range (" +
                             std::to_string(vertex_count) + " vertices)");
    return i;
  };
  mesh.triangles.reserve(mesh.triangles.size() + e.count);
  for (std::uint64_t f = 0; f < e.count; ++f) {
    src.at.record = f;
    if (q == end) src.truncated(at(end));
    const auto n = static_cast<std::uint8_t>(*q);
    if (n < 3)
      src.fail_at(at(q),
                  "face " + std::to_string(f) + " has " + std::to_string(n) + " vertices (need at least 3)");
    if (static_cast<std::size_t>(end - q - 1) < 4u * n) src.truncated(at(end));
    const char* x = q + 1;
    const std::int64_t first = index(x);
    std::int64_t prev = index(x + 4);
    for (unsigned c = 2; c < n; ++c) {
      const std::int64_t cur = index(x + 4 * c);
      mesh.triangles.push_back({first, prev, cur});
      prev = cur;
    }
    q = x + 4 * n;
  }
  src.advance(static_cast<std::size_t>(q - begin));
  return true;
}

template <class Src>
void skip_element(Src& src, const PlyElement& e) {
  const std::size_t stride = e.fixed_stride();
  if constexpr (!std::is_same_v<Src, AsciiSource>) {
    if (stride > 0) {
      if (e.count > src.remaining() / stride) {
        src.at.record = src.remaining() / stride;
        src.truncated(src.offset() + src.at.record * stride);
      }
      src.advance(e.count * stride);
      return;
    }
  }
  for (std::uint64_t r = 0; r < e.count; ++r) {
    src.at.record = r;
    for (const PlyProperty& p : e.properties) src.skip(p.type, p.is_list ? src.list_count(p.count_type) : 1);
  }
}

// Smallest number of bytes one record can take (ascii: a digit and a separator per value); a count above
// (remaining + 1) / this is a lie, rejected before anything is allocated for it.
std::size_t min_record_bytes(const PlyElement& e, bool ascii) {
  std::size_t n = 0;
  for (const PlyProperty& p : e.properties)
    n += ascii ? 2 : ply_scalar_size(p.is_list ? p.count_type : p.type);
  return n;
}

template <class Src>
void read_body(Src& src, const PlyHeader& h, const std::string& name, MeshData& mesh) {
  const bool ascii = h.format == PlyFormat::Ascii;
  const PlyElement* vertex = nullptr;
  for (const auto& e : h.elements)
    if (e.name == "vertex" && !vertex) vertex = &e;
  if (!vertex || vertex->count == 0) TT_THROW(InvalidInput, name << ": no vertices");
  VertexPlan plan = plan_vertex(*vertex, name);
  bool faces_seen = false;
  for (const auto& e : h.elements) {
    src.at = Position{&e, 0};
    const std::size_t min_bytes = min_record_bytes(e, ascii);
    if (min_bytes == 0) continue;  // no properties: nothing stored
    if (e.count > (src.remaining() + (ascii ? 1 : 0)) / min_bytes)
      src.fail("element '" + e.name + "' declares " + std::to_string(e.count) + " records but only " +
               std::to_string(src.remaining()) + " bytes remain");
    if (&e == vertex) {
      if constexpr (std::is_same_v<Src, AsciiSource>)
        read_vertices(src, e, plan, mesh);
      else if (e.fixed_stride() > 0)
        read_vertices_fixed(src, e, plan, mesh);
      else
        read_vertices(src, e, plan, mesh);
    } else if (e.name == "face" && !faces_seen) {
      faces_seen = true;
      int index_prop = e.find("vertex_indices");
      if (index_prop < 0) index_prop = e.find("vertex_index");
      if (index_prop < 0 || !e.properties[index_prop].is_list)
        TT_THROW(InvalidInput, name << ":" << e.line << ": element face has no list property vertex_indices");
      const auto V = static_cast<std::int64_t>(vertex->count);
      if constexpr (std::is_same_v<Src, AsciiSource>)
        read_faces(src, e, index_prop, V, mesh);
      else if (!read_faces_fast(src, e, V, mesh))
        read_faces(src, e, index_prop, V, mesh);
    } else {
      skip_element(src, e);
    }
  }
  src.finish();
  mesh.attributes = std::move(plan.attrs);
}

}  // namespace

MeshData parse_ply(std::string_view bytes, const std::string& name) {
  const PlyHeader h = parse_ply_header(bytes, name);
  MeshData mesh;
  const bool host_le = std::endian::native == std::endian::little;
  switch (h.format) {
    case PlyFormat::Ascii: {
      AsciiSource src(bytes.data(), bytes.size(), h.body_offset, h.body_line, name);
      read_body(src, h, name, mesh);
      break;
    }
    case PlyFormat::BinaryLittleEndian:
    case PlyFormat::BinaryBigEndian:
      if ((h.format == PlyFormat::BinaryLittleEndian) == host_le) {
        BinarySource<false> src(bytes.data(), bytes.size(), h.body_offset, name);
        read_body(src, h, name, mesh);
      } else {
        BinarySource<true> src(bytes.data(), bytes.size(), h.body_offset, name);
        read_body(src, h, name, mesh);
      }
      break;
  }
  return mesh;
}

MeshData read_ply(const std::filesystem::path& path) {
  const MappedFile file(path);
  return parse_ply(file.text(), path.string());
}

}  // namespace topotrack
