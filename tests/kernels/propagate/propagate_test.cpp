#include "kernels/propagate/propagate.hpp"

#include <gtest/gtest.h>

#include "io/error.hpp"

namespace topotrack {
namespace {

IdField field(std::vector<VertexId> ids, std::vector<float> values, int width = 1) {
  IdField f;
  f.width = width;
  f.ids = std::move(ids);
  f.values = std::move(values);
  return f;
}

float value(const IdField& f, VertexId id, int c = 0) {
  for (std::size_t i = 0; i < f.ids.size(); ++i)
    if (f.ids[i] == id) return f.values[i * f.width + c];
  ADD_FAILURE() << "id " << id << " absent";
  return 0;
}

bool has(const IdField& f, VertexId id) { return std::find(f.ids.begin(), f.ids.end(), id) != f.ids.end(); }

TEST(IdTable, SetGetEraseAndOrder) {
  IdTable t(2);
  const float a[2] = {1, 2}, b[2] = {3, 4};
  t.set(7, a);
  t.set(3, b);
  const VertexId huge = VertexId(1) << 60;
  t.set(huge, a);
  EXPECT_EQ(t.size(), 3u);
  EXPECT_TRUE(t.contains(huge));
  EXPECT_FALSE(t.contains(4));
  EXPECT_EQ(t.get(3)[1], 4.0f);
  EXPECT_TRUE(t.get(5).empty());
  t.erase(7);
  t.erase(7);  // erasing an absent id is a no-op
  EXPECT_EQ(t.size(), 2u);
  const IdField f = t.to_field();
  ASSERT_EQ(f.ids.size(), 2u);
  EXPECT_EQ(f.ids[0], 3u);
  EXPECT_EQ(f.ids[1], huge);
  EXPECT_EQ(f.values, (std::vector<float>{3, 4, 1, 2}));
  // Overwrite in place through an aliasing span.
  t.set(3, t.get(huge));
  EXPECT_EQ(t.get(3)[0], 1.0f);
}

TEST(IdTable, RejectsBadFields) {
  EXPECT_THROW(IdTable(0), InvalidInput);
  EXPECT_THROW(IdTable::from_field(field({1, 2}, {1.0f}, 1)), InvalidInput);
  EXPECT_THROW(IdTable::from_field(field({1, 1}, {1.0f, 2.0f}, 1)), InvalidInput);
  IdTable t(2);
  const float one[1] = {1};
  EXPECT_THROW(t.set(1, one), InvalidInput);
}

TEST(Propagate, SplitAndCollapseForwardAndBackward) {
  EventList ev;
  ev.record_split(1, 2, 10, 0.25);    // 10 = .25*1 + .75*2
  ev.record_collapse(10, 3, 11);      // 11 = .5*10 + .5*3, 10 and 3 gone
  const IdField before = field({1, 2, 3, 4}, {1, 10, 2, 20, 3, 30, 4, 40}, 2);
  PropagateReport rep;
  const IdField after = propagate_forward(ev, before, &rep);
  EXPECT_EQ(after.ids, (std::vector<VertexId>{1, 2, 4, 11}));
  EXPECT_FLOAT_EQ(value(after, 11, 0), 0.5f * (0.25f * 1 + 0.75f * 2) + 0.5f * 3);
  EXPECT_FLOAT_EQ(value(after, 11, 1), 0.5f * (0.25f * 10 + 0.75f * 20) + 0.5f * 30);
  EXPECT_EQ(value(after, 4, 1), 40.0f);
  EXPECT_EQ(rep.events, 2u);
  EXPECT_EQ(rep.rules_applied, 2u);
  EXPECT_EQ(rep.rules_with_missing_sources, 0u);

  const IdField back = propagate_backward(ev, after, &rep);
  // Backward: collapse gives 10 and 3 the value of 11; the split's k=10 is then removed.
  EXPECT_EQ(back.ids, (std::vector<VertexId>{1, 2, 3, 4}));
  EXPECT_EQ(value(back, 3, 0), value(after, 11, 0));
  EXPECT_EQ(value(back, 1, 1), 10.0f);  // untouched: identity
  EXPECT_EQ(value(back, 4, 0), 4.0f);
}

EventList patch_events() {
  // A patch of new vertices 20, 21 on boundary {1,2,3}: 20 from the boundary, 21 from 20 and 3
  // (the factored breadth-first form), then the deletion of vertex 2 from {1, 3}.
  EventList ev;
  ev.begin_event(EventKind::PatchCreate);
  for (VertexId v : {1, 2, 3}) ev.add_in(v);
  for (VertexId v : {1, 2, 3, 20, 21}) ev.add_out(v);
  const RuleTerm r20[] = {{1, 0.5}, {2, 0.5}};
  const RuleTerm r21[] = {{20, 0.5}, {3, 0.5}};
  ev.add_forward_rule(20, r20);
  ev.add_forward_rule(21, r21);
  ev.end_event();
  ev.begin_event(EventKind::PatchDelete);
  for (VertexId v : {1, 2, 3}) ev.add_in(v);
  for (VertexId v : {1, 3}) ev.add_out(v);
  const RuleTerm b2[] = {{1, 0.25}, {3, 0.75}};
  ev.add_backward_rule(2, b2);
  ev.end_event();
  return ev;
}

TEST(Propagate, PatchEventsChainRulesInStoredOrder) {
  const EventList ev = patch_events();
  const IdField after = propagate_forward(ev, field({1, 2, 3}, {4, 8, 16}));
  EXPECT_EQ(after.ids, (std::vector<VertexId>{1, 3, 20, 21}));
  EXPECT_FLOAT_EQ(value(after, 20), 6.0f);
  EXPECT_FLOAT_EQ(value(after, 21), 11.0f);
  const IdField before = propagate_backward(ev, after);
  EXPECT_EQ(before.ids, (std::vector<VertexId>{1, 2, 3}));
  EXPECT_FLOAT_EQ(value(before, 2), 0.25f * 4 + 0.75f * 16);
  EXPECT_EQ(value(before, 1), 4.0f);
}

TEST(Propagate, ExpandRulesUsesBoundaryVerticesOnly) {
  const EventList ev = patch_events();
  const auto fwd = expand_rules(ev, 0, true);
  ASSERT_EQ(fwd.size(), 2u);
  EXPECT_EQ(fwd[1].target, 21u);
  ASSERT_EQ(fwd[1].terms.size(), 3u);
  EXPECT_EQ(fwd[1].terms[0], (RuleTerm{1, 0.25}));
  EXPECT_EQ(fwd[1].terms[1], (RuleTerm{2, 0.25}));
  EXPECT_EQ(fwd[1].terms[2], (RuleTerm{3, 0.5}));
  EXPECT_TRUE(expand_rules(ev, 0, false).empty());
  const auto bwd = expand_rules(ev, 1, false);
  ASSERT_EQ(bwd.size(), 1u);
  EXPECT_EQ(bwd[0].target, 2u);
  EXPECT_THROW(expand_rules(ev, 5), std::out_of_range);
}

TEST(Propagate, MissingSourcesAreRenormalisedOrLeftAbsent) {
  EventList ev;
  ev.record_split(1, 2, 10, 0.5);
  ev.record_split(3, 4, 11, 0.5);
  PropagateReport rep;
  const IdField after = propagate_forward(ev, field({1, 5}, {2, 7}), &rep);
  EXPECT_EQ(value(after, 10), 2.0f);  // only source 1 present: weight renormalised to 1
  EXPECT_FALSE(has(after, 11));
  EXPECT_EQ(rep.rules_with_missing_sources, 2u);
  EXPECT_EQ(rep.targets_missing, 1u);
}

TEST(Propagate, ConstantsStayConstantAndDenseEqualsSparse) {
  EventList small, big;
  const VertexId off = VertexId(1) << 50;
  for (VertexId k = 0; k < 200; ++k) {
    small.record_split(k, k + 1, 1000 + k, 0.3);
    big.record_split(off + k, off + k + 1, off + 1000 + k, 0.3);
    if (k % 3 == 0) {
      small.record_collapse(1000 + k, k + 2, 5000 + k);
      big.record_collapse(off + 1000 + k, off + k + 2, off + 5000 + k);
    }
  }
  IdField cs, cb;
  for (VertexId k = 0; k < 300; ++k) {
    cs.ids.push_back(k);
    cb.ids.push_back(off + k);
    cs.values.push_back(1.25f);
    cb.values.push_back(1.25f);
  }
  const IdField fs = propagate_forward(small, cs), fb = propagate_forward(big, cb);
  ASSERT_EQ(fs.ids.size(), fb.ids.size());
  for (std::size_t i = 0; i < fs.ids.size(); ++i) {
    EXPECT_EQ(fs.ids[i] + off, fb.ids[i]);
    EXPECT_EQ(fs.values[i], 1.25f);
    EXPECT_EQ(fb.values[i], 1.25f);
  }
  const IdField bs = propagate_backward(small, fs);
  for (float v : bs.values) EXPECT_EQ(v, 1.25f);
}

TEST(Propagate, GatherUsesFallbackForAbsentIds) {
  const IdField f = field({2, 4}, {1, 2, 3, 4}, 2);
  std::vector<float> out;
  const std::vector<VertexId> ids = {4, 9, 2};
  const float fb[1] = {-1};
  EXPECT_EQ(gather_values(f, ids, fb, out), 1u);
  EXPECT_EQ(out, (std::vector<float>{3, 4, -1, -1, 1, 2}));
  const float fb2[2] = {5, 6};
  EXPECT_EQ(gather_values(f, ids, fb2, out), 1u);
  EXPECT_EQ(out[2], 5.0f);
  EXPECT_EQ(out[3], 6.0f);
  const float fb3[3] = {0, 0, 0};
  EXPECT_THROW(gather_values(f, ids, fb3, out), InvalidInput);
}

}  // namespace
}  // namespace topotrack
