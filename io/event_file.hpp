#pragma once
//! The binary event-list file (§4.4), documented in docs/formats.md: a header with magic and version,
//! counts, then the records.
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <string_view>

#include "io/event_list.hpp"

namespace topotrack {

//! The file bytes. \throw InvalidInput on a non-finite rule weight (it could not be read back).
std::string encode_events(const EventList& events);
//! The same bytes handed to `emit` in order, in pieces of about 1 MiB, so that a writer never holds the
//! whole file (write_events). \throw InvalidInput as above, possibly after some pieces were emitted.
void encode_events(const EventList& events, const std::function<void(std::string_view)>& emit);
//! \throw InvalidInput "<name>: byte <offset>: <fault>" on a bad magic, unsupported version, truncation,
//! lying counts, unknown event kind, non-finite weight or trailing bytes.
EventList decode_events(std::string_view bytes, const std::string& name);
//! The checksum an event file ends with (FNV-1a 64 of every byte before it), for tools and tests that
//! build or repair files by hand.
std::uint64_t event_file_checksum(std::string_view bytes);

//! Atomic write. \throw IoError naming the path; InvalidInput as encode_events.
void write_events(const std::filesystem::path& path, const EventList& events);
//! Memory-mapped read. \throw IoError (unreadable) or InvalidInput (corrupt), naming the path.
EventList read_events(const std::filesystem::path& path);

}  // namespace topotrack
