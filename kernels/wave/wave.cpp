#include "kernels/wave/wave.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>

#include "io/error.hpp"
#include "kernels/propagate/propagate.hpp"

namespace topotrack {

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

void check_state(const WaveState& s, const char* who) {
  if (s.h.size() != s.ids.size() || s.v.size() != s.ids.size())
    TT_THROW(InvalidInput, who << ": state has " << s.ids.size() << " ids, " << s.h.size() << " heights, "
                               << s.v.size() << " velocities");
}

void check_params(const WaveParams& p) {
  if (!(p.speed >= 0) || !std::isfinite(p.speed)) TT_THROW(InvalidInput, "wave: speed " << p.speed << " invalid");
  if (!(p.frame_time >= 0) || !std::isfinite(p.frame_time))
    TT_THROW(InvalidInput, "wave: frame time " << p.frame_time << " invalid");
  if (!(p.damping >= 0 && p.damping < 1)) TT_THROW(InvalidInput, "wave: damping " << p.damping << " not in [0, 1)");
  if (!(p.cfl_safety > 0 && p.cfl_safety <= 1))
    TT_THROW(InvalidInput, "wave: CFL safety " << p.cfl_safety << " not in (0, 1]");
  if (p.substeps > 1000000) TT_THROW(InvalidInput, "wave: " << p.substeps << " sub-steps is too many");
  if (!std::isfinite(p.inject_height) || !std::isfinite(p.inject_velocity))
    TT_THROW(InvalidInput, "wave: injection amplitudes must be finite");
}

// The events [begin, end) of `events` as a list of their own.
EventList slice(const EventList& events, std::size_t begin, std::size_t end) {
  EventList out;
  for (std::size_t e = begin; e < end; ++e) {
    const EventList::View v = events.event(e);
    out.begin_event(v.kind);
    for (VertexId id : v.in) out.add_in(id);
    for (VertexId id : v.out) out.add_out(id);
    for (std::size_t r = v.forward_begin; r < v.forward_end; ++r) {
      const EventList::Rule rule = events.rule(r);
      out.add_forward_rule(rule.target, rule.terms);
    }
    for (std::size_t r = v.backward_begin; r < v.backward_end; ++r) {
      const EventList::Rule rule = events.rule(r);
      out.add_backward_rule(rule.target, rule.terms);
    }
    out.end_event();
  }
  return out;
}

}  // namespace

WaveState zero_wave_state(std::span<const VertexId> ids) {
  WaveState s;
  s.ids.assign(ids.begin(), ids.end());
  s.h.assign(ids.size(), 0.0);
  s.v.assign(ids.size(), 0.0);
  return s;
}

WaveState transfer_wave_state(const WaveState& state, const EventList& events, std::span<const VertexId> next_ids,
                              const WaveParams& params, WaveReport* report) {
  const auto t0 = Clock::now();
  check_state(state, "transfer_wave_state");
  check_params(params);
  IdField field;
  field.width = 2;
  field.ids = state.ids;
  field.values.resize(2 * state.ids.size());
  for (std::size_t i = 0; i < state.ids.size(); ++i) {
    field.values[2 * i] = float(state.h[i]);
    field.values[2 * i + 1] = float(state.v[i]);
  }
  IdTable table = IdTable::from_field(field);
  const bool inject = params.inject_height != 0 || params.inject_velocity != 0;
  std::size_t injected = 0;
  std::size_t done = 0;
  for (std::size_t e = 0; e < events.size() && inject; ++e) {
    const EventList::View v = events.event(e);
    if (v.kind != EventKind::PatchCreate) continue;
    // Run everything up to and including this patch, then add energy at the vertices it created.
    if (done == 0 && e + 1 == events.size())
      propagate_forward(events, table);
    else
      propagate_forward(slice(events, done, e + 1), table);
    done = e + 1;
    for (std::size_t r = v.forward_begin; r < v.forward_end; ++r) {
      const VertexId id = events.rule(r).target;
      const std::span<const float> cur = table.get(id);
      const float hv[2] = {float((cur.empty() ? 0.0 : cur[0]) + params.inject_height),
                           float((cur.empty() ? 0.0 : cur[1]) + params.inject_velocity)};
      table.set(id, hv);
      ++injected;
    }
  }
  if (done == 0)
    propagate_forward(events, table);
  else if (done < events.size())
    propagate_forward(slice(events, done, events.size()), table);

  WaveState out;
  out.ids.assign(next_ids.begin(), next_ids.end());
  std::vector<float> values;
  const float zero[1] = {0.0f};
  const std::size_t missing = gather_values(table, next_ids, zero, values);
  out.h.resize(next_ids.size());
  out.v.resize(next_ids.size());
  for (std::size_t i = 0; i < next_ids.size(); ++i) {
    out.h[i] = values[2 * i];
    out.v[i] = values[2 * i + 1];
  }
  if (report) {
    report->injected = injected;
    report->missing = missing;
    report->transfer_seconds = since(t0);
  }
  return out;
}

