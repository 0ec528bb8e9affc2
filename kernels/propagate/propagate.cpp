#include "kernels/propagate/propagate.hpp"

#include <algorithm>
#include <map>

#include "io/error.hpp"
#include "kernels/mesh/surface_mesh.hpp"

namespace topotrack {

IdField position_field(const SurfaceMesh& mesh) {
  IdField f;
  f.width = 3;
  f.ids.reserve(mesh.n_vertices());
  f.values.reserve(3 * std::size_t(mesh.n_vertices()));
  for (Index i = 0; i < mesh.vertices_size(); ++i) {
    const Vertex v(i);
    if (mesh.is_deleted(v)) continue;
    f.ids.push_back(mesh.id(v));
    for (int c = 0; c < 3; ++c) f.values.push_back(float(mesh.position(v)[c]));
  }
  return f;
}

// IdTable ------------------------------------------------------------------------------------------

IdTable::IdTable(int width) : width_(width) {
  if (width < 1) TT_THROW(InvalidInput, "IdTable: width must be >= 1, got " << width);
}

IdTable IdTable::from_field(const IdField& field) {
  IdTable t(field.width);
  if (field.values.size() != field.ids.size() * std::size_t(field.width))
    TT_THROW(InvalidInput, "IdField: " << field.values.size() << " values for " << field.ids.size() << " ids of width "
                                       << field.width);
  VertexId max_id = 0;
  for (VertexId id : field.ids) max_id = std::max(max_id, id);
  if (!field.ids.empty() && max_id < 4 * field.ids.size() + (VertexId(1) << 20)) t.dense_.assign(max_id + 1, kNoSlot);
  t.values_.reserve(field.values.size());
  for (std::size_t i = 0; i < field.ids.size(); ++i) {
    if (t.contains(field.ids[i])) TT_THROW(InvalidInput, "IdField: id " << field.ids[i] << " appears twice");
    t.set(field.ids[i], std::span<const float>(field.values.data() + i * field.width, std::size_t(field.width)));
  }
  return t;
}

IdField IdTable::to_field() const {
  IdField f;
  f.width = width_;
  f.ids.reserve(size_);
  f.values.reserve(size_ * width_);
  auto emit = [&](VertexId id, std::uint32_t s) {
    f.ids.push_back(id);
    f.values.insert(f.values.end(), values_.begin() + std::size_t(s) * width_,
                    values_.begin() + (std::size_t(s) + 1) * width_);
  };
  for (std::size_t id = 0; id < dense_.size(); ++id)
    if (dense_[id] != kNoSlot) emit(id, dense_[id]);
  std::vector<std::pair<VertexId, std::uint32_t>> sparse(sparse_.begin(), sparse_.end());
  std::sort(sparse.begin(), sparse.end());
  for (const auto& [id, s] : sparse) emit(id, s);
  return f;
}

std::uint32_t IdTable::slot_of(VertexId id) const {
  if (id < dense_.size()) return dense_[id];
  if (sparse_.empty()) return kNoSlot;
  const auto it = sparse_.find(id);
  return it == sparse_.end() ? kNoSlot : it->second;
}

std::span<const float> IdTable::get(VertexId id) const {
  const std::uint32_t s = slot_of(id);
  if (s == kNoSlot) return {};
  return {values_.data() + std::size_t(s) * width_, std::size_t(width_)};
}

std::uint32_t IdTable::insert_slot(VertexId id) {
  const std::uint32_t existing = slot_of(id);
  if (existing != kNoSlot) return existing;
  std::uint32_t s;
  if (!free_.empty()) {
    s = free_.back();
    free_.pop_back();
  } else {
    s = std::uint32_t(values_.size() / width_);
    values_.resize(values_.size() + width_);
  }
  ++size_;
  if (id >= dense_.size() && id < 4 * VertexId(size_) + (VertexId(1) << 20)) {
    // Grow the dense index geometrically and move the hashed ids it now covers.
    const std::size_t n = std::max<std::size_t>(id + 1, dense_.size() + dense_.size() / 2);
    dense_.resize(n, kNoSlot);
    for (auto it = sparse_.begin(); it != sparse_.end();) {
      if (it->first < n) {
        dense_[it->first] = it->second;
        it = sparse_.erase(it);
      } else {
        ++it;
      }
    }
  }
  if (id < dense_.size())
    dense_[id] = s;
  else
    sparse_.emplace(id, s);
  return s;
}

std::span<float> IdTable::set(VertexId id, std::span<const float> values) {
  if (values.size() != std::size_t(width_))
    TT_THROW(InvalidInput, "IdTable::set: " << values.size() << " values for width " << width_);
  const float* src = values.data();
  std::vector<float> copy;
  if (src >= values_.data() && src < values_.data() + values_.size()) {  // aliasing our storage
    copy.assign(values.begin(), values.end());
    src = copy.data();
  }
  const std::uint32_t s = insert_slot(id);
  float* dst = values_.data() + std::size_t(s) * width_;
  std::copy(src, src + width_, dst);
  return {dst, std::size_t(width_)};
}

void IdTable::erase(VertexId id) {
  std::uint32_t s = kNoSlot;
  if (id < dense_.size()) {
    s = dense_[id];
    dense_[id] = kNoSlot;
  } else if (!sparse_.empty()) {
    const auto it = sparse_.find(id);
    if (it != sparse_.end()) {
      s = it->second;
      sparse_.erase(it);
    }
  }
  if (s == kNoSlot) return;
  free_.push_back(s);
  --size_;
}

// Propagation --------------------------------------------------------------------------------------

namespace {

class RuleRunner {
public:
  RuleRunner(const EventList& events, IdTable& table, PropagateReport* report)
      : ev_(events), t_(table), rep_(report), acc_(table.width()), out_(table.width()) {}

