// The binary event-list file: round trips, and rejection of every truncation, byte flip and lying count.
#include "io/event_file.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>
#include <cstring>
#include <limits>

#include "io/error.hpp"
#include "tests/io/temp_dir.hpp"

namespace topotrack {
namespace {

EventList sample_events() {
  EventList l;
  l.record_split(1, 2, 7, 0.25);
  l.record_subdivide(3, 4, 5, 8, 0.2, 0.3, 0.5);
  l.record_collapse(7, 2, 9);
  // A topology patch: boundary {1, 3, 4}, new vertices 20 and 21 (21 built from 20, §4.4 factored form).
  l.begin_event(EventKind::PatchCreate);
  for (VertexId v : {1, 3, 4}) l.add_in(v);
  for (VertexId v : {1, 3, 4, 20, 21}) l.add_out(v);
  const RuleTerm a[3] = {{1, 0.5}, {3, 0.25}, {4, 0.25}};
  const RuleTerm b[2] = {{20, 0.5}, {4, 0.5}};
  l.add_forward_rule(20, a);
  l.add_forward_rule(21, b);
  l.end_event();
  l.begin_event(EventKind::PatchDelete);
  for (VertexId v : {20, 21, 1, 3}) l.add_in(v);
  for (VertexId v : {1, 3}) l.add_out(v);
  const RuleTerm c[2] = {{1, 1.0 / 3.0}, {3, 2.0 / 3.0}};
  l.add_backward_rule(20, c);
  l.add_backward_rule(21, std::span<const RuleTerm>(c, 1));
  l.end_event();
  l.record_split(std::numeric_limits<VertexId>::max(), 0, 12345678901234ull, -1e-300);
  return l;
}

std::string read_bytes(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// Overwrite bytes [at, at+sizeof v) with v (little endian host) and fix the checksum, so that only the
// structural checks stand between the reader and the lie.
template <class T>
std::string forge(std::string bytes, std::size_t at, T v) {
  std::memcpy(bytes.data() + at, &v, sizeof v);
  const std::uint64_t h = event_file_checksum(std::string_view(bytes).substr(0, bytes.size() - 8));
  std::memcpy(bytes.data() + bytes.size() - 8, &h, 8);
  return bytes;
}
std::string rehash(std::string bytes) { return forge<std::uint8_t>(bytes, 0, 'T'); }

void expect_corrupt(const std::string& bytes, const std::string& text) {
  try {
    decode_events(bytes, "forged.events");
    ADD_FAILURE() << "no exception for: " << text;
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("forged.events: byte "), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(text), std::string::npos) << e.what();
  }
}

TEST(EventFile, RoundTrip) {
  const EventList l = sample_events();
  const std::string bytes = encode_events(l);
  EXPECT_EQ(bytes.substr(0, 8), "TTEVENTS");
  const EventList back = decode_events(bytes, "mem");
  EXPECT_EQ(back, l);
  EXPECT_EQ(back.count_by_kind(), (std::vector<std::size_t>{2, 1, 1, 1, 1}));
  EXPECT_EQ(encode_events(back), bytes);
}

TEST(EventFile, EmptyListRoundTrips) {
  const std::string bytes = encode_events(EventList{});
  EXPECT_EQ(bytes.size(), 48u + 8u);
  EXPECT_TRUE(decode_events(bytes, "mem").empty());
}

TEST(EventFile, ThroughFile) {
  test::TempDir d;
  const EventList l = sample_events();
  write_events(d / "f.events", l);
  EXPECT_EQ(read_events(d / "f.events"), l);
  EXPECT_THROW(read_events(d / "missing.events"), IoError);
  EXPECT_EQ(d.entries(), (std::vector<std::string>{"f.events"}));
}

TEST(EventFile, LargeListRoundTrips) {
  EventList l;
  for (VertexId i = 0; i < 50000; ++i) {
    l.record_split(i, i + 1, 100000 + i, 0.5);
    l.record_collapse(i, i + 2, 200000 + i);
  }
  EXPECT_EQ(decode_events(encode_events(l), "mem"), l);
}

// write_events streams the bytes in pieces (a frame's list on a fine lattice is ~100 MB): the pieces are the
// file's bytes, and a fault found after some were written leaves the previous file as it was.
TEST(EventFile, StreamedInPiecesWithTheSameBytes) {
  EventList l;
  for (VertexId i = 0; i < 60000; ++i) l.record_subdivide(i, i + 1, i + 2, 300000 + i, 0.2, 0.3, 0.5);
  std::vector<std::size_t> sizes;
  std::string joined;
  encode_events(l, [&](std::string_view piece) {
    sizes.push_back(piece.size());
    joined.append(piece);
  });
  const std::string whole = encode_events(l);
  EXPECT_GT(whole.size(), std::size_t(4) << 20);
  EXPECT_GE(sizes.size(), std::size_t(4));
  EXPECT_LE(*std::max_element(sizes.begin(), sizes.end()), std::size_t(2) << 20);
  EXPECT_EQ(joined, whole);

  test::TempDir d;
  write_events(d / "f.events", l);
  EXPECT_EQ(read_events(d / "f.events"), l);
  const std::string before = read_bytes(d / "f.events");
  EventList bad = l;
  bad.record_split(1, 2, 3, std::numeric_limits<double>::quiet_NaN());  // after ~6 MB of good records
  try {
    write_events(d / "f.events", bad);
    ADD_FAILURE() << "a non-finite weight was written";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find((d / "f.events").string() + ": "), std::string::npos) << e.what();
  }
  EXPECT_EQ(read_bytes(d / "f.events"), before);
  EXPECT_EQ(d.entries(), (std::vector<std::string>{"f.events"}));
}

TEST(EventFile, EveryTruncationIsRejected) {
  const std::string bytes = encode_events(sample_events());
  for (std::size_t n = 0; n < bytes.size(); ++n)
    EXPECT_THROW(decode_events(std::string_view(bytes).substr(0, n), "t"), InvalidInput) << "length " << n;
}

TEST(EventFile, EveryByteFlipIsRejected) {
  const std::string bytes = encode_events(sample_events());
  for (std::size_t i = 0; i < bytes.size(); ++i)
    for (unsigned char mask : {0x01, 0x80, 0xff}) {
      std::string b = bytes;
      b[i] = static_cast<char>(b[i] ^ mask);
      EXPECT_THROW(decode_events(b, "f"), InvalidInput) << "byte " << i << " mask " << int(mask);
    }
}

TEST(EventFile, TrailingBytesAreRejected) {
  std::string b = encode_events(sample_events());
  b.insert(b.size() - 8, "xy");
  expect_corrupt(rehash(b), "trailing bytes");
}

TEST(EventFile, LyingCountsAreRejectedBeforeAllocation) {
  const std::string b = encode_events(sample_events());
  expect_corrupt(forge<std::uint64_t>(b, 16, std::uint64_t{1} << 60), "exceed the file size");
  expect_corrupt(forge<std::uint64_t>(b, 24, std::uint64_t{1} << 62), "exceed the file size");
  expect_corrupt(forge<std::uint64_t>(b, 32, 1000000), "exceed the file size");
  expect_corrupt(forge<std::uint64_t>(b, 40, ~std::uint64_t{0}), "exceed the file size");
  expect_corrupt(forge<std::uint64_t>(b, 16, 3), "the header says");
  expect_corrupt(forge<std::uint64_t>(b, 24, 5), "exceeds the id or rule total");
  expect_corrupt(forge<std::uint64_t>(b, 40, 30), "the header says");
  // First event: kind at 48, then V_in size at 49, V_out 53, forward 57, backward 61.
  expect_corrupt(forge<std::uint32_t>(b, 49, 0xffffffffu), "V_in size 4294967295 exceeds");
  expect_corrupt(forge<std::uint32_t>(b, 57, 0x7fffffffu), "forward rule count");
  expect_corrupt(forge<std::uint8_t>(b, 48, 0), "unknown kind 0");
  expect_corrupt(forge<std::uint8_t>(b, 48, 6), "unknown kind 6");
  expect_corrupt(forge<std::uint32_t>(b, 8, 2), "unsupported event file version 2");
  expect_corrupt(forge<std::uint32_t>(b, 12, 1), "unknown flags");
  expect_corrupt(forge<std::uint8_t>(b, 0, 'X'), "bad magic");
}

TEST(EventFile, NonFiniteWeightIsRejected) {
  const std::string b = encode_events(sample_events());
  // First event (split 1,2 -> 7): 48 + 17 head + 2*8 in + 3*8 out = 105: rule target, 113: term count,
  // 117: source, 125: weight.
  expect_corrupt(forge<double>(b, 125, std::numeric_limits<double>::quiet_NaN()), "non-finite rule weight");
  expect_corrupt(forge<double>(b, 125, -std::numeric_limits<double>::infinity()), "non-finite rule weight");
  EventList l;
  l.record_split(1, 2, 3, std::numeric_limits<double>::infinity());
  EXPECT_THROW(encode_events(l), InvalidInput);
}

TEST(EventFile, ErrorsNameTheFile) {
  test::TempDir d;
  const auto p = d.write("bad.events", "TTEVENTS\x01");
  try {
    read_events(p);
    FAIL();
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find(p.string() + ": byte "), std::string::npos) << e.what();
  }
  const auto empty = d.write("empty.events", "");
  EXPECT_THROW(read_events(empty), InvalidInput);
}

}  // namespace
}  // namespace topotrack
