#include "io/event_list.hpp"

#include "io/error.hpp"

namespace topotrack {

std::string_view to_string(EventKind kind) {
  switch (kind) {
    case EventKind::EdgeSplit: return "split";
    case EventKind::TriangleSubdivide: return "subdivide";
    case EventKind::EdgeCollapse: return "collapse";
    case EventKind::PatchCreate: return "patch_create";
    case EventKind::PatchDelete: return "patch_delete";
  }
  return "unknown";
}

void EventList::clear() { *this = EventList{}; }

std::vector<std::size_t> EventList::count_by_kind() const {
  std::vector<std::size_t> counts(kEventKindCount, 0);
  for (const auto& r : events_) ++counts[static_cast<int>(r.kind) - 1];
  return counts;
}

EventList::View EventList::event(std::size_t e) const {
  const Record& r = events_.at(e);
  const std::size_t id_end = e + 1 < events_.size() ? events_[e + 1].id_begin : ids_.size();
  const std::size_t rule_end = e + 1 < events_.size() ? events_[e + 1].rule_begin : rule_target_.size();
  View v{r.kind,
         std::span<const VertexId>(ids_.data() + r.id_begin, r.out_begin - r.id_begin),
         std::span<const VertexId>(ids_.data() + r.out_begin, id_end - r.out_begin),
         r.rule_begin, r.backward_begin, r.backward_begin, rule_end};
  return v;
}

EventList::Rule EventList::rule(std::size_t r) const {
  const std::uint32_t b = rule_term_begin_[r], e = rule_term_begin_[r + 1];
  return Rule{rule_target_[r], std::span<const RuleTerm>(terms_.data() + b, e - b)};
}

void EventList::begin_event(EventKind kind) {
  if (open_) TT_THROW(Error, "EventList::begin_event: previous event not ended");
  if (static_cast<int>(kind) < 1 || static_cast<int>(kind) > kEventKindCount)
    TT_THROW(InvalidInput, "event kind " << static_cast<int>(kind) << " is not a known kind");
  open_ = true;
  const auto ids = static_cast<std::uint32_t>(ids_.size());
  const auto rules = static_cast<std::uint32_t>(rule_target_.size());
  events_.push_back(Record{kind, ids, ids, rules, rules});
  if (rule_term_begin_.empty()) rule_term_begin_.push_back(0);
}

void EventList::add_in(VertexId v) {
  Record& r = events_.back();
  if (r.out_begin != ids_.size()) TT_THROW(Error, "EventList::add_in after add_out");
  ids_.push_back(v);
  ++r.out_begin;
}

void EventList::add_out(VertexId v) { ids_.push_back(v); }

void EventList::add_rule(VertexId target, std::span<const RuleTerm> terms) {
  rule_target_.push_back(target);
  terms_.insert(terms_.end(), terms.begin(), terms.end());
  rule_term_begin_.push_back(static_cast<std::uint32_t>(terms_.size()));
}

void EventList::add_forward_rule(VertexId target, std::span<const RuleTerm> terms) {
  Record& r = events_.back();
  if (r.backward_begin != rule_target_.size())
    TT_THROW(Error, "EventList::add_forward_rule after a backward rule");
  add_rule(target, terms);
  ++r.backward_begin;
}

void EventList::add_backward_rule(VertexId target, std::span<const RuleTerm> terms) {
  add_rule(target, terms);
}

void EventList::end_event() { open_ = false; }

void EventList::record_split(VertexId i, VertexId j, VertexId k, double alpha) {
  begin_event(EventKind::EdgeSplit);
  add_in(i);
  add_in(j);
  add_out(i);
  add_out(j);
  add_out(k);
  const RuleTerm t[2] = {{i, alpha}, {j, 1.0 - alpha}};
  add_forward_rule(k, t);
  end_event();
}

void EventList::record_subdivide(VertexId i, VertexId j, VertexId k, VertexId l, double ai, double aj,
                                 double ak) {
  begin_event(EventKind::TriangleSubdivide);
  for (VertexId v : {i, j, k}) add_in(v);
  for (VertexId v : {i, j, k, l}) add_out(v);
  const RuleTerm t[3] = {{i, ai}, {j, aj}, {k, ak}};
  add_forward_rule(l, t);
  end_event();
}

void EventList::record_collapse(VertexId i, VertexId j, VertexId k) {
  begin_event(EventKind::EdgeCollapse);
  add_in(i);
  add_in(j);
  add_out(k);
  const RuleTerm f[2] = {{i, 0.5}, {j, 0.5}};
  add_forward_rule(k, f);
  const RuleTerm b[1] = {{k, 1.0}};
  add_backward_rule(i, b);
  add_backward_rule(j, b);
  end_event();
}

void EventList::append(const EventList& other) {
  for (std::size_t e = 0; e < other.size(); ++e) {
    const View v = other.event(e);
    begin_event(v.kind);
    for (VertexId id : v.in) add_in(id);
    for (VertexId id : v.out) add_out(id);
    for (std::size_t r = v.forward_begin; r < v.forward_end; ++r) {
      const Rule rule = other.rule(r);
      add_forward_rule(rule.target, rule.terms);
    }
    for (std::size_t r = v.backward_begin; r < v.backward_end; ++r) {
      const Rule rule = other.rule(r);
      add_backward_rule(rule.target, rule.terms);
    }
    end_event();
  }
}

}  // namespace topotrack
