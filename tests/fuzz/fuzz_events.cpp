// libFuzzer target: the event-list file reader (io/event_file). What it accepts must round-trip:
// encode(decode(x)) decodes again, to a list that encodes to the same bytes.
#include <cstdint>
#include <string>
#include <string_view>

#include "io/error.hpp"
#include "io/event_file.hpp"
#include "tests/fuzz/fuzz_check.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace topotrack;
  EventList events;
  try {
    events = decode_events(std::string_view(reinterpret_cast<const char*>(data), size), "fuzz.events");
  } catch (const Error&) {
    return 0;
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
  return 0;
}
