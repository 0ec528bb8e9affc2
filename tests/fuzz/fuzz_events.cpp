// libFuzzer target: the event-list file reader (io/event_file). What it accepts must round-trip:
// encode(decode(x)) decodes again, to a list that encodes to the same bytes.
// Each input is read twice: as it is, and with its last 8 bytes replaced by the checksum of the rest
// (event_file_checksum, little endian, as io/event_file.cpp writes it). Without the second reading a mutation almost
// never keeps the checksum right, and the fuzzer never gets past it into the body (5 minutes: 330 edges,
// no new input).
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>

#include "io/error.hpp"
#include "io/event_file.hpp"
#include "tests/fuzz/fuzz_check.hpp"

namespace {

void check(std::string_view bytes) {
  using namespace topotrack;
  EventList events;
  try {
    events = decode_events(bytes, "fuzz.events");
  } catch (const Error&) {
    return;
  }
  const std::string once = encode_events(events);
  EventList again;
  try {
    again = decode_events(once, "re-encoded");
  } catch (const Error&) {
    fuzz::broken("an accepted event list does not read back after encoding");
  }
  if (again.size() != events.size() || again.rule_count() != events.rule_count() ||
      again.term_count() != events.term_count() || encode_events(again) != once)
    fuzz::broken("event list changes through encode/decode");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view raw(reinterpret_cast<const char*>(data), size);
  check(raw);
  if (size >= 8) {
    std::string sealed(raw);
    const std::uint64_t h = topotrack::event_file_checksum(std::string_view(sealed).substr(0, size - 8));
    for (int i = 0; i < 8; ++i) sealed[size - 8 + std::size_t(i)] = char((h >> (8 * i)) & 0xff);
    check(sealed);
  }
  return 0;
}
