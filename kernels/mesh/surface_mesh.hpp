#pragma once
//! SurfaceMesh: a triangle mesh with half-edge connectivity in flat arrays (PMP-style handles,
//! geometry-central-style compaction), a persistent 64-bit id per vertex and typed per-vertex
//! properties of any width.
//!
//! Conventions: halfedges come in pairs, opposite(h) = h ^ 1 and edge(h) = h / 2. A boundary
//! halfedge has no face. Each vertex stores one outgoing halfedge, a boundary one if the vertex is on
//! the boundary. Deletion only marks; compact() re-packs and returns the old->new maps.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <typeinfo>
#include <vector>

#include "io/error.hpp"
#include "io/event_list.hpp"

namespace topotrack {

using Vec3 = Eigen::Vector3d;
using Index = std::uint32_t;
inline constexpr Index kInvalidIndex = ~Index(0);

#define TOPOTRACK_HANDLE(Name)                                                     \
  struct Name {                                                                    \
    Index idx = kInvalidIndex;                                                     \
    constexpr Name() = default;                                                    \
    explicit constexpr Name(Index i) : idx(i) {}                                   \
    constexpr bool is_valid() const { return idx != kInvalidIndex; }               \
    constexpr auto operator<=>(const Name&) const = default;                       \
  };
TOPOTRACK_HANDLE(Vertex)
TOPOTRACK_HANDLE(Halfedge)
TOPOTRACK_HANDLE(Edge)
TOPOTRACK_HANDLE(Face)
#undef TOPOTRACK_HANDLE

// Per-vertex properties -------------------------------------------------------------------------

//! Type-erased storage of one per-vertex property (width values per vertex).
class BasePropertyArray {
public:
  BasePropertyArray(std::string name, int width) : name_(std::move(name)), width_(width) {}
  virtual ~BasePropertyArray() = default;
  const std::string& name() const { return name_; }
  int width() const { return width_; }
  virtual const std::type_info& type() const = 0;
  virtual void resize(std::size_t n) = 0;
  //! dst <- wa * a + wb * b for arithmetic types; dst <- (wa >= wb ? a : b) otherwise.
  virtual void interpolate(Index dst, Index a, double wa, Index b, double wb) = 0;
  //! Keep element new_to_old[i] at position i.
  virtual void gather(const std::vector<Index>& new_to_old) = 0;
  virtual std::unique_ptr<BasePropertyArray> clone() const = 0;

private:
  std::string name_;
  int width_;
};

template <class T>
class PropertyArray final : public BasePropertyArray {
public:
  PropertyArray(std::string name, int width, T init) : BasePropertyArray(std::move(name), width), init_(init) {}
  const std::type_info& type() const override { return typeid(T); }
  void resize(std::size_t n) override { data_.resize(n * width(), init_); }
  void interpolate(Index dst, Index a, double wa, Index b, double wb) override {
    const int w = width();
    for (int c = 0; c < w; ++c) {
      if constexpr (std::is_arithmetic_v<T>)
        data_[dst * w + c] = static_cast<T>(wa * data_[a * w + c] + wb * data_[b * w + c]);
      else
        data_[dst * w + c] = wa >= wb ? data_[a * w + c] : data_[b * w + c];
    }
  }
  void gather(const std::vector<Index>& new_to_old) override {
    const int w = width();
    std::vector<T> out(new_to_old.size() * w);
    for (std::size_t i = 0; i < new_to_old.size(); ++i)
      for (int c = 0; c < w; ++c) out[i * w + c] = data_[new_to_old[i] * w + c];
    data_.swap(out);
  }
  std::unique_ptr<BasePropertyArray> clone() const override { return std::make_unique<PropertyArray>(*this); }
  std::vector<T>& data() { return data_; }
  const std::vector<T>& data() const { return data_; }

private:
  std::vector<T> data_;
  T init_;
};

//! A typed handle to a per-vertex property; cheap to copy, valid until the property is removed.
template <class T>
class VertexProperty {
public:
  VertexProperty() = default;
  explicit VertexProperty(PropertyArray<T>* a) : a_(a) {}
  bool is_valid() const { return a_ != nullptr; }
  int width() const { return a_->width(); }
  //! The `width()` values of vertex v.
  std::span<T> operator[](Vertex v) { return {a_->data().data() + std::size_t(v.idx) * width(), std::size_t(width())}; }
  std::span<const T> operator[](Vertex v) const {
    return {a_->data().data() + std::size_t(v.idx) * width(), std::size_t(width())};
  }
  T& operator()(Vertex v, int c = 0) { return a_->data()[std::size_t(v.idx) * width() + c]; }
  const T& operator()(Vertex v, int c = 0) const { return a_->data()[std::size_t(v.idx) * width() + c]; }
  std::vector<T>& vector() { return a_->data(); }
  const std::vector<T>& vector() const { return a_->data(); }

private:
  PropertyArray<T>* a_ = nullptr;
};

// The mesh ----------------------------------------------------------------------------------------

//! Old->new index maps returned by compact(); kInvalidIndex for removed elements.
struct CompactMaps {
  std::vector<Index> vertices, edges, faces;
};

class SurfaceMesh {
public:
  SurfaceMesh() = default;
  SurfaceMesh(SurfaceMesh&&) noexcept = default;
  SurfaceMesh& operator=(SurfaceMesh&&) noexcept = default;
  SurfaceMesh(const SurfaceMesh&) = delete;
  SurfaceMesh& operator=(const SurfaceMesh&) = delete;
  //! An explicit deep copy (the mesh is move-only to avoid accidental copies of large data).
  SurfaceMesh clone() const;

