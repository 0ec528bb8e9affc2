#include "kernels/propagate/tracked_sequence.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "io/error.hpp"
#include "io/event_file.hpp"

namespace topotrack {

std::vector<TrackedFrame> tracked_frames(std::span<const std::filesystem::path> meshes, std::span<const long> numbers) {
  std::vector<TrackedFrame> out;
  out.reserve(meshes.size());
  for (std::size_t i = 0; i < meshes.size(); ++i) {
    TrackedFrame f;
    f.mesh = meshes[i];
    f.events = std::filesystem::path(meshes[i]).replace_extension(".events");
    f.number = i < numbers.size() ? numbers[i] : long(i);
    out.push_back(std::move(f));
  }
  return out;
}

EventList load_frame_events(std::span<const TrackedFrame> frames, std::size_t k) {
  if (k >= frames.size()) TT_THROW(InvalidInput, "load_frame_events: frame " << k << " of " << frames.size());
  if (k == 0) return {};
  std::error_code ec;
  if (!std::filesystem::exists(frames[k].events, ec))
    TT_THROW(InvalidInput, frames[k].events.string() << ": missing event list (is " << frames[k].mesh.string()
                                                     << " part of a tracked sequence?)");
  return read_events(frames[k].events);
}

void propagate_sequence(std::size_t count, std::size_t source, bool forward, const IdField& start,
                        const std::function<EventList(std::size_t)>& events_of,
                        const std::function<void(std::size_t, const IdTable&)>& emit,
                        SequencePropagateReport* report) {
  if (source >= count) TT_THROW(InvalidInput, "propagate_sequence: source frame " << source << " of " << count);
  IdTable table = IdTable::from_field(start);
  SequencePropagateReport rep;
  double seconds = 0;
  emit(source, table);
  rep.frames = 1;
  const std::size_t steps = forward ? count - 1 - source : source;
  for (std::size_t s = 1; s <= steps; ++s) {
    const std::size_t k = forward ? source + s : source - s;
    const EventList events = events_of(forward ? k : k + 1);
    const auto t0 = std::chrono::steady_clock::now();
    if (forward)
      propagate_forward(events, table, &rep.rules);
    else
      propagate_backward(events, table, &rep.rules);
    seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    rep.events += events.size();
    emit(k, table);
    ++rep.frames;
  }
  rep.propagate_seconds = seconds;
  if (report) *report = rep;
}

RoundTripReport round_trip(std::size_t count, std::size_t source, const IdField& start,
                           const std::function<EventList(std::size_t)>& events_of) {
  IdField last;
  SequencePropagateReport fwd, bwd;
  propagate_sequence(
      count, source, true, start, events_of,
      [&](std::size_t k, const IdTable& table) {
        if (k + 1 == count) last = table.to_field();
      },
      &fwd);
  IdField back;
  propagate_sequence(
      count, count - 1, false, last, events_of,
      [&](std::size_t k, const IdTable& table) {
        if (k == source) back = table.to_field();
      },
      &bwd);
  RoundTripReport r;
  r.forward_seconds = fwd.propagate_seconds;
  r.backward_seconds = bwd.propagate_seconds;
  const int w = start.width;
  if (!start.values.empty()) {
    const auto [lo, hi] = std::minmax_element(start.values.begin(), start.values.end());
    r.range = double(*hi) - double(*lo);
  }
  const IdTable table = IdTable::from_field(back);
  double sum = 0, sum2 = 0;
  for (std::size_t i = 0; i < start.ids.size(); ++i) {
    const std::span<const float> v = table.get(start.ids[i]);
    if (v.empty()) {
      ++r.missing;
      continue;
    }
    for (int c = 0; c < w; ++c) {
      const double e = std::abs(double(v[c]) - double(start.values[i * w + c]));
      r.max_abs = std::max(r.max_abs, e);
      sum += e;
      sum2 += e * e;
      ++r.values;
    }
  }
  if (r.values) {
    r.mean_abs = sum / double(r.values);
    r.rms = std::sqrt(sum2 / double(r.values));
  }
  return r;
}

}  // namespace topotrack