  void apply_rules(std::size_t begin, std::size_t end) {
    const int w = t_.width();
    for (std::size_t r = begin; r < end; ++r) {
      const EventList::Rule rule = ev_.rule(r);
      std::fill(acc_.begin(), acc_.end(), 0.0);
      double total = 0, present = 0;
      bool missing = false;
      for (const RuleTerm& term : rule.terms) {
        total += term.weight;
        const std::span<const float> v = t_.get(term.source);
        if (v.empty()) {
          missing = true;
          continue;
        }
        present += term.weight;
        for (int c = 0; c < w; ++c) acc_[c] += term.weight * double(v[c]);
      }
      if (rep_) ++rep_->rules_applied;
      if (missing) {
        if (rep_) ++rep_->rules_with_missing_sources;
        if (present == 0) {
          t_.erase(rule.target);
          if (rep_) ++rep_->targets_missing;
          continue;
        }
        for (int c = 0; c < w; ++c) acc_[c] *= total / present;
      }
      for (int c = 0; c < w; ++c) out_[c] = float(acc_[c]);
      t_.set(rule.target, out_);
    }
  }

  //! Erase the ids of `from` that are not in `keep`.
  void erase_difference(std::span<const VertexId> from, std::span<const VertexId> keep) {
    if (from.size() * keep.size() <= 64) {
      for (VertexId id : from)
        if (std::find(keep.begin(), keep.end(), id) == keep.end()) t_.erase(id);
      return;
    }
    sorted_.assign(keep.begin(), keep.end());
    std::sort(sorted_.begin(), sorted_.end());
    for (VertexId id : from)
      if (!std::binary_search(sorted_.begin(), sorted_.end(), id)) t_.erase(id);
  }

private:
  const EventList& ev_;
  IdTable& t_;
  PropagateReport* rep_;
  std::vector<double> acc_;
  std::vector<float> out_;
  std::vector<VertexId> sorted_;
};

}  // namespace

void propagate_forward(const EventList& events, IdTable& table, PropagateReport* report) {
  RuleRunner run(events, table, report);
  for (std::size_t e = 0; e < events.size(); ++e) {
    const EventList::View v = events.event(e);
    run.apply_rules(v.forward_begin, v.forward_end);
    run.erase_difference(v.in, v.out);
  }
  if (report) report->events += events.size();
}

void propagate_backward(const EventList& events, IdTable& table, PropagateReport* report) {
  RuleRunner run(events, table, report);
  for (std::size_t e = events.size(); e-- > 0;) {
    const EventList::View v = events.event(e);
    run.apply_rules(v.backward_begin, v.backward_end);
    run.erase_difference(v.out, v.in);
  }
  if (report) report->events += events.size();
}

IdField propagate_forward(const EventList& events, const IdField& before, PropagateReport* report) {
  IdTable t = IdTable::from_field(before);
  propagate_forward(events, t, report);
  return t.to_field();
}

IdField propagate_backward(const EventList& events, const IdField& after, PropagateReport* report) {
  IdTable t = IdTable::from_field(after);
  propagate_backward(events, t, report);
  return t.to_field();
}

std::size_t gather_values(const IdTable& table, std::span<const VertexId> ids, std::span<const float> fallback,
                          std::vector<float>& out) {
  const int w = table.width();
  if (fallback.size() != 1 && fallback.size() != std::size_t(w))
    TT_THROW(InvalidInput, "gather_values: fallback has " << fallback.size() << " values, width is " << w);
  out.resize(ids.size() * w);
  std::size_t missing = 0;
  for (std::size_t i = 0; i < ids.size(); ++i) {
    const std::span<const float> v = table.get(ids[i]);
    float* dst = out.data() + i * w;
    if (v.empty()) {
      ++missing;
      for (int c = 0; c < w; ++c) dst[c] = fallback.size() == 1 ? fallback[0] : fallback[c];
    } else {
      std::copy(v.begin(), v.end(), dst);
    }
  }
  return missing;
}

std::size_t gather_values(const IdField& field, std::span<const VertexId> ids, std::span<const float> fallback,
                          std::vector<float>& out) {
  return gather_values(IdTable::from_field(field), ids, fallback, out);
}

std::vector<ExpandedRule> expand_rules(const EventList& events, std::size_t e, bool forward) {
  const EventList::View v = events.event(e);
  const std::size_t begin = forward ? v.forward_begin : v.backward_begin;
  const std::size_t end = forward ? v.forward_end : v.backward_end;
  std::vector<ExpandedRule> out;
  std::map<VertexId, std::size_t> assigned;  // target -> index in out of its latest rule
  std::map<VertexId, double> sum;
  for (std::size_t r = begin; r < end; ++r) {
    const EventList::Rule rule = events.rule(r);
    sum.clear();
    for (const RuleTerm& t : rule.terms) {
      const auto it = assigned.find(t.source);
      if (it == assigned.end()) {
        sum[t.source] += t.weight;
      } else {
        for (const RuleTerm& s : out[it->second].terms) sum[s.source] += t.weight * s.weight;
      }
    }
    ExpandedRule x;
    x.target = rule.target;
    for (const auto& [src, w] : sum) x.terms.push_back({src, w});
    assigned[rule.target] = out.size();
    out.push_back(std::move(x));
  }
  return out;
}

}  // namespace topotrack
