#include "io/ply_writer.hpp"

#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <set>

#include "io/atomic_file.hpp"
#include "io/error.hpp"
#include "io/ply_format.hpp"

namespace topotrack {

namespace {

constexpr std::size_t kBlockRecords = 1 << 15;

// One vertex property of the output.
struct Column {
  std::string name;
  PlyScalar type;
  const VertexAttribute* attr;  // nullptr for x y z and id
  int comp;                     // component of the attribute, or the axis
  bool colour;                  // float in [0,1] -> uchar
};

struct Layout {
  std::vector<Column> columns;  // after x y z
  bool has_ids = false;
  PlyScalar id_type = PlyScalar::I32;
  PlyScalar index_type = PlyScalar::I32;
  PlyScalar pos_type = PlyScalar::F32;
  std::size_t vertex_stride = 0;
  std::size_t face_stride = 0;
};

bool valid_name(const std::string& n) {
  if (n.empty()) return false;
  for (unsigned char c : n)
    if (c <= ' ' || c >= 127) return false;
  return true;
}

Layout plan(const MeshData& mesh, const PlyWriteOptions& options) {
  Layout L;
  const std::size_t V = mesh.vertex_count();
  L.pos_type = options.double_positions ? PlyScalar::F64 : PlyScalar::F32;
  std::set<std::string> names{"x", "y", "z"};
  auto add = [&](const std::string& name, PlyScalar t, const VertexAttribute* a, int comp, bool colour) {
    if (!names.insert(name).second)
      TT_THROW(InvalidInput, "PLY output: vertex property '" << name << "' would appear twice");
    L.columns.push_back({name, t, a, comp, colour});
  };
  if (mesh.ids) {
    if (mesh.ids->size() != V)
      TT_THROW(InvalidInput, "PLY output: " << mesh.ids->size() << " ids for " << V << " vertices");
    L.has_ids = true;
    const bool fits = std::all_of(mesh.ids->begin(), mesh.ids->end(), [](std::int64_t id) {
      return id >= std::numeric_limits<std::int32_t>::min() && id <= std::numeric_limits<std::int32_t>::max();
    });
    L.id_type = fits ? PlyScalar::I32 : PlyScalar::I64;
    add("id", L.id_type, nullptr, 0, false);
  }
  for (const VertexAttribute& a : mesh.attributes) {
    if (!valid_name(a.name))
      TT_THROW(InvalidInput, "PLY output: attribute name '" << a.name << "' is empty or holds whitespace");
    if (a.width < 1 || a.values.size() != V * static_cast<std::size_t>(a.width))
      TT_THROW(InvalidInput, "PLY output: attribute '" << a.name << "' has " << a.values.size()
                                                       << " values, expected width " << a.width << " x "
                                                       << V);
    if (a.name == "color" && (a.width == 3 || a.width == 4)) {
      const char* n[4] = {"red", "green", "blue", "alpha"};
      for (int c = 0; c < a.width; ++c) add(n[c], PlyScalar::U8, &a, c, true);
      for (float f : a.values)
        if (!std::isfinite(f)) TT_THROW(InvalidInput, "PLY output: non-finite colour value");
    } else if ((a.name == "v" || a.name == "normal") && a.width == 3) {
      const std::string p = a.name == "v" ? "v" : "n";
      for (int c = 0; c < 3; ++c) add(p + "xyz"[c], PlyScalar::F32, &a, c, false);
    } else if (a.width == 1) {
      add(a.name, PlyScalar::F32, &a, 0, false);
    } else {
      for (int c = 0; c < a.width; ++c) add(a.name + "_" + std::to_string(c), PlyScalar::F32, &a, c, false);
    }
  }
  if (V > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max())) L.index_type = PlyScalar::I64;
  for (std::size_t f = 0; f < mesh.triangle_count(); ++f)
    for (std::int64_t i : mesh.triangles[f])
      if (i < 0 || static_cast<std::size_t>(i) >= V)
        TT_THROW(InvalidInput, "PLY output: triangle " << f << " has vertex index " << i << " out of range ("
                                                       << V << " vertices)");
  for (std::size_t v = 0; v < V; ++v)
    for (int c = 0; c < 3; ++c) {
      const double x = mesh.positions[v][c];
      if (!std::isfinite(x) || (!options.double_positions && !std::isfinite(static_cast<float>(x))))
        TT_THROW(InvalidInput, "PLY output: vertex "
                                   << v << " has a coordinate " << x
                                   << (std::isfinite(x) ? " beyond float range" : " that is not finite"));
    }
  L.vertex_stride = 3 * ply_scalar_size(L.pos_type);
  for (const Column& c : L.columns) L.vertex_stride += ply_scalar_size(c.type);
  L.face_stride = 1 + 3 * ply_scalar_size(L.index_type);
  return L;
}

std::string header(const MeshData& mesh, const Layout& L, const PlyWriteOptions& o) {
  std::string h = "ply\nformat ";
  h += o.ascii ? "ascii" : o.big_endian ? "binary_big_endian" : "binary_little_endian";
  h += " 1.0\ncomment written by topotrack\nelement vertex " + std::to_string(mesh.vertex_count()) + "\n";
  const std::string pt(to_string(L.pos_type));
  for (const char* a : {"x", "y", "z"}) h += "property " + pt + " " + a + "\n";
  for (const Column& c : L.columns) h += "property " + std::string(to_string(c.type)) + " " + c.name + "\n";
  h += "element face " + std::to_string(mesh.triangle_count()) + "\n";
  h += "property list uchar " + std::string(to_string(L.index_type)) + " vertex_indices\nend_header\n";
  return h;
}

std::uint8_t to_uchar(float f) {
  return static_cast<std::uint8_t>(std::lround(std::clamp(f, 0.0f, 1.0f) * 255.0f));
}

template <class T>
inline char* put(char* p, T v, bool swap) {
  std::memcpy(p, &v, sizeof(T));
  if (swap && sizeof(T) > 1) std::reverse(p, p + sizeof(T));
  return p + sizeof(T);
}

// Writes the body in blocks of records into `emit`, so a file is never held twice in memory.
class BodyWriter {
 public:
  BodyWriter(const MeshData& mesh, const Layout& L, const PlyWriteOptions& o,
             const std::function<void(std::string_view)>& emit)
      : m_(mesh),
        L_(L),
        o_(o),
        emit_(emit),
        swap_(!o.ascii && (o.big_endian != (std::endian::native == std::endian::big))) {}

