// Speed of propagation through a whole sequence (§4.6, §5: "a few seconds for the entire animation"):
// a synthetic tracked sequence of F frames with V vertices whose event lists look like the tracker's (per frame
// 1% edge splits, 1% edge collapses, one topology patch of 64 deleted and 64 created vertices), a colour
// (width 3) carried forward from frame 0 through all frames and gathered into every frame's vertex order.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <random>

#include "kernels/propagate/tracked_sequence.hpp"

namespace topotrack {
namespace {

struct Sequence {
  std::vector<VertexId> first_ids;
  std::vector<EventList> events;              // events[k]: frame k-1 -> k (events[0] empty)
  std::vector<std::vector<VertexId>> ids;     // vertex ids of each frame
};

Sequence make_sequence(std::size_t vertices, std::size_t frames) {
  std::mt19937_64 rng(42);
  Sequence s;
  std::vector<VertexId> alive(vertices);
  for (std::size_t i = 0; i < vertices; ++i) alive[i] = i;
  VertexId next = vertices;
  s.first_ids = alive;
  s.ids.push_back(alive);
  s.events.emplace_back();
  auto pick = [&] { return std::uniform_int_distribution<std::size_t>(0, alive.size() - 1)(rng); };
  auto take = [&] {
    const std::size_t i = pick();
    const VertexId id = alive[i];
    alive[i] = alive.back();
    alive.pop_back();
    return id;
  };
  for (std::size_t f = 1; f < frames; ++f) {
    EventList ev;
    const std::size_t ops = vertices / 100;
    for (std::size_t k = 0; k < ops; ++k) {
      const VertexId i = alive[pick()], j = alive[pick()];
      if (i == j) continue;
      ev.record_split(i, j, next, 0.5);
      alive.push_back(next++);
    }
    for (std::size_t k = 0; k < ops; ++k) {
      const VertexId i = take(), j = take();
      ev.record_collapse(i, j, next);
      alive.push_back(next++);
    }
    // A topology patch: 64 vertices deleted (backward rules from 16 boundary vertices), 64 created.
    std::vector<VertexId> boundary(16), deleted(64);
    for (auto& b : boundary) b = take();
    for (auto& d : deleted) d = take();
    std::vector<RuleTerm> terms;
    for (VertexId b : boundary) terms.push_back({b, 1.0 / boundary.size()});
    ev.begin_event(EventKind::PatchDelete);
    for (VertexId d : deleted) ev.add_in(d);
    for (VertexId b : boundary) ev.add_in(b);
    for (VertexId b : boundary) ev.add_out(b);
    for (VertexId d : deleted) ev.add_backward_rule(d, terms);
    ev.end_event();
    ev.begin_event(EventKind::PatchCreate);
    for (VertexId b : boundary) ev.add_in(b);
    for (VertexId b : boundary) ev.add_out(b);
    std::vector<VertexId> created;
    for (int k = 0; k < 64; ++k) created.push_back(next++);
    for (VertexId c : created) ev.add_out(c);
    for (std::size_t k = 0; k < created.size(); ++k) {
      // March: each new vertex from two boundary vertices and the previous new one (factored rules, §4.4).
      std::vector<RuleTerm> t = {{boundary[k % 16], 0.4}, {boundary[(k + 5) % 16], 0.3}};
      t.push_back(k ? RuleTerm{created[k - 1], 0.3} : RuleTerm{boundary[(k + 9) % 16], 0.3});
      ev.add_forward_rule(created[k], t);
    }
    ev.end_event();
    for (VertexId b : boundary) alive.push_back(b);
    for (VertexId c : created) alive.push_back(c);
    s.events.push_back(std::move(ev));
    s.ids.push_back(alive);
  }
  return s;
}

void BM_PropagateSequence(benchmark::State& state) {
  const std::size_t V = std::size_t(state.range(0)), F = std::size_t(state.range(1));
  const Sequence s = make_sequence(V, F);
  IdField start;
  start.width = 3;
  start.ids = s.first_ids;
  for (std::size_t i = 0; i < V; ++i)
    for (int c = 0; c < 3; ++c) start.values.push_back(float((i * (c + 1)) % 17) / 16.0f);
  std::size_t events = 0, missing = 0;
  std::vector<float> out;
  const float fallback[1] = {0.5f};
  for (auto _ : state) {
    SequencePropagateReport rep;
    missing = 0;
    propagate_sequence(
        F, 0, true, start, [&](std::size_t k) { return s.events[k]; },
        [&](std::size_t k, const IdTable& table) {
          missing += gather_values(table, s.ids[k], fallback, out);
          benchmark::DoNotOptimize(out.data());
        },
        &rep);
    events = rep.events;
  }
  state.counters["events"] = double(events);
  state.counters["missing"] = double(missing);
  state.counters["vertex_frames_per_s"] =
      benchmark::Counter(double(V) * F, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_PropagateSequence)
    ->ArgNames({"verts", "frames"})
    ->Args({10000, 100})
    ->Args({100000, 10})
    ->Args({100000, 100})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace topotrack

BENCHMARK_MAIN();