  //! Build from an indexed triangle list. Open boundaries are allowed unless require_closed; ids, when
  //! given, are the persistent vertex ids (fresh ids continue after the largest). Edges are numbered in
  //! the order of their (smaller, larger) vertex index pair. A mesh it returns passes validate(false),
  //! and validate(true) as well when built with require_closed: no separate validation is needed.
  //! \throw InvalidInput on an index out of range, a degenerate triangle (repeated index), an edge
  //! shared by more than two triangles, inconsistent orientation, a duplicated triangle or a
  //! non-manifold vertex, and with require_closed on a boundary edge or a vertex in no triangle; the
  //! message names the triangle, edge or vertex.
  static SurfaceMesh from_triangles(std::span<const Vec3> positions, std::span<const std::array<Index, 3>> triangles,
                                    std::span<const VertexId> ids = {}, bool require_closed = false);

  // Sizes: allocated elements, including deleted ones until compact().
  std::size_t vertices_size() const { return vpos_.size(); }
  std::size_t halfedges_size() const { return hto_.size(); }
  std::size_t edges_size() const { return hto_.size() / 2; }
  std::size_t faces_size() const { return fhe_.size(); }
  // Live counts.
  std::size_t n_vertices() const { return vpos_.size() - deleted_vertices_; }
  std::size_t n_edges() const { return edges_size() - deleted_edges_; }
  std::size_t n_faces() const { return fhe_.size() - deleted_faces_; }
  bool has_garbage() const { return deleted_vertices_ + deleted_edges_ + deleted_faces_ > 0; }

  // Connectivity.
  Halfedge halfedge(Vertex v) const { return vhe_[v.idx]; }
  Halfedge halfedge(Face f) const { return fhe_[f.idx]; }
  Halfedge halfedge(Edge e, int i) const { return Halfedge(2 * e.idx + Index(i)); }
  Vertex to_vertex(Halfedge h) const { return hto_[h.idx]; }
  Vertex from_vertex(Halfedge h) const { return hto_[h.idx ^ 1u]; }
  Halfedge next(Halfedge h) const { return hnext_[h.idx]; }
  Halfedge prev(Halfedge h) const { return hprev_[h.idx]; }
  static Halfedge opposite(Halfedge h) { return Halfedge(h.idx ^ 1u); }
  static Edge edge(Halfedge h) { return Edge(h.idx >> 1); }
  Face face(Halfedge h) const { return hface_[h.idx]; }
  //! Next outgoing halfedge of from_vertex(h), counter-clockwise.
  Halfedge ccw_rotated(Halfedge h) const { return opposite(prev(h)); }
  Vertex vertex(Edge e, int i) const { return hto_[2 * e.idx + Index(i)]; }

  bool is_boundary(Halfedge h) const { return !hface_[h.idx].is_valid(); }
  bool is_boundary(Edge e) const { return is_boundary(halfedge(e, 0)) || is_boundary(halfedge(e, 1)); }
  bool is_boundary(Vertex v) const { return vhe_[v.idx].is_valid() && is_boundary(vhe_[v.idx]); }
  bool is_isolated(Vertex v) const { return !vhe_[v.idx].is_valid(); }
  bool is_deleted(Vertex v) const { return vdel_[v.idx] != 0; }
  bool is_deleted(Edge e) const { return edel_[e.idx] != 0; }
  bool is_deleted(Face f) const { return fdel_[f.idx] != 0; }
  //! The halfedge from a to b, or an invalid handle.
  Halfedge find_halfedge(Vertex a, Vertex b) const;
  std::size_t valence(Vertex v) const;
  //! The three vertices of a triangle, in order.
  std::array<Vertex, 3> vertices(Face f) const;
  //! The vertices of the one-ring of v (neighbours), counter-clockwise.
  void one_ring(Vertex v, std::vector<Vertex>& out) const;
  //! The outgoing halfedges of v, counter-clockwise.
  void outgoing(Vertex v, std::vector<Halfedge>& out) const;

