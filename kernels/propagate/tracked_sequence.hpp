#pragma once
//! A tracked sequence as the tracker writes it (OUT/<name>.<nnnn>.ply with persistent `id`s, and beside each
//! frame OUT/<name>.<nnnn>.events, the event list taking the previous frame to this one), and the propagation
//! of per-vertex values through the whole sequence (§4.6): forward from a frame to the end, backward from a
//! frame to the start, one frame in memory at a time.
#include <filesystem>
#include <functional>
#include <span>
#include <vector>

#include "io/event_list.hpp"
#include "kernels/propagate/propagate.hpp"

namespace topotrack {

struct TrackedFrame {
  std::filesystem::path mesh;
  std::filesystem::path events;  //!< mesh with the extension .events
  long number = -1;
};

//! Pair each mesh file with the event file beside it.
std::vector<TrackedFrame> tracked_frames(std::span<const std::filesystem::path> meshes, std::span<const long> numbers);

//! The events taking frame k-1 to frame k; an empty list for frame 0 (whose file may be absent).
//! \throw InvalidInput (via read_events) naming the file when a later frame's events are missing or corrupt.
EventList load_frame_events(std::span<const TrackedFrame> frames, std::size_t k);

struct SequencePropagateReport {
  std::size_t frames = 0;
  std::size_t events = 0;
  PropagateReport rules;
  double propagate_seconds = 0;    //!< in the rules only (not in the callbacks)
};

//! Carry `start` (values by id on frame `source`) through frames 0..count-1 and hand each frame's values to
//! `emit(k, table)`, starting with frame `source` itself. Forward visits source, source+1, .., count-1 and
//! applies events_of(k) (frame k-1 -> k) forward; backward visits source, source-1, .., 0 and applies
//! events_of(k+1) backward. Deterministic (serial in the rules).
//! \throw InvalidInput for source >= count, plus whatever the callbacks throw.
void propagate_sequence(std::size_t count, std::size_t source, bool forward, const IdField& start,
                        const std::function<EventList(std::size_t)>& events_of,
                        const std::function<void(std::size_t, const IdTable&)>& emit,
                        SequencePropagateReport* report = nullptr);

struct RoundTripReport {
  std::size_t values = 0;    //!< ids of the source frame compared (times the width: values)
  std::size_t missing = 0;   //!< source ids with no value after the round trip (left out of the statistics)
  double range = 0;          //!< max - min of the start values
  double max_abs = 0, mean_abs = 0, rms = 0;  //!< |back - start| over the values compared
  double forward_seconds = 0, backward_seconds = 0;
};

//! The round trip of §4.6: `start` (values on frame `source`) carried forward to the last frame, then backward
//! to `source`, compared value by value with `start`. \throw InvalidInput for source >= count, plus whatever
//! events_of throws.
RoundTripReport round_trip(std::size_t count, std::size_t source, const IdField& start,
                           const std::function<EventList(std::size_t)>& events_of);

}  // namespace topotrack