  void run() {
    if (o_.ascii) {
      ascii_vertices();
      ascii_faces();
    } else {
      binary_vertices();
      binary_faces();
    }
  }

 private:
  void binary_vertices() {
    const std::size_t V = m_.vertex_count();
    for (std::size_t b = 0; b < V; b += kBlockRecords) {
      const std::size_t e = std::min(V, b + kBlockRecords);
      block_.resize((e - b) * L_.vertex_stride);
      char* p = block_.data();
      for (std::size_t v = b; v < e; ++v) {
        const auto& x = m_.positions[v];
        if (L_.pos_type == PlyScalar::F64) {
          for (int c = 0; c < 3; ++c) p = put<double>(p, x[c], swap_);
        } else {
          for (int c = 0; c < 3; ++c) p = put<float>(p, static_cast<float>(x[c]), swap_);
        }
        for (const Column& col : L_.columns) {
          if (!col.attr) {
            const std::int64_t id = (*m_.ids)[v];
            p = col.type == PlyScalar::I32 ? put<std::int32_t>(p, static_cast<std::int32_t>(id), swap_)
                                           : put<std::int64_t>(p, id, swap_);
            continue;
          }
          const float f = col.attr->values[v * static_cast<std::size_t>(col.attr->width) + col.comp];
          p = col.colour ? put<std::uint8_t>(p, to_uchar(f), swap_) : put<float>(p, f, swap_);
        }
      }
      emit_(block_);
    }
  }

  void binary_faces() {
    const std::size_t F = m_.triangle_count();
    for (std::size_t b = 0; b < F; b += kBlockRecords) {
      const std::size_t e = std::min(F, b + kBlockRecords);
      block_.resize((e - b) * L_.face_stride);
      char* p = block_.data();
      for (std::size_t f = b; f < e; ++f) {
        *p++ = 3;
        for (std::int64_t i : m_.triangles[f])
          p = L_.index_type == PlyScalar::I32 ? put<std::int32_t>(p, static_cast<std::int32_t>(i), swap_)
                                              : put<std::int64_t>(p, i, swap_);
      }
      emit_(block_);
    }
  }

  template <class T>
  void number(T v) {
    char buf[32];
    const auto r = std::to_chars(buf, buf + sizeof buf, v);
    block_.append(buf, r.ptr);
  }
  void flush_if_full() {
    if (block_.size() >= (std::size_t{1} << 20)) {
      emit_(block_);
      block_.clear();
    }
  }

  void ascii_vertices() {
    block_.clear();
    for (std::size_t v = 0; v < m_.vertex_count(); ++v) {
      for (int c = 0; c < 3; ++c) {
        if (c) block_ += ' ';
        if (L_.pos_type == PlyScalar::F64)
          number(m_.positions[v][c]);
        else
          number(static_cast<float>(m_.positions[v][c]));
      }
      for (const Column& col : L_.columns) {
        block_ += ' ';
        if (!col.attr) {
          number((*m_.ids)[v]);
          continue;
        }
        const float f = col.attr->values[v * static_cast<std::size_t>(col.attr->width) + col.comp];
        if (col.colour)
          number(static_cast<unsigned>(to_uchar(f)));
        else
          number(f);
      }
      block_ += '\n';
      flush_if_full();
    }
  }

  void ascii_faces() {
    for (const auto& t : m_.triangles) {
      block_ += '3';
      for (std::int64_t i : t) {
        block_ += ' ';
        number(i);
      }
      block_ += '\n';
      flush_if_full();
    }
    if (!block_.empty()) emit_(block_);
  }

  const MeshData& m_;
  const Layout& L_;
  const PlyWriteOptions& o_;
  const std::function<void(std::string_view)>& emit_;
  bool swap_;
  std::string block_;
};

void encode(const MeshData& mesh, const PlyWriteOptions& options,
            const std::function<void(std::string_view)>& emit) {
  const Layout L = plan(mesh, options);
  emit(header(mesh, L, options));
  BodyWriter(mesh, L, options, emit).run();
}

}  // namespace

std::string encode_ply(const MeshData& mesh, const PlyWriteOptions& options) {
  std::string out;
  encode(mesh, options, [&out](std::string_view s) { out.append(s); });
  return out;
}

void write_ply(const std::filesystem::path& path, const MeshData& mesh, const PlyWriteOptions& options) {
  try {
    write_file_atomic(
        path, [&](AtomicFileWriter& w) { encode(mesh, options, [&w](std::string_view s) { w.write(s); }); });
  } catch (const InvalidInput& e) {
    TT_THROW(InvalidInput, path.string() << ": " << e.what());
  }
}

}  // namespace topotrack