  // Geometry and ids.
  const Vec3& position(Vertex v) const { return vpos_[v.idx]; }
  Vec3& position(Vertex v) { return vpos_[v.idx]; }
  std::vector<Vec3>& positions() { return vpos_; }
  const std::vector<Vec3>& positions() const { return vpos_; }
  VertexId id(Vertex v) const { return vid_[v.idx]; }
  void set_id(Vertex v, VertexId id);
  const std::vector<VertexId>& ids() const { return vid_; }
  //! The next fresh id; every id handed out so far is smaller.
  VertexId next_id() const { return next_id_; }
  void set_next_id(VertexId id) { next_id_ = std::max(next_id_, id); }
  VertexId take_fresh_id() { return next_id_++; }

  // Editing ---------------------------------------------------------------------------------------
  //! A new isolated vertex with a fresh id.
  Vertex add_vertex(const Vec3& p);
  //! Split edge e at p: the new vertex (fresh id) is connected to the opposite corners of the one or
  //! two adjacent triangles. Properties are interpolated with weight alpha for vertex(e,0).
  Vertex split(Edge e, const Vec3& p, double alpha = 0.5);
  //! Split triangle f at p (1-to-3); properties from the barycentric weights.
  Vertex split(Face f, const Vec3& p, const std::array<double, 3>& bary);
  //! Whether collapsing h (from_vertex(h) into to_vertex(h)) keeps a 2-manifold: the link
  //! condition, no new duplicate edge, no vertex of valence below 3, no vanishing component.
  bool is_collapse_ok(Halfedge h) const;
  //! Collapse h: from_vertex(h) is deleted, to_vertex(h) is kept (same handle) and moved to p.
  //! Ids are the caller's business (§4.4 gives the kept vertex a fresh id). \pre is_collapse_ok(h)
  void collapse(Halfedge h, const Vec3& p);
  //! Whether flipping e keeps a 2-manifold (interior edge, new edge absent, valences stay >= 3).
  bool is_flip_ok(Edge e) const;
  void flip(Edge e);
  //! Remove deleted elements; returns old->new maps. Handles held across compact() are stale.
  CompactMaps compact();

  //! Check every connectivity invariant; with require_closed also that there is no boundary and no
  //! isolated vertex. Also rejects degenerate faces and duplicate edges.
  //! \throw TopologyError naming the first broken invariant.
  void validate(bool require_closed = true) const;

  // Properties ----------------------------------------------------------------------------------
  template <class T>
  VertexProperty<T> add_vertex_property(const std::string& name, int width = 1, T init = T()) {
    if (find_property(name)) TT_THROW(Error, "vertex property '" << name << "' exists");
    if (width < 1) TT_THROW(Error, "vertex property '" << name << "': width must be >= 1");
    auto a = std::make_unique<PropertyArray<T>>(name, width, init);
    a->resize(vpos_.size());
    auto* raw = a.get();
    props_.push_back(std::move(a));
    return VertexProperty<T>(raw);
  }
  //! The property of that name and type, or an invalid handle.
  template <class T>
  VertexProperty<T> get_vertex_property(const std::string& name) const {
    BasePropertyArray* a = find_property(name);
    if (!a || a->type() != typeid(T)) return {};
    return VertexProperty<T>(static_cast<PropertyArray<T>*>(a));
  }
  void remove_vertex_property(const std::string& name);
  std::vector<std::string> vertex_property_names() const;
  BasePropertyArray* find_property(const std::string& name) const;

private:
  Halfedge new_edge(Vertex from, Vertex to);
  Face new_face(Halfedge h);
  void set_next(Halfedge h, Halfedge n) {
    hnext_[h.idx] = n;
    hprev_[n.idx] = h;
  }
  void adjust_outgoing_halfedge(Vertex v);
  void remove_edge_helper(Halfedge h);
  void remove_loop_helper(Halfedge h);
  void resize_properties();

  std::vector<Vec3> vpos_;
  std::vector<VertexId> vid_;
  std::vector<Halfedge> vhe_;
  std::vector<std::uint8_t> vdel_;
  std::vector<Vertex> hto_;
  std::vector<Halfedge> hnext_, hprev_;
  std::vector<Face> hface_;
  std::vector<std::uint8_t> edel_;
  std::vector<Halfedge> fhe_;
  std::vector<std::uint8_t> fdel_;
  std::size_t deleted_vertices_ = 0, deleted_edges_ = 0, deleted_faces_ = 0;
  VertexId next_id_ = 0;
  std::vector<std::unique_ptr<BasePropertyArray>> props_;
};

}  // namespace topotrack
