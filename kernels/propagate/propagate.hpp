#pragma once
//! Propagation of per-vertex data over event lists (§4.6): forward in time by running the events in
//! order with their forward rules f, backward by running them in reverse order with their backward
//! rules b. Values are keyed by persistent vertex ids.
#include <cstdint>
#include <span>
#include <unordered_map>
#include <vector>

#include "io/event_list.hpp"

namespace topotrack {

//! A per-vertex float attribute of `width` values per vertex, keyed by id (values[i*width + c]
//! belongs to ids[i]).
struct IdField {
  int width = 1;
  std::vector<VertexId> ids;
  std::vector<float> values;
};

class SurfaceMesh;
//! The live vertices' positions keyed by their persistent ids (width 3, in vertex order): what §4.6
//! carries through an event list to tell where each vertex was a frame earlier.
IdField position_field(const SurfaceMesh& mesh);

//! Id -> values table used while propagating. Ids are mostly dense integers from a counter, so they
//! index a vector directly; an id far beyond the ids seen (more than 4x the table size plus 2^20)
//! goes to a hash map instead, so huge ids cost no memory.
class IdTable {
public:
  explicit IdTable(int width = 1);
  //! \throw InvalidInput on width < 1, values.size() != ids.size() * width or a repeated id.
  static IdTable from_field(const IdField& field);
  //! All ids present, in increasing id order.
  IdField to_field() const;

  int width() const { return width_; }
  std::size_t size() const { return size_; }
  bool contains(VertexId id) const { return slot_of(id) != kNoSlot; }
  //! The values of id, or an empty span if absent.
  std::span<const float> get(VertexId id) const;
  //! Insert or overwrite; returns the values of id (width floats).
  std::span<float> set(VertexId id, std::span<const float> values);
  void erase(VertexId id);

private:
  static constexpr std::uint32_t kNoSlot = ~std::uint32_t(0);
  std::uint32_t slot_of(VertexId id) const;
  std::uint32_t insert_slot(VertexId id);

  int width_;
  std::size_t size_ = 0;
  std::vector<std::uint32_t> dense_;  // slot by id, for small ids
  std::unordered_map<VertexId, std::uint32_t> sparse_;
  std::vector<float> values_;         // width_ per slot
  std::vector<std::uint32_t> free_;
};

//! What a propagation did.
struct PropagateReport {
  std::size_t events = 0;
  std::size_t rules_applied = 0;
  //! Rules with a source absent from the table: the present sources' weights were renormalised, or,
  //! with no source present, the target was left absent (counted in targets_missing).
  std::size_t rules_with_missing_sources = 0;
  std::size_t targets_missing = 0;
};

//! Run `events` forward on `table` in place (§4.6): events in order, each event's forward rules in their
//! stored order (target <- sum weight * source), then the ids in V_in but not in V_out are erased.
void propagate_forward(const EventList& events, IdTable& table, PropagateReport* report = nullptr);
//! Run `events` backward on `table` in place (§4.6): events in reverse order, each event's backward
//! rules in their stored order, then the ids in V_out but not in V_in are erased.
void propagate_backward(const EventList& events, IdTable& table, PropagateReport* report = nullptr);

//! Values by id after the events, from values by id before them (frame n-1 -> n).
//! \throw InvalidInput as IdTable::from_field.
IdField propagate_forward(const EventList& events, const IdField& before, PropagateReport* report = nullptr);
//! Values by id before the events, from values by id after them (frame n -> n-1).
IdField propagate_backward(const EventList& events, const IdField& after, PropagateReport* report = nullptr);

//! Values for the vertex id list `ids` (e.g. SurfaceMesh::ids()), width per id, into `out`; an absent id
//! gets `fallback` (width values, or one value repeated). Returns the number of absent ids.
//! \throw InvalidInput if fallback has neither 1 nor width values.
std::size_t gather_values(const IdTable& table, std::span<const VertexId> ids, std::span<const float> fallback,
                          std::vector<float>& out);
std::size_t gather_values(const IdField& field, std::span<const VertexId> ids, std::span<const float> fallback,
                          std::vector<float>& out);

//! A rule written in terms of vertices that the event does not create (its "boundary" vertices).
struct ExpandedRule {
  VertexId target = 0;
  std::vector<RuleTerm> terms;  //!< by increasing source id, one term per source
};
//! The forward (or backward) rules of event `e` with every source that an earlier rule of the same event
//! assigns substituted by that rule's terms (§4.4: "linear combination of boundary vertices"), for
//! printing and inspection. \throw std::out_of_range on a bad event index.
std::vector<ExpandedRule> expand_rules(const EventList& events, std::size_t e, bool forward = true);

}  // namespace topotrack