double wave_energy(const CotanLaplacian& L, const WaveState& state, double speed) {
  check_state(state, "wave_energy");
  if (state.h.size() != L.size())
    TT_THROW(InvalidInput, "wave_energy: state of " << state.h.size() << " for a mesh of " << L.size());
  double kinetic = 0;
  for (std::size_t i = 0; i < L.size(); ++i) kinetic += L.mass[i] * state.v[i] * state.v[i];
  return 0.5 * kinetic + 0.5 * speed * speed * L.dirichlet(state.h);
}

int stable_substeps(const CotanLaplacian& L, const WaveParams& params) {
  check_params(params);
  if (params.substeps > 0) return params.substeps;
  const double lambda = L.max_eigenvalue_bound();
  if (!(lambda > 0) || params.speed == 0 || params.frame_time == 0) return 1;
  const double dt_max = params.cfl_safety * 2.0 / (params.speed * std::sqrt(lambda));
  const double steps = std::ceil(params.frame_time / dt_max);
  if (!(steps <= 1e6)) TT_THROW(InvalidInput, "wave: the CFL bound needs " << steps << " sub-steps per frame");
  return std::max(1, int(steps));
}

void integrate_waves(const CotanLaplacian& L, WaveState& state, const WaveParams& params, WaveReport* report) {
  const auto t0 = Clock::now();
  check_state(state, "integrate_waves");
  check_params(params);
  const std::size_t n = L.size();
  if (state.h.size() != n)
    TT_THROW(InvalidInput, "integrate_waves: state of " << state.h.size() << " for a mesh of " << n << " vertices");
  const int steps = stable_substeps(L, params);
  const double dt = params.frame_time / steps;
  const double c2 = params.speed * params.speed;
  const double keep = 1.0 - params.damping;
  if (report) report->energy_before = wave_energy(L, state, params.speed);
  std::vector<double> ch(n);
  // Symplectic Euler: v += dt * c^2 laplace(h); h += dt * v.
  for (int s = 0; s < steps; ++s) {
    L.apply(state.h, ch);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
      for (std::size_t i = r.begin(); i < r.end(); ++i) {
        state.v[i] -= dt * c2 * ch[i] / L.mass[i];
        state.h[i] = keep * (state.h[i] + dt * state.v[i]);
      }
    });
  }
  if (report) {
    report->substeps = steps;
    report->dt = dt;
    report->energy_after = wave_energy(L, state, params.speed);
    double m = 0;
    for (double h : state.h) m = std::max(m, std::abs(h));
    report->max_abs_height = m;
    report->integrate_seconds = since(t0);
  }
}

void integrate_waves(std::span<const Vec3> positions, std::span<const std::array<Index, 3>> triangles,
                     WaveState& state, const WaveParams& params, WaveReport* report) {
  const auto t0 = Clock::now();
  const CotanLaplacian L = cotan_laplacian(positions, triangles);
  if (report) report->laplacian_seconds = since(t0);
  integrate_waves(L, state, params, report);
}

}  // namespace topotrack
