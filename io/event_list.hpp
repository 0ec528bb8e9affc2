#pragma once
//! The event list of §4.4: every resampling of the tracked mesh between two frames, in the order it
//! happened, keyed by persistent vertex ids.
//!
//! An event is (V_in, V_out, f, b). f is a list of forward rules, b a list of backward rules; a rule
//! assigns to one target vertex a weighted sum of source vertices:
//!   split of edge (i,j) at k:      V_in {i,j}   V_out {i,j,k}  f: k <- a i + (1-a) j        b: none
//!   subdivision of triangle ijk:   V_in {i,j,k} V_out {i,j,k,l} f: l <- ai i + aj j + ak k  b: none
//!   collapse of edge (i,j) into k: V_in {i,j}   V_out {k}      f: k <- .5 i + .5 j          b: i <- k, j <- k
//!   topology patch created:        V_in boundary, V_out new vertices; f: one rule per new vertex, b: none
//!   topology patch deleted:        V_in deleted + boundary, V_out boundary; f: none, b: one rule per deleted vertex
//! Within one event the rules are applied in their stored order, in both directions. Patch rules are
//! stored in the order of the breadth-first march of §4.4: a rule's sources are boundary vertices or
//! vertices whose rule comes earlier in the same event, which is the paper's "linear combination of
//! boundary vertices" in factored form (see expand_rules in kernels/propagate); it keeps a patch of
//! p vertices with b boundary vertices at O(p) terms instead of O(p b).
#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

namespace topotrack {

using VertexId = std::uint64_t;

enum class EventKind : std::uint8_t {
  EdgeSplit = 1,
  TriangleSubdivide = 2,
  EdgeCollapse = 3,
  PatchCreate = 4,
  PatchDelete = 5,
};
inline constexpr int kEventKindCount = 5;
std::string_view to_string(EventKind kind);

//! One term of a rule: `weight` times the value at vertex `source`.
struct RuleTerm {
  VertexId source = 0;
  double weight = 0;
  bool operator==(const RuleTerm&) const = default;
};

//! Flat storage of an event list; append-only while recording.
class EventList {
public:
  struct Rule {
    VertexId target;
    std::span<const RuleTerm> terms;
  };
  //! A read-only view of one event.
  struct View {
    EventKind kind;
    std::span<const VertexId> in;
    std::span<const VertexId> out;
    std::size_t forward_begin, forward_end;    //!< rule indices
    std::size_t backward_begin, backward_end;  //!< rule indices
  };

  std::size_t size() const { return events_.size(); }
  bool empty() const { return events_.empty(); }
  void clear();
  //! Number of events of each kind, indexed by int(kind) - 1.
  std::vector<std::size_t> count_by_kind() const;

  View event(std::size_t e) const;
  Rule rule(std::size_t r) const;
  std::size_t rule_count() const { return rule_target_.size(); }
  std::size_t term_count() const { return terms_.size(); }

  // Recording ------------------------------------------------------------------------------
  void record_split(VertexId i, VertexId j, VertexId k, double alpha);
  void record_subdivide(VertexId i, VertexId j, VertexId k, VertexId l, double ai, double aj, double ak);
  void record_collapse(VertexId i, VertexId j, VertexId k);

  //! Generic recording, used by topology patches and by the file reader: begin an event, add its
  //! vertex sets and rules, end it. Rules must be added forward ones first, then backward ones.
  void begin_event(EventKind kind);
  void add_in(VertexId v);
  void add_out(VertexId v);
  void add_forward_rule(VertexId target, std::span<const RuleTerm> terms);
  void add_backward_rule(VertexId target, std::span<const RuleTerm> terms);
  void end_event();

  //! Append all events of `other` after ours.
  void append(const EventList& other);

  bool operator==(const EventList& o) const = default;

private:
  struct Record {
    EventKind kind;
    std::uint32_t id_begin;       // V_in then V_out in ids_
    std::uint32_t out_begin;
    std::uint32_t rule_begin;     // forward rules, then backward rules
    std::uint32_t backward_begin;
    bool operator==(const Record&) const = default;
  };
  void add_rule(VertexId target, std::span<const RuleTerm> terms);

  std::vector<Record> events_;
  std::vector<VertexId> ids_;
  std::vector<VertexId> rule_target_;
  std::vector<std::uint32_t> rule_term_begin_;  // size rules + 1 once any rule exists
  std::vector<RuleTerm> terms_;
  bool open_ = false;
};

}  // namespace topotrack
